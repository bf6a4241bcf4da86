"""``radau5``'s work budget ``max_steps`` (issue 29, :mod:`lumped.solvers.eventdriven.budget`):
every step tried counts, a run whose pace cannot reach ``t_end`` within the budget stops
at once, and the stop is a clear ``Status.MAX_ITERS`` in both loops, never bridged."""

from __future__ import annotations

import pytest

from lumped import Element, Mass, Scene, SolverError, Status, get_law, simulate
from lumped.scenarios import scenario_scene
from lumped.solvers.eventdriven import budget
from lumped.solvers.eventdriven.run import Radau5Run
from lumped.solvers.status import RunSettings

LOOPS = [False, True]


def _oscillator() -> Scene:
    # undamped: about 40 steps a period at rtol 1e-8, the same pace throughout
    return Scene([Mass("m", m=1.0, x0=0.1)],
                 [Element("k", get_law("linear_spring").bind(k=100.0), "ground", "m")])


@pytest.mark.parametrize("compiled", LOOPS)
def test_max_steps_ends_the_run_with_a_clear_status(compiled):
    scene = scenario_scene("forcing-F2")
    full = simulate(scene, method="radau5", t_end=2.0, rtol=1e-8, compiled=compiled)
    assert full.ok and full.stats["steps"] > 100
    sol = simulate(scene, method="radau5", t_end=2.0, rtol=1e-8, compiled=compiled,
                   max_steps=60, throw=False)
    assert sol.status is Status.MAX_ITERS  # (not bridged, though bridge=True)
    assert sol.stats["steps"] + sol.stats["rejected"] <= 60 and sol.t[-1] < 0.2
    assert "bridge" not in sol.message
    for part in ("radau5 stopped at t = ", "of t_end = 2.0", "max_steps = 60 is spent",
                 f"{sol.stats['steps']} accepted steps", "give a larger max_steps"):
        assert part in sol.message
    with pytest.raises(SolverError, match="max_steps = 60 is spent") as err:
        simulate(scene, method="radau5", t_end=2.0, rtol=1e-8, compiled=compiled,
                 max_steps=60)
    assert err.value.status is Status.MAX_ITERS and err.value.t == sol.t[-1]


def test_both_loops_stop_at_the_same_step():
    scene = scenario_scene("forcing-F2")
    a, b = (simulate(scene, method="radau5", t_end=2.0, rtol=1e-8, compiled=c,
                     max_steps=137, throw=False) for c in LOOPS)
    assert a.status is b.status is Status.MAX_ITERS
    assert a.t[-1] == b.t[-1] and a.stats["steps"] == b.stats["steps"]


def test_rejected_steps_count_against_the_budget():
    # a Herschel-Bulkley n = 2 dashpot released at 0.90 N of spring force (yield 0.53 N):
    # the simplified Newton misses its flat start again and again (rejected steps)
    hb = get_law("herschel_bulkley").bind(gamma=1.0, tau=0.5286419768660505, n=2.0)
    scene = Scene([Mass("m0", m=1.0, x0=-0.45170628585923367)],
                  [Element("e0", get_law("linear_spring").bind(k=2.0), "ground", "m0"),
                   Element("e4", hb, "ground", "m0")])
    full = simulate(scene, method="radau5", t_end=0.5, rtol=1e-6, compiled=False)
    steps, rejected = full.stats["steps"], full.stats["rejected"]
    assert full.ok and rejected >= 2
    # enough for the accepted steps, not for the steps tried
    sol = simulate(scene, method="radau5", t_end=0.5, rtol=1e-6, compiled=False,
                   max_steps=steps + 1, throw=False)
    assert sol.status is Status.MAX_ITERS and sol.stats["steps"] < steps
    assert f"{sol.stats['rejected']} rejected" in sol.message


