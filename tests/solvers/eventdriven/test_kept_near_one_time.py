"""Choices of the mode that keep it at (nearly) one time end the run in a few choices
(issue 29, "never a hang"; :meth:`lumped.solvers.eventdriven.budget.WorkBudget.kept`)."""

from __future__ import annotations

import math

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.scene import SineBurst
from lumped.solvers.eventdriven import budget, mode_state, run
from lumped.solvers.status import Status

T_STAR = 0.13772186781395804  # e0's guard read crossed, kept after every step from here


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


def test_a_mode_kept_after_every_short_step_ends_the_run_in_a_few_choices(monkeypatch):
    # each step of 5e-12 s crossed e0's guard (a junction's Herschel-Bulkley n = 0.3
    # dashpot) at its start, and the full laws kept the mode, a mode choice of 18 000
    # residual evaluations (2 s) each: the stuck test saw once per 250 choices (minutes;
    # more than 20 min at the tight tolerance's property run); now 4 choices
    calls = []
    at_event = mode_state.ModeState.at_event

    def counted(self, t, *args):
        if t >= T_STAR:
            calls.append(t)
            assert len(calls) <= 20, "a mode kept at t* again and again"  # (the base)
        return at_event(self, t, *args)

    bridge_over = run.Radau5Run.bridge_over
    bridged = []

    def first_bridge_only(self):  # (the one at t = 0.12422; the stall's fails, 6 s)
        bridged.append(self.t)
        return len(bridged) == 1 and bridge_over(self)

    monkeypatch.setattr(mode_state.ModeState, "at_event", counted)
    monkeypatch.setattr(run.Radau5Run, "bridge_over", first_bridge_only)
    sol = simulate(_loaded_network(), method="radau5", t_end=0.5, dt=0.005, rtol=1e-10,
                   atol=1e-13, compiled=False, throw=False)
    assert sol.status is Status.STEP_TOO_SMALL and len(bridged) == 2
    assert "kept the mode there 4 times, from t = " in sol.message
    assert len(calls) <= 8 and calls[-1] - calls[0] < 1e-10


def test_a_series_of_kept_choices_is_at_a_hopeless_pace_only():
    b = budget.WorkBudget(1_000_000, 0.5)
    stats = {"steps": 300, "rejected": 130}
    # at one t, or crept on by 5.9e-12 s a choice: a series
    assert [b.kept(0.1, stats) for _ in range(3)] == [1, 2, 3]
    assert [b.kept(T_STAR + k * 5.87e-12, stats) for k in range(4)] == [1, 2, 3, 4]
    # kept choices 1 us apart (2e5 choices to t_end, 1e6 tries left): no series
    assert [b.kept(0.2 + k * 1e-6, stats) for k in range(4)] == [1, 1, 1, 1]
    # the pace is that of the series since its first choice
    assert [b.kept(0.3 + t, stats) for t in (0.0, 1e-9, 1e-9, 8e-9)] == [1, 2, 3, 1]
