"""The user's columns of ``lumped bench``: a run with new numbers beside the warm repeat.

No timing assertions (speed is measured by the benchmark, never by a test): the columns
exist, are finite and positive where measured, and ``nan`` where not.
"""

from __future__ import annotations

import argparse
import csv
import math

import pytest

from lumped import bench
from lumped.bench.network_scenes import bingham_chain
from lumped.cli import bench as cmd_bench

TINY = bench.Ladders(dts=(1e-2,), eps=(), rtols=(), tol_rtols=(1e-6,), min_time=0.0)
SCENE = next(s for s in bench.SCENES if s.name == "release-0.5")
NAMES = ("closed-bdf2", "radau5", "scipy-events-DOP853")
USERS_COLUMNS = ("cpu_new_s", "ratio_new", "new_over_warm", "cpu_new_first_s", "new_repeats")


@pytest.fixture(scope="module")
def report():
    methods = tuple(bench.BENCH_METHODS[n] for n in NAMES)
    return bench.run_benchmark(ladders=TINY, scenes=(SCENE,), methods=methods, creep=False,
                               events=False)


def test_compiled_methods_report_a_run_with_new_numbers(report):
    by = {r.method: r for r in report.runs}
    assert set(by) == set(NAMES) and all(r.ok for r in report.runs)
    r = by["radau5"]
    assert r.has_new_numbers and r.message == ""
    for value in (r.cpu_new_s, r.ratio_new, r.new_over_warm):
        assert math.isfinite(value) and value > 0.0
    assert r.ratio_new == pytest.approx(r.cpu_new_s / report.unit_s)
    assert r.new_over_warm == pytest.approx(r.cpu_new_s / r.cpu_s)
    # the smallest of as many runs with new numbers as the warm timing took calls
    assert 1 <= r.new_repeats <= min(r.repeats, bench.runner.NEW_REPEATS)
    assert r.cpu_new_s <= r.cpu_new_first_s
    for name in ("closed-bdf2", "scipy-events-DOP853"):  # nothing compiled per scene
        assert not by[name].has_new_numbers
        assert math.isnan(by[name].ratio_new) and math.isnan(by[name].new_over_warm)


def test_the_columns_reach_the_csv_and_the_tables(report, tmp_path):
    bench.write_outputs(report, tmp_path)
    header = (tmp_path / "runs.csv").read_text().splitlines()[0].split(",")
    assert set(USERS_COLUMNS) <= set(header)
    back = {r.method: r for r in bench.read_csv(tmp_path / "runs.csv")}
    assert back["radau5"].cpu_new_s == next(r for r in report.runs
                                            if r.method == "radau5").cpu_new_s
    assert math.isnan(back["closed-bdf2"].cpu_new_s)
    text = (tmp_path / "summary.md").read_text()
    assert "#### With new numbers (the user's columns)" in text
    assert "| release-0.5 | 0.001 | " in text
    table = bench.ratio_table(report, new_numbers=True)
    assert "radau5 / scipy-events-DOP853; new/warm" in table


def test_a_csv_without_the_columns_still_reads(report, tmp_path):
    """A runs.csv written before the user's columns reads, with them ``nan``."""
    bench.write_csv(report.runs, tmp_path / "runs.csv")
    with (tmp_path / "runs.csv").open(newline="") as fh:
        table = list(csv.reader(fh))
    keep = [i for i, name in enumerate(table[0]) if name not in USERS_COLUMNS]
    assert len(keep) == len(table[0]) - len(USERS_COLUMNS)
    with (tmp_path / "old.csv").open("w", newline="") as fh:
        csv.writer(fh).writerows([[row[i] for i in keep] for row in table])
    rows = bench.read_csv(tmp_path / "old.csv")
    assert len(rows) == len(report.runs) and all(not r.has_new_numbers for r in rows)
    assert all(r.new_repeats == 0 and math.isnan(r.cpu_new_first_s) for r in rows)


def test_new_numbers_differ_every_time_and_touch_only_k():
    factors = [bench.new_factor() for _ in range(3)]
    assert len(set(factors)) == 3 and all(1.0 < f < 1.001 for f in factors)
    fresh = bench.bench_scene_with_new_numbers(SCENE)
    assert fresh.osc.k != SCENE.osc.k and fresh.osc.k == pytest.approx(SCENE.osc.k, rel=1e-4)
    assert (fresh.osc.m, fresh.osc.gamma, fresh.osc.tau, fresh.x0, fresh.forcing) == (
        SCENE.osc.m, SCENE.osc.gamma, SCENE.osc.tau, SCENE.x0, SCENE.forcing)

    chain = bingham_chain(3)
    moved = bench.scene_with_new_numbers(chain, 1.5)
    assert moved is not chain and moved.node_names == chain.node_names
    for old, new in zip(chain.elements, moved.elements, strict=True):
        assert new.law is not old.law and (new.a, new.b) == (old.a, old.b)
        want = {p: v * 1.5 if p == "k" else v for p, v in old.law.params.items()}
        assert new.law.params == want
    assert moved.force_specs == chain.force_specs
    with pytest.raises(ValueError, match="no element of the scene has any of"):
        bench.scene_with_new_numbers(chain, parameters=("c",))


def test_compiled_fixed_step_entries_are_registered_but_run_only_when_named():
    for name in ("jit-bdf1", "jit-bdf2"):
        entry = bench.BENCH_METHODS[name]
        assert entry.kind == "step" and entry.ours and entry.warmup and entry.new_numbers
        assert not entry.default
        assert entry in bench.available_methods(every=True)
        assert entry not in bench.available_methods()
    assert bench.BENCH_METHODS["radau5"].new_numbers
    assert not bench.BENCH_METHODS["closed-bdf1"].new_numbers


def test_command_line_prints_the_users_table_and_knows_the_named_only_entries(
        tmp_path, capsys):
    parser = argparse.ArgumentParser()
    cmd_bench.add_arguments(parser)
    args = parser.parse_args(["--out", str(tmp_path), "--quick", "--scenes", "release-0.005",
                              "--methods", "radau5,scipy-events-LSODA", "--no-creep",
                              "--no-events"])
    assert cmd_bench.run(args) == 0
    assert "With new numbers" in capsys.readouterr().out
    rows = bench.read_csv(tmp_path / "runs.csv")
    assert all(r.cpu_new_s > 0.0 for r in rows if r.method == "radau5")
    with pytest.raises(ValueError, match="jit-bdf2"):  # the known names list it
        cmd_bench.run(parser.parse_args(["--out", str(tmp_path), "--methods", "nope"]))
