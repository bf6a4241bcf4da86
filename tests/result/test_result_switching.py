"""Solution.events and Solution.stick_intervals() of fixed-step runs, against the exact
event-driven reference, and of radau5 (located events) against a fine fixed step."""

from __future__ import annotations

import numpy as np
import pytest
from _helpers import log_uniform
from hypothesis import given
from hypothesis import strategies as st

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.reference import exact_solution
from lumped.scene import SineBurst, bingham_oscillator, paper_F2
from lumped.solvers import Event

DT, T_END = 1e-3, 5.0


def _exact_sticks(forcing, x0):
    ref = exact_solution(m=1.0, k=100.0, gamma=1.0, tau=1.0, x0=x0, forcing=forcing,
                         t_eval=[0.0, T_END])
    return [(iv.t_start, iv.t_end) for iv in ref.intervals if iv.phase == "stick"]


@pytest.mark.parametrize("method", ["closed-bdf1", "closed-bdf2", "bdf2"])
@pytest.mark.parametrize(("forcing", "x0"), [(paper_F2, 0.0), (None, 0.5)])
def test_stick_intervals_match_the_exact_reference(method, forcing, x0):
    sol = simulate(bingham_oscillator(x0=x0, forcing=forcing), method=method, dt=DT,
                   t_end=T_END)
    got = [(a, b) for a, b in sol.stick_intervals("dashpot") if b - a > 5 * DT]
    want = [(a, b) for a, b in _exact_sticks(forcing, x0) if b - a > 5 * DT]
    assert len(got) == len(want), (got, want)
    tol = 40 * DT if method == "closed-bdf1" else 5 * DT
    for (a, b), (a_ex, b_ex) in zip(got, want, strict=True):
        assert abs(a - a_ex) <= tol and abs(b - b_ex) <= tol, ((a, b), (a_ex, b_ex))
    assert got[-1][1] == T_END            # at rest for good


def test_events_are_the_branch_switches_at_the_first_sample_on_the_new_branch():
    sol = simulate(bingham_oscillator(forcing=paper_F2), method="closed-bdf1", dt=DT,
                   t_end=T_END)
    events = sol.events
    assert events and all(isinstance(e, Event) and e.kind == "switch" for e in events)
    assert all(e.element == "dashpot" for e in events)        # a linear spring never switches
    assert [e.t for e in events] == sorted(e.t for e in events)
    for prev, ev in zip(events, events[1:], strict=False):
        assert ev.from_branch == prev.to_branch
    sticks = sol.stick_intervals("dashpot")
    # a stick starts at t = 0 or at an event into the locking branch, and ends one sample
    # before the event out of it
    into = {e.t for e in events}
    for a, b in sticks:
        assert a == 0.0 or a in into
        assert b == T_END or round(b + DT, 9) in {round(t, 9) for t in into}


def test_stick_intervals_of_every_dashpot_and_argument_checks():
    scene = Scene(
        [Mass("mass", m=1.0, x0=0.3), Junction("j")],
        [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
         Element("arm", get_law("linear_spring").bind(k=100.0), "j", "mass"),
         Element("damper", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "j"),
         Element("drag", get_law("newtonian").bind(c=0.5), "ground", "mass")],
    )
    sol = simulate(scene, method="bdf1", dt=1e-2, t_end=3.0)
    table = sol.stick_intervals()
    assert set(table) == {"damper", "drag"}
    assert table["drag"] == []                # a Newtonian dashpot never locks
    assert table["damper"] and table["damper"][-1][1] == 3.0
    with pytest.raises(ValueError, match="`element`.*'spring'"):
        sol.stick_intervals("spring")
    with pytest.raises(ValueError, match="`element`.*'nope'"):
        sol.stick_intervals("nope")


@given(m=log_uniform(0.1, 10.0), k=log_uniform(1.0, 1e3), gamma=log_uniform(0.1, 10.0),
       tau=st.floats(0.01, 5.0), x0=st.floats(-1.0, 1.0), amplitude=st.floats(0.0, 20.0))
def test_stick_intervals_agree_with_the_velocity_of_the_closed_form(m, k, gamma, tau, x0,
                                                                     amplitude):
    """Cross-check: the samples in stick intervals (the law's locking branch) are exactly
    the samples where the closed form's velocity is 0 with the force within the yield band
    (Algorithm 1's own stuck test). ``tau > 0``: with ``tau = 0`` the law is Newtonian and
    has no locking branch (a mass at rest under no force is not stuck)."""
    forcing = SineBurst(amplitude, 5.0, 0.5)
    sol = simulate(bingham_oscillator(m=m, k=k, gamma=gamma, tau=tau, x0=x0, forcing=forcing),
                   method="closed-bdf1", dt=1e-2, t_end=1.0)
    stuck = np.zeros(len(sol.t), dtype=bool)
    for a, b in sol.stick_intervals("dashpot"):
        stuck[(sol.t >= a) & (sol.t <= b)] = True
    v, F = sol.v["mass"], sol.F["dashpot"]
    assert np.array_equal(stuck, (v == 0.0) & (np.abs(F) <= tau))


def test_radau5_stick_intervals_come_from_its_located_events():
    """A Coulomb slider on a spring, pushed by a sine: it sticks from rest until the load
    exceeds its yield force, then only reverses (slip to slip through v = 0). radau5's
    intervals are the same on its step points and on an output grid, and agree with
    bdf2 at a fine step; the reversals are no sticks (each came out as a zero-length
    interval on the step points, and the first stick as (0, 0))."""
    scene = Scene([Mass("m", m=1.0)],
                  [Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m"),
                   Element("f", get_law("coulomb").bind(tau=1.0, r=10.0), "ground", "m")],
                  {"m": SineBurst(3.0, 3.0, 4.0)})
    steps = simulate(scene, method="radau5", t_end=3.0, rtol=1e-8)
    grid = simulate(scene, method="radau5", t_end=3.0, rtol=1e-8, dt=1e-3)
    fine = simulate(scene, method="bdf2", t_end=3.0, dt=1e-4)
    assert len([e for e in steps.events if e.element == "f"]) >= 3  # the reversals
    got = steps.stick_intervals("f")
    assert got == grid.stick_intervals("f")
    want = [(a, b) for a, b in fine.stick_intervals("f") if b - a > 5e-4]
    assert len(got) == len(want) == 1
    (a, b), (a_f, b_f) = got[0], want[0]
    assert a == a_f == 0.0 and abs(b - b_f) <= 2e-4 and b > 0.1
