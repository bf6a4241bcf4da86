"""The event-driven scipy peer and the tolerance-driven bench entries (issue 8, point 7).

Correctness, not speed: the peer must agree with the exact reference to its tolerance.
"""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from lumped import bench
from lumped.bench import runner as bench_runner
from lumped.solvers import registry
from lumped.solvers.registry import METHOD_REGISTRY, RunSettings, register_method
from lumped.solvers.status import RawRun

SCENES = {s.name: s for s in bench.SCENES}
SLIPPING = ("forcing-F2", "release-0.5", "stick-breakout")
RESTING = ("forcing-F1", "release-0.005")


@pytest.fixture(scope="module")
def references():
    return {name: bench.reference_grid(SCENES[name]) for name in SLIPPING + RESTING}


def _error(scene, method, rtol, x_ref, **kw):
    solved = bench.event_driven_solver(scene, method, rtol, rtol * scene.length_scale,
                                       200_000, scene.t_end, **kw)()
    assert np.array_equal(solved.t, np.arange(len(x_ref)) * bench.GRID_DT)
    return float(np.max(np.abs(solved.x - x_ref))), solved


@pytest.mark.parametrize("method", ["DOP853", "LSODA"])
@pytest.mark.parametrize("name", SLIPPING)
def test_agrees_with_the_exact_reference_to_its_tolerance(name, method, references):
    scene = SCENES[name]
    errs = {}
    for rtol in (1e-6, 1e-10):
        errs[rtol], solved = _error(scene, method, rtol, references[name])
        assert errs[rtol] <= 100.0 * rtol * scene.length_scale, (rtol, errs[rtol])
        assert solved.steps > 0 and solved.nfev >= solved.steps
    assert errs[1e-10] < 1e-2 * errs[1e-6]


@pytest.mark.parametrize("method", ["DOP853", "LSODA"])
@pytest.mark.parametrize("name", RESTING)
def test_a_stuck_mass_stays_exactly_put(name, method, references):
    err, solved = _error(SCENES[name], method, 1e-6, references[name])
    assert err == 0.0
    assert np.all(solved.x == SCENES[name].x0)


@pytest.mark.parametrize("name", SLIPPING)
def test_events_match_the_reference(name):
    """Every stick, reversal and break-out of the exact solution, in order, at its time."""
    from lumped.reference import exact_solution

    scene = SCENES[name]
    exact = exact_solution(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.forcing,
                           t_eval=[0.0, scene.t_end])
    want = [(e.t, e.kind) for e in exact.events if e.kind != "forcing-off"]
    log: list[tuple[float, str]] = []
    bench.event_driven_solver(scene, "DOP853", 1e-12, 1e-12 * scene.length_scale, 200_000,
                              scene.t_end, log=log)()
    assert [k for _, k in log] == [k for _, k in want]
    assert len(want) >= 2
    np.testing.assert_allclose([t for t, _ in log], [t for t, _ in want], rtol=0, atol=1e-9)
    with pytest.raises(RuntimeError, match=f"more than {len(want) - 1} events"):
        bench.event_driven_solver(scene, "DOP853", 1e-12, 1e-12 * scene.length_scale,
                                  200_000, scene.t_end, max_events=len(want) - 1)()


def test_budget_exhaustion_is_a_reported_failure():
    scene = SCENES["release-0.5"]
    peer = bench.BENCH_METHODS["scipy-events-DOP853"]
    starved = bench.Ladders(dts=(), eps=(), rtols=(), tol_rtols=(1e-10,), max_nfev=50,
                            min_time=0.0)
    (setting,) = bench_runner._settings(peer, scene, starved)
    assert setting == {"rtol": 1e-10, "atol": 1e-10 * scene.length_scale}
    row = bench.run_one(scene, peer, setting, bench.reference_grid(scene), 1.0, starved)
    assert row.status == "failed" and "50 right-hand-side evaluations" in row.message
    assert row.setting == "rtol=1e-10" and math.isnan(row.max_err)


def test_registry_holds_the_event_peers_and_refuses_bad_entries():
    names = [m.name for m in bench.available_methods()]
    for peer in ("scipy-events-DOP853", "scipy-events-LSODA"):
        assert peer in names and not bench.BENCH_METHODS[peer].ours
    with pytest.raises(TypeError, match="`method`"):
        bench.register_bench_method("closed-bdf1")
    with pytest.raises(ValueError, match="`method.kind`"):
        bench.register_bench_method(bench.Method("x", "adaptive", lambda *a: None))
    assert bench.TARGETS[-1] == 1e-11


