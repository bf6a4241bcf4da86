"""``radau5`` at events: stuck intervals without steps (:mod:`lumped.solvers.modes.stuck`), the
guessed mode (:mod:`lumped.solvers.modes.mode_guess`) and the crossing root
(:mod:`lumped.solvers.modes.crossing_root`).

Accuracy against :mod:`lumped.reference` (the exact event-driven solution); the shortcuts
against the full paths they replace.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.bench.scenes import SCENES, generic_scene
from lumped.reference import exact_solution
from lumped.scene.forcing import SineBurst
from lumped.solvers.closed.closed_form import BinghamOscillator
from lumped.solvers.eventdriven import mode_state as adaptive_modes
from lumped.solvers.modes.crossing_root import first_root_py, illinois


def _bench(name: str):
    return next(s for s in SCENES if s.name == name)


def _switches(sol):
    return [ev for ev in sol.events if ev.kind == "switch"]


def test_a_stuck_run_takes_no_steps_and_carries_the_forcing_exactly():
    # eq. (17a): F1 never reaches the yield force; the dashpot carries F(t) - k x = F(t)
    bs = _bench("forcing-F1")
    sol = simulate(generic_scene(bs), method="radau5", t_end=5.0, rtol=1e-8, atol=1e-11)
    assert sol.stats["steps"] == 0 and sol.stats["held_intervals"] == 2
    assert np.all(sol.x["mass"] == 0.0) and np.all(sol.v["mass"] == 0.0)
    t = np.linspace(0.0, 5.0, 5001)
    rows = sol.sol(t)
    f = np.array([bs.forcing(ti) for ti in t])
    assert np.all(rows[:, 1] == 0.0) and np.all(rows[:, 2] == 0.0)
    assert np.all(rows[:, 3] == 0.0)  # the spring at x = 0
    assert np.max(np.abs(rows[:, 4] - f)) <= 4e-16 * bs.forcing.amplitude
    # the output rows lie on the balance too (the scan's samples: the forcing's extrema)
    assert np.max(np.abs(sol.F["dashpot"] - [bs.forcing(ti) for ti in sol.t])) <= 1e-16
    assert [ev.kind for ev in sol.events] == ["time"]


def test_break_out_times_match_the_exact_reference():
    bs = _bench("stick-breakout")
    sol = simulate(generic_scene(bs), method="radau5", t_end=bs.t_end, rtol=1e-10,
                   atol=1e-13)
    assert sol.stats["held_intervals"] >= 8
    ex = exact_solution(bs.osc, x0=bs.x0, v0=bs.v0, forcing=bs.forcing,
                        t_eval=np.array([0.0, bs.t_end]))
    exact = [ev.t for ev in ex.events if ev.kind != "forcing-off"]
    ours = _switches(sol)
    assert len(ours) == len(exact)
    assert max(abs(ev.t - te) for ev, te in zip(ours, exact, strict=True)) <= 1e-10
    t = np.linspace(0.0, bs.t_end, 4001)
    x = exact_solution(bs.osc, x0=bs.x0, v0=bs.v0, forcing=bs.forcing, t_eval=t)
    assert np.max(np.abs(sol.sol(t)[:, 1] - x.trajectory.x)) <= 1e-10


@settings(max_examples=40)
@given(k=st.floats(10.0, 1e3), tau=st.floats(0.2, 5.0), ratio=st.floats(1.05, 4.0),
       omega=st.floats(0.5, 20.0), t_off=st.floats(0.5, 3.0))
def test_stuck_starts_and_break_outs_against_the_reference(k, tau, ratio, omega, t_off):
    """From rest and stuck, a sine burst above the yield force: the break-out found by the
    scan, and every later event, at the exact times; x to the tolerance; v exactly 0
    while stuck."""
    osc = BinghamOscillator(m=1.0, k=k, gamma=1.0, tau=tau)
    forcing = SineBurst(ratio * tau, omega, t_off)
    from lumped.bench.scenes import BenchScene

    bs = BenchScene("random", osc, 0.0, forcing=forcing, t_end=t_off + 1.0)
    sol = simulate(generic_scene(bs), method="radau5", t_end=bs.t_end, rtol=1e-9,
                   atol=1e-12 * max(1.0, tau / k))
    assert sol.stats["held_intervals"] >= 1
    ex = exact_solution(osc, x0=0.0, v0=0.0, forcing=forcing,
                        t_eval=np.linspace(0.0, bs.t_end, 801))
    # (a switch at the forcing's switch-off is the reference's "forcing-off" event)
    exact = [ev.t for ev in ex.events if ev.kind != "forcing-off"]
    ours = [ev for ev in _switches(sol) if ev.t != t_off]
    assert len(ours) == len(exact)
    assert all(abs(ev.t - te) <= 1e-8 for ev, te in zip(ours, exact, strict=True))
    scale = ratio * tau / k
    got = sol.sol(np.linspace(0.0, bs.t_end, 801))
    assert np.max(np.abs(got[:, 1] - ex.trajectory.x)) <= 1e-6 * scale
    t_first = ours[0].t if ours else math.inf  # a burst off before its peak: no event
    assert np.all(sol.v["mass"][sol.t < t_first] == 0.0)


@pytest.mark.parametrize("scene", ["stick-breakout", "fast-forcing", "chain-2"])
def test_the_guessed_mode_is_the_full_search_s(scene, monkeypatch):
    def make():
        if scene == "chain-2":
            return bingham_chain(2), 2.0
        bs = _bench(scene)
        return generic_scene(bs), min(bs.t_end, 3.0)

    sc, t_end = make()
    kw = {"method": "radau5", "t_end": t_end, "rtol": 1e-8, "atol": 1e-11}
    fast = simulate(sc, **kw)
    monkeypatch.setattr(adaptive_modes, "try_modes", lambda *a, **k: None)
    sc, _ = make()
    full = simulate(sc, **kw)
    assert [(e.element, e.kind, e.from_branch, e.to_branch) for e in fast.events] == [
        (e.element, e.kind, e.from_branch, e.to_branch) for e in full.events]
    assert max(abs(e.t - f.t) for e, f in zip(fast.events, full.events, strict=True)) <= 1e-12
    t = np.linspace(0.0, t_end, 1001)
    a, b = fast.sol(t), full.sol(t)
    scale = np.maximum(1.0, np.abs(b).max(axis=0))
    assert np.all(np.abs(a - b) <= 1e-9 * scale)


def test_the_illinois_root_is_found_to_round_off():
    g = lambda s: (s - 0.3) * (1.0 + s * s) - 1e-3 * s  # noqa: E731
    r = illinois(g, 0.0, 1.0, g(0.0), g(1.0)) if g(0.0) > 0 else None
    if r is None:  # g(0) < 0 here: the guard's sign convention, flipped
        h = lambda s: -g(s)  # noqa: E731
        r = illinois(h, 0.0, 1.0, h(0.0), h(1.0))
    exact = 0.3 + 1e-3 * 0.3 / (1.0 + 0.09)  # one Newton step from 0.3, then polish
    for _ in range(5):
        exact -= g(exact) / ((1.0 + exact * exact) + 2 * exact * (exact - 0.3) - 1e-3)
    assert abs(r - exact) <= 4e-16


def test_the_first_crossing_on_a_step_polynomial():
    # a guard g = q on q(s) = 1 - 2 s (linear through the nodes): root at s = 0.5; a second
    # guard crossing later (q + 0.5 at s = 0.75) is not the first
    from lumped.solvers.radau.tableau import C

    nodes = [(tuple(1.0 - 2.0 * s for s in (0.0, *C)), (0.0, 0.0, 0.0, 0.0))]
    got = first_root_py(nodes, [lambda q, F: (q + 0.5, q)])
    assert got is not None and got[1] == (0, 1) and abs(got[0] - 0.5) <= 1e-15
    assert first_root_py(nodes, [lambda q, F: (q + 2.0,)]) is None
    assert math.isfinite(got[0])


def test_the_parts_of_a_mode_kept_per_plan_are_those_made_anew():
    """:meth:`ModeState.set_modes` takes a mode's kernels, guards, watched elements and
    lock count from the scene plan after its first use: for every mode of a scene with
    two dashpots in parallel (their locks share the load: a cone split) and one in
    series, the held parts, first made and then cached, are those the laws give, and the
    cones are there exactly when two locks sit in parallel."""
    import itertools
    from types import MappingProxyType

    from lumped import Element, Mass, Scene
    from lumped.laws import get_law
    from lumped.solvers.eventdriven.setup import read_options, scene_plan
    from lumped.solvers.modes.lock_events import lock_cones
    from lumped.solvers.registry import RunSettings

    bingham = get_law("bingham")
    scene = Scene([Mass("m1", m=1.0), Mass("m2", m=2.0)],
                  [Element("s1", get_law("linear_spring").bind(k=100.0), "ground", "m1"),
                   Element("d1", bingham.bind(gamma=1.0, tau=1.0), "ground", "m1"),
                   Element("d2", bingham.bind(gamma=2.0, tau=0.5), "ground", "m1"),
                   Element("d3", bingham.bind(gamma=1.0, tau=0.3), "m1", "m2")])
    plan = scene_plan(scene)
    settings_ = RunSettings(t_end=1.0, dt=None, rtol=1e-6, atol=1e-9, throw=True,
                            options=None, extra=MappingProxyType({}))
    ms = adaptive_modes.ModeState(scene, plan, settings_, read_options(settings_), 1e-6,
                                  1e-9, {}, 1e-6)
    lbs = plan.branches
    F = [0.1, 0.2, -0.1, 0.05]
    kinds = set()
    for _ in range(2):  # made, then from the cache
        for mode in itertools.product(*(range(lb.count) for lb in lbs)):
            ms.set_modes(list(mode), F)
            assert ms.modes == list(mode)
            assert ms.kernels == [lbs[e].stage_kernel_for(b) for e, b in enumerate(mode)]
            assert ms.guards == [lbs[e].stage_guards_for(b) for e, b in enumerate(mode)]
            assert ms.watched == [e for e in range(4) if lbs[e].count > 1]
            locked = lock_cones(lbs, list(mode), F, plan.cyclic)
            both = 1 in locked and 2 in locked  # d1 and d2 locked, in parallel
            assert sorted(ms.cones) == ([1, 2] if both else [])
            if both:
                assert ms.cones == {e: locked[e] for e in (1, 2)}
            kinds.add(both)
    assert kinds == {True, False}
    assert len(plan.mode_parts) == math.prod(lb.count for lb in lbs)


def test_held_forces_follow_each_scene_s_own_forcing():
    """The forcing's kinds are kept per forcing (:class:`lumped.solvers.modes.stuck.StaticHold`):
    scenes of one structure, even of the same element objects, under other forcings (two
    sine bursts, a constant, none), run in turn, each carry their own load in the held
    dashpot, bit for bit, in the rows and the dense output."""
    from lumped import Element, Mass, Scene
    from lumped.laws import get_law

    elements = [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
                Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground",
                        "mass")]
    loads = [SineBurst(0.5, 5.0 * math.pi, 1.0), SineBurst(0.3, 2.0, 2.5), 0.2, None]
    scenes = [Scene([Mass("mass", m=1.0, x0=0.003)], elements,
                    {} if f is None else {"mass": f}) for f in loads]
    t = np.linspace(0.0, 4.0, 801)
    for _ in range(2):
        for sc in scenes:
            sol = simulate(sc, method="radau5", t_end=4.0, rtol=1e-6, compiled=True)
            assert sol.stats["steps"] == 0
            F_s = sol.data[0, 3]
            f_rows = np.array([sc.external_forces(ti)[0] for ti in sol.t])
            assert np.array_equal(sol.F["dashpot"], f_rows - F_s)
            f = np.array([sc.external_forces(ti)[0] for ti in t])
            assert np.array_equal(sol.sol(t)[:, 4], f - F_s)
            assert np.all(sol.sol(t)[:, 1] == 0.003) and np.all(sol.sol(t)[:, 2] == 0.0)
