"""Two Coulomb dashpots in parallel reverse beside a taut string (seed 25171 of the
property of both loops).

Three masses: ``m0`` on a spring to ground, ``m2`` hung from ``m0`` by a taut string
``e2`` beside a Herschel-Bulkley ``n = 0.5`` dashpot ``e3`` (stuck), ``m1`` joined to
``m0`` by two Coulomb dashpots ``e1`` and ``e4`` (opposite ways round) and to ground by a
spring. At ``t = 0.2498445`` the two Coulomb dashpots, slipping together, reach rate 0
under a load of 1.5 on their pair, far past their joint yield force ``0.326``: they
reverse. The string, taut since ``t = 0.0288``, had drifted ``1.4e-14`` past its length.
The full laws' probe (:func:`lumped.solvers.modes.choice.select_modes`) read it in
positions' form, a force of ``m 1.4e-14 / h_p^2`` (2178 on a probe of ``1e-9`` s, where
it carries 0.57), and the pair slipping on as before: every step crossed their guard at
once, a mode choice of 0.3 s every ``1.5e-8`` s, about 12 minutes to the run's work
budget. The probe now reads a string at its length on the velocity level
(:func:`lumped.solvers.modes.mode_guess.lock_drifts`)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.codegen.branches import law_branches
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.modes.mode_guess import lock_drifts

DT = 0.005282882637806486  # the property's middle level: rtol = dt^2, atol = dt^3
T_END = 0.4226306110245188
REVERSAL = 0.2498445


def friction_beside_string() -> Scene:
    """The scene as the property drew it (the positions' tiny ``x0`` set to 0)."""
    law = get_law
    return Scene(
        [Mass("m0", 0.9999963597864482, v0=0.31710090750550934),
         Mass("m1", 1.0, v0=-0.028422047777974857),
         Mass("m2", 0.1803398730159171, v0=1.8967531222727514)],
        [Element("e0", law("linear_spring").bind(k=38.324124493143536), "ground", "m0"),
         Element("e1", law("coulomb").bind(tau=0.010244798239909113, r=8.27529649177872),
                 "m0", "m1"),
         Element("e2", law("string_spring").bind(k=0.9999997255105045,
                                                 L=0.02232301210057683), "m0", "m2"),
         Element("e3", law("herschel_bulkley").bind(gamma=2.8555086919149284, tau=0.1,
                                                    n=0.5), "m0", "m2"),
         Element("e4", law("coulomb").bind(tau=0.31622776601683794, r=10.0), "m1", "m0"),
         Element("e5", law("linear_spring").bind(k=25.29332856240838), "m1", "ground")])


def test_the_pair_reverses_at_rate_zero_and_the_run_ends():
    sol = simulate(friction_beside_string(), method="radau5", dt=DT, t_end=T_END,
                   rtol=DT**2, atol=DT**3, compiled=False, max_steps=20_000)
    assert sol.ok, sol.message
    assert "bridged" not in sol.message and "bridges" not in sol.stats, sol.message
    assert sol.stats["steps"] + sol.stats["rejected"] < 500, sol.stats
    turn = [(ev.element, ev.from_branch, ev.to_branch) for ev in sol.events
            if abs(ev.t - REVERSAL) < 1e-6]
    # e1 (m0 -> m1) from F = -tau to +tau, e4 (m1 -> m0) from +tau to -tau
    assert turn == [("e1", 0, 1), ("e4", 1, 0)], sol.events
    assert len(sol.events) <= 8
    # after it the pair slips the other way: m1 faster than m0, their forces at +-tau
    after = sol.t > REVERSAL + 1e-3
    assert np.all(sol.v["m1"][after] > sol.v["m0"][after])
    assert np.allclose(sol.F["e1"][after], 0.010244798239909113, rtol=1e-9)
    # against the same run at rtol 1e-10 (1.7e-8 apart), and backward differences of
    # order 2 (bdf2 at 1e-4, 5e-5 and 4e-5 s: 2.5e-5, 7.4e-6, 4.6e-6 off that run; at
    # 2e-5 s and below the fixed-step methods stop at t = 0.2698 on the round-off of the
    # locks e2, e3 in parallel)
    tight = simulate(friction_beside_string(), method="radau5", dt=DT, t_end=T_END,
                     rtol=1e-10, atol=1e-13, compiled=False, max_steps=20_000)
    ref = simulate(friction_beside_string(), method="bdf2", dt=5e-5, t_end=T_END)
    assert tight.ok and "bridges" not in tight.stats and ref.ok
    for n in ("m0", "m1", "m2"):
        assert sol.x[n][-1] == pytest.approx(tight.x[n][-1], abs=1e-6), n
        assert sol.x[n][-1] == pytest.approx(ref.x[n][-1], abs=2e-5), n


def test_lock_drifts_reads_strings_at_their_length_only():
    L = 0.02232301210057683
    scene = Scene(
        [Mass("a", 1.0), Mass("b", 1.0), Mass("c", 1.0)],
        [Element("s", get_law("string_spring").bind(k=1.0, L=L), "a", "b"),
         Element("t", get_law("string_spring").bind(k=1.0, L=L), "a", "c"),
         Element("k", get_law("linear_spring").bind(k=1.0), "b", "c"),
         Element("d", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "a")])
    lbs = [law_branches(el.law) for el in scene.elements]
    x = [0.3, 0.3 + L + 1.4e-14, 0.3 + 0.5 * L]  # s past its length, t slack
    got = lock_drifts(scene, lbs, x)
    assert got[0] == pytest.approx(-1.4e-14, rel=1e-2)
    assert got[1:] == [0.0, 0.0, 0.0]
    # beyond sqrt(eps) max(|L|, |x_a|, |x_b|) of its length: positions' form
    far = 0.3 + L + 10 * math.sqrt(np.finfo(float).eps) * 0.33
    assert lock_drifts(scene, lbs, [0.3, far, 0.3])[0] == 0.0


def test_the_old_creep_is_a_stall_at_the_default_budget(monkeypatch):
    # the full laws' probe in positions' form again (the creep before lock_drifts): its
    # kept choices, 1.5e-8 s apart with 0.17 s to go, are a stall after four of them
    # (budget.KEPT_CHOICES) and the run is bridged; before, the default budget's series
    # test needed a pace 100 times slower than 1e6 tries left: a choice of 0.3 s every
    # 1.5e-8 s for 12 minutes, to the pace test's window
    import lumped.solvers.eventdriven.mode_state as mode_state
    import lumped.solvers.modes.choice as choice

    monkeypatch.setattr(choice, "lock_drifts", lambda scene, *args: [0.0] * len(
        scene.elements))
    calls = []
    at_event = mode_state.ModeState.at_event

    def counted(self, t, *args):
        calls.append(t)
        assert len(calls) < 60, f"{len(calls)} events, the last at t = {t!r}"
        return at_event(self, t, *args)

    monkeypatch.setattr(mode_state.ModeState, "at_event", counted)
    sol = simulate(friction_beside_string(), method="radau5", dt=DT, t_end=T_END,
                   rtol=DT**2, atol=DT**3, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats["bridges"] == 1, sol.stats
    assert "kept the mode there 4 times" in sol.message

