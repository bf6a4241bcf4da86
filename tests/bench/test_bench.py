"""Smoke tests of the work-precision machinery (no timing assertions)."""

from __future__ import annotations

import argparse
import csv
import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped import bench
from lumped.bench import runner as bench_runner
from lumped.cli import bench as cmd_bench
from lumped.plotting import have_matplotlib
from lumped.solvers.closed.closed_form import BinghamOscillator

TINY = bench.Ladders(dts=(1e-2, 1e-3), eps=(1e-6,), rtols=(1e-6,), max_nfev=100_000,
                     min_time=0.0, creep_t_end=2.0, event_dts=(1e-3, 5e-4, 2.5e-4))
SCENES = tuple(s for s in bench.SCENES if s.name in ("release-0.5", "forcing-F2"))
METHODS = tuple(m for m in bench.METHODS
                if m.name in ("closed-bdf1", "closed-bdf2", "scipy-LSODA"))


@pytest.fixture(scope="module")
def report():
    return bench.run_benchmark(ladders=TINY, scenes=SCENES, methods=METHODS, creep=True,
                               events=False)


def test_every_run_is_reported_and_errors_fall_with_dt(report):
    assert len(report.runs) == len(SCENES) * (2 * 2 + 1)
    assert all(r.ok for r in report.runs), [r.message for r in report.runs if not r.ok]
    for scene in SCENES:
        for name in ("closed-bdf1", "closed-bdf2"):
            rows = sorted((r for r in report.runs if r.scene == scene.name and r.method == name),
                          key=lambda r: -r.dt)
            assert rows[1].max_err < rows[0].max_err
            assert rows[1].steps == 10 * rows[0].steps
        lsoda = next(r for r in report.runs if r.scene == scene.name and r.method == "scipy-LSODA")
        assert lsoda.max_err < 1e-3 and lsoda.steps > 0 and lsoda.nfev >= lsoda.steps
    assert all(r.cpu_s >= 0.0 and r.ratio >= 0.0 for r in report.runs)


def test_outputs_exist(report, tmp_path):
    msgs = bench.write_outputs(report, tmp_path)
    rows = list(csv.DictReader((tmp_path / "runs.csv").open()))
    assert len(rows) == len(report.runs)
    text = (tmp_path / "summary.md").read_text()
    for scene in SCENES:
        assert f"#### {scene.name}" in text
    assert "Creep" in text and "Observed orders" in text
    png = tmp_path / "work_precision.png"
    if have_matplotlib():
        assert png.stat().st_size > 1000
        assert any("plot written" in m for m in msgs)
    else:  # the `test` extra does not pull matplotlib in: then a notice, and no file
        assert not png.exists()
        assert any("matplotlib is not installed" in m for m in msgs), msgs


def test_creep_exact_for_closed_forms_and_drifts_for_the_regularised_model(report):
    by = {(c["method"], c["setting"]): c for c in report.creep}
    assert by[("closed-bdf1", "dt=0.001")]["drift"] == 0.0
    assert by[("closed-bdf2", "dt=0.001")]["drift"] == 0.0
    assert by[("scipy-LSODA", "eps=1e-06 rtol=1e-10")]["drift"] > 0.0


def test_summary_picks_the_fastest_run_that_reaches_the_target(report):
    best = bench.summarize_runs(report.runs, targets=(1e-1, 1e-30))
    for scene in SCENES:
        for m in METHODS:
            assert best[(scene.name, 1e-30, m.name)] is None  # "unreachable"
            got = best[(scene.name, 1e-1, m.name)]
            reach = [r for r in report.runs if r.scene == scene.name and r.method == m.name
                     and r.max_err <= 1e-1]
            assert got is not None and got.cpu_s == min(r.cpu_s for r in reach)


def test_a_failed_scipy_run_is_a_reported_result():
    scene = SCENES[0]
    starved = bench.Ladders(dts=(), eps=(1e-9,), rtols=(1e-10,), max_nfev=20, min_time=0.0)
    radau = next(m for m in bench.METHODS if m.name == "scipy-Radau")
    x_ref = bench.reference_grid(scene)
    row = bench.run_one(scene, radau, bench_runner._settings(radau, scene, starved)[0], x_ref, 1.0,
                        starved)
    assert row.status == "failed" and "20 right-hand-side evaluations" in row.message
    assert math.isnan(row.max_err)


@given(v=st.floats(-1e300, 1e300), eps=st.floats(1e-300, 1.0))
def test_regularised_jacobian_never_overflows(v, eps):
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    J = bench.regularised_jacobian(osc, eps)(0.0, [0.0, v])
    d = J[1][1]
    assert math.isfinite(d) or (1.0 / eps) == math.inf
    assert d <= -1.0  # -(1/gamma + tau sech^2 / eps) / m


