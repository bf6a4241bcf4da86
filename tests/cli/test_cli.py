"""The ``lumped`` command line: ``lumped paper``."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from lumped.cli import main
from lumped.plotting import have_matplotlib
from lumped.scenarios import PAPER_SCENARIOS, run_scenario
from lumped.trajectory import summarize


def read_csv(path):
    header = path.read_text().splitlines()[0]
    return header, np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)


def test_paper_writes_every_scenario_at_full_precision(tmp_path, capsys):
    assert main(["paper", "--out", str(tmp_path), "--t-end", "0.5", "--dt", "1e-3"]) == 0
    out = capsys.readouterr().out
    for name in PAPER_SCENARIOS:
        header, data = read_csv(tmp_path / f"{name}.csv")
        assert header == "t,x,v,F_s,F_d"
        assert data.shape == (501, 5)
        traj = run_scenario(name, dt=1e-3, t_end=0.5)
        assert np.array_equal(data, traj.as_array())  # round-trip exact: no digits lost
        assert name in out
    assert "last stick at" in out and "stick time" in out


def test_paper_closed_bdf2_and_figures_when_matplotlib_is_there(tmp_path, capsys):
    assert main(["paper", "--out", str(tmp_path), "--t-end", "0.2", "--dt", "1e-3",
                 "--method", "closed-bdf2", "--scenario", "release-0.5"]) == 0
    png = tmp_path / "release-0.5.png"
    if have_matplotlib():
        assert png.read_bytes().startswith(b"\x89PNG") and png.stat().st_size > 1000
    else:  # the `test` extra does not pull matplotlib in: then the notice must show
        assert not png.exists()
        assert "matplotlib is not installed" in capsys.readouterr().out
    _, data = read_csv(tmp_path / "release-0.5.csv")
    assert np.array_equal(data, run_scenario("release-0.5", method="closed-bdf2", dt=1e-3,
                                             t_end=0.2).as_array())


def test_paper_without_matplotlib_prints_a_notice_and_writes_csvs(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # makes `import matplotlib` fail
    assert main(["paper", "--out", str(tmp_path), "--t-end", "0.01", "--dt", "1e-3"]) == 0
    out = capsys.readouterr().out
    assert "matplotlib is not installed" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == sorted(
        f"{n}.csv" for n in PAPER_SCENARIOS)


@pytest.mark.parametrize("argv,message", [
    (["--dt", "0"], "`--dt` must be positive, got 0.0"),
    (["--dt=-1e-3"], "`--dt` must be positive, got -0.001"),
    (["--dt", "nan"], "`--dt` must be finite, got nan"),
    (["--t-end", "inf"], "`--t-end` must be finite"),
    (["--method", "rk4"], "`--method` must be one of"),
    (["--scenario", "release-0.05"], "unknown scenario 'release-0.05'"),
])
def test_paper_usage_errors_exit_2_naming_the_argument(tmp_path, capsys, argv, message):
    assert main(["paper", "--out", str(tmp_path), *argv]) == 2
    assert message in capsys.readouterr().err
    assert not any(tmp_path.iterdir())


def test_console_script_is_installed_and_reports_errors(tmp_path):
    done = subprocess.run([sys.executable, "-m", "lumped", "paper", "--out", str(tmp_path),
                           "--dt", "-1"], capture_output=True, text=True)
    assert done.returncode == 2 and "`--dt` must be positive" in done.stderr
    done = subprocess.run([sys.executable, "-m", "lumped", "--version"], capture_output=True,
                          text=True)
    assert done.returncode == 0 and done.stdout.startswith("lumped ")


@pytest.mark.parametrize("method", ["bdf1", "bdf2", "auto", "exact"])
def test_paper_runs_every_method_on_the_same_grid(tmp_path, method):
    assert main(["paper", "--out", str(tmp_path), "--t-end", "0.3", "--dt", "1e-3",
                 "--method", method, "--scenario", "forcing-F2"]) == 0
    header, data = read_csv(tmp_path / "forcing-F2.csv")
    closed = run_scenario("forcing-F2", method="closed-bdf1", dt=1e-3, t_end=0.3)
    assert header == "t,x,v,F_s,F_d"
    assert np.array_equal(data[:, 0], closed.t)
    # every method approximates the same motion (max |x| about 0.09 by t = 0.3)
    assert np.abs(data[:, 1] - closed.x).max() < 0.05 * np.abs(closed.x).max()


def test_paper_generic_bdf1_matches_algorithm_1(tmp_path):
    assert main(["paper", "--out", str(tmp_path), "--t-end", "1.0", "--dt", "1e-3",
                 "--method", "bdf1", "--scenario", "release-0.5"]) == 0
    _, data = read_csv(tmp_path / "release-0.5.csv")
    closed = run_scenario("release-0.5", method="closed-bdf1", dt=1e-3, t_end=1.0)
    for j, col in enumerate(["x", "v", "F_s", "F_d"], start=1):
        ref = getattr(closed, col)
        assert np.abs(data[:, j] - ref).max() <= 1e-12 * np.abs(ref).max(), col


def test_run_and_compare_are_wired(tmp_path, capsys):
    from pathlib import Path

    examples = Path(__file__).resolve().parents[2] / "examples"
    out = tmp_path / "r.csv"
    assert main(["run", str(examples / "release-0.5.toml"), "--out", str(out), "--method",
                 "exact", "--t-end", "0.5"]) == 0
    assert out.read_text().splitlines()[0] == "t,x_mass,v_mass,F_spring,F_dashpot"
    assert main(["run", str(examples / "maxwell.toml"), "--out", str(out), "--method",
                 "exact"]) == 2
    assert "method 'exact' covers only one mass" in capsys.readouterr().err
    assert main(["compare", str(examples / "release-0.5.toml"), "--t-end", "0.2"]) == 0
    assert "ratio" in capsys.readouterr().out


def test_generic_bdf1_keeps_eq19_exactly_so_the_summary_matches(capsys):
    closed = run_scenario("forcing-F1", method="closed-bdf1", dt=1e-3, t_end=0.5)
    generic = run_scenario("forcing-F1", method="bdf1", dt=1e-3, t_end=0.5)
    assert np.array_equal(generic.as_array(), closed.as_array())
    s = summarize(generic)
    assert s.stick_time == pytest.approx(0.5) and s.last_stick_time is None


def test_every_subcommand_is_wired(capsys):
    for command in ("paper", "run", "compare", "bench"):
        assert main([command, "--help"]) == 0
        assert f"usage: lumped {command}" in capsys.readouterr().out
