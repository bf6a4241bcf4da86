"""``lumped sweep``: table files, heat map, exit codes, usage errors."""

from __future__ import annotations

from pathlib import Path

import pandas as pd
import pytest

from lumped.cli import main

F2 = str(Path(__file__).resolve().parents[2] / "examples" / "forcing-F2.toml")


def test_sweep_writes_table_and_heatmap(tmp_path, capsys):
    out = tmp_path / "study"
    code = main(["sweep", F2, "--grid", "nodes.mass.force.amplitude=0:10:3",
                 "--grid", "nodes.mass.force.omega=5,15", "--out", str(out),
                 "--t-end", "2", "--dt", "1e-3", "--quantity", "stick_time"])
    assert code == 0
    text = capsys.readouterr().out
    assert "6 scenes (compiled, closed-bdf2)" in text
    table = pd.read_csv(out / "sweep.csv")
    assert table.shape[0] == 6
    assert list(table.columns[:2]) == ["nodes.mass.force.amplitude", "nodes.mass.force.omega"]
    assert (table["status"] == "success").all()
    # amplitude 0: the mass never moves
    assert (table.loc[table["nodes.mass.force.amplitude"] == 0.0, "stick_time"] == 2.0).all()
    pytest.importorskip("pyarrow")
    parquet = pd.read_parquet(out / "sweep.parquet")
    assert (parquet["message"] == "").all()
    numeric = table.select_dtypes("number").columns.drop("message")
    pd.testing.assert_frame_equal(parquet[numeric].astype(float), table[numeric].astype(float))
    ds = pytest.importorskip("xarray").open_dataset(out / "sweep.nc").load()
    assert ds["stick_time"].dims == ("nodes.mass.force.amplitude", "nodes.mass.force.omega")
    assert ds["stick_time"].values.ravel().tolist() == table["stick_time"].tolist()
    pytest.importorskip("matplotlib")
    assert (out / "stick_time.png").read_bytes()[:4] == b"\x89PNG"


def test_sweep_exit_code_1_when_a_scene_stops(tmp_path, capsys):
    code = main(["sweep", F2, "--grid", "elements.spring.parameters.k=100,1e300",
                 "--grid", "nodes.mass.x0=1e10", "--out", str(tmp_path), "--t-end", "0.1",
                 "--dt", "1e-3", "--quiet", "--quantity", "x_end"])
    assert code == 1
    table = pd.read_csv(tmp_path / "sweep.csv")
    assert list(table["status"]) == ["success", "non_finite"]
    assert capsys.readouterr().out == ""


@pytest.mark.parametrize("argv, message", [
    (["--grid", "nodes.mass.x0"], "`--grid` must look like"),
    (["--grid", "nodes.mass.x0=1,2", "--grid", "nodes.mass.x0=3"], "given twice"),
    (["--grid", "nodes.mass.x0=1,2", "--quantity", "colour"], "`quantity` must be one of"),
    (["--grid", "nodes.mass.mass=1,-1"], "'nodes.mass.mass' = -1.0"),
])
def test_sweep_usage_errors(tmp_path, capsys, argv, message):
    assert main(["sweep", F2, "--out", str(tmp_path), "--t-end", "0.1", *argv]) == 2
    assert message in capsys.readouterr().err