def test_bridged_steps_count_against_the_budget():
    # an "accumulation" of 3 events within 1 s (by the keywords) is bridged by backward
    # Euler: its steps are work too
    scene = scenario_scene("forcing-F2")
    extra = {"zeno_events": 3, "zeno_window": 1.0, "compiled": False}
    run = Radau5Run(scene, RunSettings(t_end=5.0, rtol=1e-8, atol=1e-10, extra=extra))
    raw = run.run()
    bridged = raw.stats["bridged_steps"]
    assert raw.status is Status.SUCCESS and bridged >= 32
    own = run.budget.tries(raw.stats) - bridged
    kw = {"t_end": 5.0, "rtol": 1e-8, "atol": 1e-10, **extra}
    assert simulate(scene, method="radau5", max_steps=own + bridged + 1, **kw).ok
    sol = simulate(scene, method="radau5", max_steps=own + bridged // 2, throw=False, **kw)
    assert sol.status is Status.MAX_ITERS and "max_steps" in sol.message
    assert "backward-Euler steps of bridges" in sol.message


@pytest.mark.parametrize("compiled", LOOPS)
def test_a_pace_that_cannot_reach_t_end_stops_at_once(compiled, monkeypatch):
    # 1000 s of a 0.63 s period need about 64 000 steps: with max_steps = 2000 the run
    # stops after its first window of tries (200 here), not after 2000 (the compiled loop
    # returns to the driver at least once a window)
    monkeypatch.setattr(budget, "PACE_WINDOW", 200)
    sol = simulate(_oscillator(), method="radau5", t_end=1000.0, rtol=1e-8, atol=1e-11,
                   compiled=compiled, max_steps=2000, throw=False)
    assert sol.status is Status.MAX_ITERS
    assert 200 <= sol.stats["steps"] + sol.stats["rejected"] <= 210
    assert "cannot reach t_end: its last 20" in sol.message


@pytest.mark.parametrize("compiled", LOOPS)
def test_a_steady_pace_within_the_budget_runs_to_the_end(compiled, monkeypatch):
    monkeypatch.setattr(budget, "PACE_WINDOW", 200)
    full = simulate(_oscillator(), method="radau5", t_end=20.0, rtol=1e-8, atol=1e-11,
                    compiled=compiled)
    tried = full.stats["steps"] + full.stats["rejected"]
    sol = simulate(_oscillator(), method="radau5", t_end=20.0, rtol=1e-8, atol=1e-11,
                   compiled=compiled, max_steps=int(1.2 * tried))
    assert sol.ok and sol.stats["steps"] == full.stats["steps"]


def test_the_pace_window_scales_with_the_budget():
    assert budget.window(1_000) == budget.window(1_000_000) == budget.PACE_WINDOW == 10_000
    assert budget.window(10**8) == 10**6


def _window(b: budget.WorkBudget, t: float, steps: int, rejected: int):
    # the budget's test after a window of STUCK_WINDOW tries from the last one
    stats = {"steps": steps, "rejected": rejected}
    return b.check(t, stats)


@pytest.mark.parametrize(("rejected", "moved", "stuck"), [
    (600, 1e-9, True),   # mostly rejected, a hopeless pace: stuck
    (100, 1e-9, False),  # mostly accepted (an accumulation of events): the pace test's
    (600, 1e-2, False),  # mostly rejected at a pace within the budget
])
def test_a_stuck_run_stops_after_a_short_window_of_tries(rejected, moved, stuck):
    w = budget.STUCK_WINDOW
    b = budget.WorkBudget(1_000_000, 1.0)
    assert w < b.window
    assert _window(b, 0.5, w, 0) is None  # the first window: 0.5 s in w steps
    got = _window(b, 0.5 + moved, 2 * w - rejected, rejected)
    assert (got is not None) is stuck
    if stuck:
        assert got[0] is Status.MAX_ITERS and "it is stuck" in got[1]
        assert f"last {w} tries, {rejected} of them rejected" in got[1]


def test_a_run_whose_stage_solves_fail_stops_within_two_short_windows(monkeypatch):
    # issue 29: a junction on springs, its Coulomb link slipping; with the stage Newton's
    # test of the junction's velocity not floored at the springs' round-off (as before
    # that fix) every stage solve fails from t = 0.35387: the run crept, was bridged
    # twice and spent 20 000 tries (15 000 rejected) before the pace test stopped it
    from _lock_scenes import junction_on_springs_slipping_on_coulomb

    from lumped.solvers.radau import stage

    monkeypatch.setattr(stage, "roundoff_worst", lambda du, U, J, scale, junction, rate,
                        f, tol, worst, h=1.0, after_impact=False: worst)
    sol = simulate(junction_on_springs_slipping_on_coulomb(), method="radau5", dt=0.025,
                   t_end=0.5, rtol=1e-10, atol=1e-13, compiled=False, throw=False)
    assert sol.status is Status.MAX_ITERS and "it is stuck" in sol.message
    tried = sol.stats["steps"] + sol.stats["rejected"]
    assert tried <= 2 * budget.STUCK_WINDOW + 100, sol.stats


@pytest.mark.parametrize("max_steps", [1_000_000, 1_500])
def test_the_compiled_loop_counts_every_try_against_the_budget(max_steps, monkeypatch):
    # the scene above with its stage solves failing inside the compiled loop (no
    # round-off test of the junction's velocity there, as before that fix): the loop
    # used to cap accepted steps only, so with max_steps = 5000 it spent 14 773 tries,
    # and the stuck test waited 19 160 tries for it to return; now it returns at a
    # window of tries and at the budget's last try
    from _lock_scenes import junction_on_springs_slipping_on_coulomb

    from lumped.solvers.eventdriven import fast
    from lumped.solvers.radau import stage

    monkeypatch.setattr(stage, "roundoff_worst", lambda du, U, J, scale, junction, rate,
                        f, tol, worst, h=1.0, after_impact=False: worst)
    monkeypatch.setattr(fast, "roundoff_test", lambda: 0)
    sol = simulate(junction_on_springs_slipping_on_coulomb(), method="radau5", dt=0.025,
                   t_end=0.5, rtol=1e-10, atol=1e-13, compiled=True, max_steps=max_steps,
                   throw=False)
    assert sol.stats["loop"] == "compiled" and sol.status is Status.MAX_ITERS
    stats = sol.stats
    own = stats["steps"] + stats["rejected"]
    assert stats["rejected"] > 2 * stats["steps"]  # (the failing stage solves)
    if max_steps > 5_000:
        assert "it is stuck" in sol.message and own <= 3 * budget.STUCK_WINDOW
    else:
        assert "max_steps = 1500 is spent" in sol.message
        assert own + stats.get("bridged_steps", 0) <= max_steps