@given(v=st.floats(-0.1, 0.1), eps=st.sampled_from([1e-1, 1e-3, 1e-5]))
def test_regularised_jacobian_matches_finite_differences(v, eps):
    osc = BinghamOscillator(2.0, 100.0, 0.5, 3.0)
    rhs = bench.regularised_rhs(osc, lambda t: 0.0, eps)
    J = bench.regularised_jacobian(osc, eps)(0.0, [0.1, v])
    h = 1e-6 * eps
    fd_v = (rhs(0.0, [0.1, v + h])[1] - rhs(0.0, [0.1, v - h])[1]) / (2 * h)
    fd_x = (rhs(0.0, [0.1 + 1e-6, v])[1] - rhs(0.0, [0.1 - 1e-6, v])[1]) / 2e-6
    assert J[1][1] == pytest.approx(fd_v, rel=1e-5, abs=1e-6 / eps)
    assert J[1][0] == pytest.approx(fd_x, rel=1e-6)
    assert J[0] == [0.0, 1.0]


def test_score_refuses_a_dt_off_the_grid():
    solved = bench.Solved(np.arange(5) * 1.5e-3, np.zeros(5), 4, 4)
    with pytest.raises(ValueError, match="grid step"):
        bench_runner._score(solved, np.zeros(7), bench.GRID_DT)
    with pytest.raises(ValueError, match="divides"):
        bench.check_ladders(bench.Ladders(dts=(3e-4,), eps=(), rtols=()))
    bench.check_ladders(bench.FULL)
    bench.check_ladders(bench.QUICK)


def test_event_study_rows():
    rows = bench.event_study(("viscous-soft",), dts=(1e-3, 5e-4, 2.5e-4))
    labels = {r["window"] for r in rows}
    assert {"before 1st event", "after event 1 (stick)", "whole run", "end value"} <= labels
    assert all(r["order"] > 0.5 for r in rows)
    assert "| viscous-soft | closed-bdf2 |" in bench.event_markdown(rows)


def test_command_line(tmp_path, capsys):
    parser = argparse.ArgumentParser()
    cmd_bench.add_arguments(parser)
    args = parser.parse_args(["--out", str(tmp_path), "--quick", "--scenes", "release-0.005",
                              "--methods", "closed-bdf1,scipy-LSODA,scipy-events-LSODA",
                              "--no-creep", "--no-events"])
    assert cmd_bench.run(args) == 0
    assert (tmp_path / "runs.csv").exists() and (tmp_path / "summary.md").exists()
    assert "runs" in capsys.readouterr().out
    with pytest.raises(ValueError, match="unknown scene"):
        cmd_bench.run(parser.parse_args(["--out", str(tmp_path), "--scenes", "nope"]))


def test_closed_form_entries_time_the_python_engine_even_once_compiled_code_is_loaded(
        monkeypatch):
    """``engine="auto"`` would switch to the compiled loop once ``closed_form_jit`` is
    imported, so one table would mix the two engines: the entries pass ``engine``."""
    from lumped.solvers.closed import closed_form_jit

    def refuse(*args, **kwargs):
        raise AssertionError("the closed-form bench entry ran the compiled engine")

    monkeypatch.setattr(closed_form_jit, "compiled_columns", refuse)
    scene = next(s for s in bench.SCENES if s.name == "release-0.5")
    for name in ("closed-bdf1", "closed-bdf2"):
        entry = next(m for m in bench.METHODS if m.name == name)
        solved = entry.solve(scene, {"dt": 1e-2}, TINY)()
        assert solved.steps == round(scene.t_end / 1e-2)
        assert np.all(np.isfinite(solved.x))


def test_plot_legend_names_a_method_missing_from_the_first_panel(report, tmp_path,
                                                                monkeypatch):
    """Every method with a run anywhere is in the legend, in the report's order, even with
    no successful run on the first scene (the legend came from the first panel only)."""
    import dataclasses

    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    first = report.scenes[0]
    runs = [dataclasses.replace(r, status="failed") if (r.scene == first and
                                                        r.method == "scipy-LSODA") else r
            for r in report.runs]
    seen = {}
    legend = Figure.legend

    def spy(self, handles, labels, **kw):
        seen["labels"] = list(labels)
        return legend(self, handles, labels, **kw)

    monkeypatch.setattr(Figure, "legend", spy)
    bench.write_plot(dataclasses.replace(report, runs=runs), tmp_path / "wp.png")
    assert seen["labels"] == [m for m in report.methods
                              if any(r.method == m and r.ok for r in runs)]
    assert "scipy-LSODA" in seen["labels"]