# ---------------------------------------------------------------------------------------
# a simulate method driven by rtol/atol as one bench entry


@pytest.fixture
def fake_methods():
    """Two fake tolerance-driven `simulate` methods: one on the 1e-3 grid (the exact
    reference there, whatever the tolerance), one on a coarser grid without dense output."""
    saved = (dict(METHOD_REGISTRY), set(registry.FIXED_STEP_METHODS), registry.METHODS)
    seen = []

    def on_grid(scene, settings: RunSettings) -> RawRun:
        seen.append((settings.rtol, settings.atol))
        fixed = RunSettings(t_end=settings.t_end, dt=bench.GRID_DT)
        return METHOD_REGISTRY["exact"](scene, fixed)

    def off_grid(scene, settings: RunSettings) -> RawRun:
        return METHOD_REGISTRY["closed-bdf2"](scene, RunSettings(t_end=settings.t_end, dt=2e-3))

    register_method("fake-tol", on_grid)
    register_method("fake-coarse", off_grid)
    yield seen
    METHOD_REGISTRY.clear()
    METHOD_REGISTRY.update(saved[0])
    registry.FIXED_STEP_METHODS.clear()
    registry.FIXED_STEP_METHODS.update(saved[1])
    registry.METHODS = saved[2]


def test_tolerance_method_runs_a_simulate_method_over_its_ladder(fake_methods):
    scene = SCENES["release-0.5"]
    entry = bench.tolerance_method("ours-fake", "fake-tol", rtols=(1e-4, 1e-8))
    assert entry.kind == "tol" and entry.ours and entry.warmup
    ladders = bench.Ladders(dts=(), eps=(), rtols=(), min_time=0.0)
    report = bench.run_benchmark(ladders=ladders, scenes=(scene,), methods=(entry,),
                                 creep=False, events=False)
    assert [r.setting for r in report.runs] == ["rtol=0.0001", "rtol=1e-08"]
    assert all(r.ok and r.max_err < 1e-12 for r in report.runs)
    L = scene.length_scale
    assert (1e-4, 1e-4 * L) in fake_methods and (1e-8, 1e-8 * L) in fake_methods
    assert report.ours == ("ours-fake",)


def test_tolerance_method_refuses_to_invent_a_dense_output(fake_methods):
    scene = SCENES["release-0.5"]
    entry = bench.tolerance_method("coarse", "fake-coarse", rtols=(1e-6,))
    (setting,) = bench_runner._settings(entry, scene, bench.QUICK)
    row = bench.run_one(scene, entry, setting, bench.reference_grid(scene), 1.0, bench.QUICK)
    assert row.status == "failed" and "no dense output" in row.message


def test_x_on_grid_uses_the_dense_output_when_there_is_one():
    t = np.linspace(0.0, 1.0, 11)
    cols = ("t", "x_mass", "v_mass", "F_spring")
    sol = SimpleNamespace(columns=cols, method="m", t=np.array([0.0, 1.0]),
                          sol=lambda tt: np.column_stack([tt, tt**2, 2 * tt, -tt]))
    np.testing.assert_array_equal(bench.x_on_grid(sol, t), t**2)
    bad = SimpleNamespace(columns=cols, method="m", sol=lambda tt: tt)
    with pytest.raises(ValueError, match="shape"):
        bench.x_on_grid(bad, t)


def test_ratio_table_compares_our_best_with_the_fastest_peer():
    def row(method, cpu, err):
        return bench.RunResult("s", method, "x", math.nan, math.nan, 1e-6, 1e-6, "ok", "",
                               err, err, 1, 1, cpu, cpu, 1)

    runs = [row("ours-a", 2.0, 1e-4), row("ours-b", 1.0, 1e-4), row("ours-b", 8.0, 1e-8),
            row("peer-a", 4.0, 1e-4), row("peer-b", 0.5, 1e-8), row("peer-b", 9.0, 1e-12)]
    report = bench.BenchReport(runs=runs, creep=[], events=[], unit_s=1.0, reference_s={},
                               methods=("ours-a", "ours-b", "peer-a", "peer-b"),
                               scenes=("s",), ours=("ours-a", "ours-b"))
    text = bench.ratio_table(report, targets=(1e-3, 1e-7, 1e-11, 1e-14))
    cells = text.splitlines()[2].split(" | ")
    assert cells[1] == "2 (ours-b / peer-b)"  # 1.0 / 0.5: peer-b's 1e-8 run reaches 1e-3 too
    assert cells[2] == "16 (ours-b / peer-b)"
    assert cells[3] == "ours unreachable" and cells[4].startswith("-")
