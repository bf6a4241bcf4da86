"""Choices of the mode that keep it at (nearly) one time end the run in a few choices
(issue 29, "never a hang"; :meth:`lumped.solvers.eventdriven.budget.WorkBudget.kept`); the
scene that kept them, a junction's dashpot reversing beside a taut string, now runs on
(:func:`lumped.solvers.modes.mode_guess.probe_state`)."""

from __future__ import annotations

import math

import numpy as np

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.scene import SineBurst
from lumped.solvers.eventdriven import budget, mode_state

T_STAR = 0.13772186781395804  # e0's reversal (its guard was read crossed at every step)


def _loaded_network() -> Scene:
    # the LUMPED_LARGE tight-tolerance draw (profile long, seed 22036; e6's length does
    # not matter: the run is the same for L = 0.309 and 0.187)
    law = get_law
    nodes = [Junction("j0", x0=2.1169743959251394e-280),
             Mass("m1", m=1.0, x0=1e-10, v0=1.9560005348671519),
             Mass("m2", m=1.0, x0=0.9038776255776981, v0=0.2188241071295347),
             Mass("m3", m=6.382825532589985, x0=-0.9374120788327445, v0=-1.9380219266718957)]
    els = [
        Element("e0", law("herschel_bulkley").bind(gamma=1.0, tau=0.11449813609920753, n=0.3),
                "ground", "j0"),
        Element("e1", law("string_spring").bind(k=5.824914987394342, L=0.0010000001),
                "j0", "m1"),
        Element("e2", law("bingham").bind(gamma=1.0, tau=0.021114489476348367), "j0", "m2"),
        Element("e3", law("herschel_bulkley").bind(gamma=1.9732609650945703,
                                                   tau=0.08790508269112257, n=2.0),
                "m2", "m3"),
        Element("e4", law("implicit_spring").bind(k=16.292220464466197, L0=0.007563686756579493,
                                                  F0=2.161099006276271), "m1", "m3"),
        Element("e5", law("linear_spring").bind(k=0.9999998627552429), "m3", "ground"),
        Element("e6", law("string_spring").bind(k=0.18743599143933298, L=0.18743599143933298),
                "j0", "m3")]
    return Scene(nodes, els, {"m2": SineBurst(-29.303116853593185, 9.99976974414163, math.inf)})


def test_a_dashpot_reversing_beside_a_taut_string_slips_on_at_once(monkeypatch):
    # j0 and m1 (e1 taut, 4.6e-17 below its length L) reverse at t* at -13.4 m/s^2: e0
    # (Herschel-Bulkley n = 0.3) goes from slip+ straight to slip-. The junction's rate
    # after the choice was a 4.3e-5 s probe's, -5.7e-4 (the held-mode probe at 4.3e-11 s
    # cycled on the string's rounding), off the stage solution's -1e-15: the dense output
    # of e0's rate overshot through 0 just after the first stage, every step, down to the
    # floor; then the choices read slip+ again and kept it (4 times, ended by WorkBudget.kept)
    calls = []
    at_event = mode_state.ModeState.at_event

    def counted(self, t, *args):
        if abs(t - T_STAR) < 1e-6:
            calls.append(t)
            assert len(calls) <= 20, "a mode kept at t* again and again"  # (the base)
        return at_event(self, t, *args)

    monkeypatch.setattr(mode_state.ModeState, "at_event", counted)
    sol = simulate(_loaded_network(), method="radau5", t_end=0.5, dt=0.005, rtol=1e-10,
                   atol=1e-13, compiled=False, throw=False)
    assert sol.ok, sol.message
    e0 = [ev for ev in sol.events if ev.element == "e0" and abs(ev.t - T_STAR) < 1e-6]
    assert [(ev.from_branch, ev.to_branch) for ev in e0] == [(0, 1)]  # slip+ -> slip-
    assert len(calls) == 1
    # across the reversal, as bdf2 (first order here, through the events): within twice
    # its own error estimate |x(dt) - x(dt/2)|
    ref = [simulate(_loaded_network(), method="bdf2", t_end=0.15, dt=dt) for dt in
           (1e-4, 5e-5)]
    for T in (0.13, 0.14, 0.15):
        i, j = (int(np.argmin(abs(np.asarray(s.t) - T))) for s in (sol, ref[1]))
        k = int(np.argmin(abs(np.asarray(ref[0].t) - T)))
        for key in ("x", "v"):
            for node in ("j0", "m1", "m2", "m3"):
                b1, b2 = getattr(ref[0], key)[node][k], getattr(ref[1], key)[node][j]
                got = getattr(sol, key)[node][i]
                assert abs(got - b2) <= 2.0 * abs(b2 - b1) + 1e-9, (T, key, node)


def test_a_series_of_kept_choices_is_at_a_hopeless_pace_only():
    b = budget.WorkBudget(1_000_000, 0.5)
    stats = {"steps": 300, "rejected": 130}
    # at one t, or crept on by 5.9e-12 s a choice: a series
    assert [b.kept(0.1, stats) for _ in range(3)] == [1, 2, 3]
    assert [b.kept(T_STAR + k * 5.87e-12, stats) for k in range(4)] == [1, 2, 3, 4]
    # kept choices 10 us apart (3e4 choices to t_end, 1e6 tries left): no series
    assert [b.kept(0.2 + k * 1e-5, stats) for k in range(4)] == [1, 1, 1, 1]
    # 1 us apart, 3e5 choices to t_end: a series whatever the budget (KEPT_CHOICES)
    assert [b.kept(0.21 + k * 1e-6, stats) for k in range(4)] == [1, 2, 3, 4]
    huge = budget.WorkBudget(10**12, 0.5)
    assert [huge.kept(0.22 + k * 1e-6, stats) for k in range(4)] == [1, 2, 3, 4]
    # ... and at a small budget its tries left decide (100 left: 1e4 choices)
    small = budget.WorkBudget(530, 0.5)
    assert [small.kept(0.2 + k * 1e-5, stats) for k in range(4)] == [1, 2, 3, 4]
    # the pace is that of the series since its first choice
    assert [b.kept(0.3 + t, stats) for t in (0.0, 1e-9, 1e-9, 1e-5)] == [1, 2, 3, 1]
