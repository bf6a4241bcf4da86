"""Sweeps of the adaptive ``radau5`` at a tolerance (``rtol``/``atol``, no ``dt``): rows
against ``simulate`` per scene, the interval summary against exact balances and a fine
fixed step, the ``[solver]`` table, the command line, and the argument checks."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from lumped import simulate
from lumped.cli import main
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.sweep import simulate_many
from lumped.sweep.summary import solution_record

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
RELEASE = EXAMPLES / "release-0.5.toml"
CHAIN = EXAMPLES / "bingham-chain-3.toml"


def _chain(values: dict) -> Scene:
    """Two masses, each link a linear spring and a Bingham dashpot; m2 released from
    ``x2``; the second spring's stiffness ``k2`` is swept."""
    lin, bing = get_law("linear_spring"), get_law("bingham")
    return Scene([Mass("m1", m=1.0), Mass("m2", m=0.5, x0=values.get("x2", 0.4))],
                 [Element("s1", lin.bind(k=40.0), "ground", "m1"),
                  Element("d1", bing.bind(gamma=0.5, tau=1.5), "ground", "m1"),
                  Element("s2", lin.bind(k=values["k2"]), "m1", "m2"),
                  Element("d2", bing.bind(gamma=1.0, tau=0.6), "m1", "m2")])


def test_rows_are_those_of_simulate_per_scene():
    ks = [15.0, 20.0, 30.0]
    res = simulate_many(_chain, {"k2": ks}, method="radau5", rtol=1e-6, t_end=3.0)
    assert res.backend == "serial" and res.ok
    table = res.table
    assert "dt" not in table.columns
    for i, k in enumerate(ks):
        scene = _chain({"k2": k})
        sol = simulate(scene, method="radau5", rtol=1e-6, t_end=3.0)
        row = table.iloc[i]
        assert row["method"] == "radau5" and row["status"] == "success"
        assert row["steps"] == sol.stats["steps"] < len(sol.t)  # accepted steps, not rows
        assert row["t_reached"] == 3.0
        for node in ("m1", "m2"):
            assert row[f"x_end.{node}"] == sol.x[node][-1]
            assert row[f"v_end.{node}"] == sol.v[node][-1]
        expected = {"k2": k} | solution_record(sol, scene, None)
        assert row.to_dict() == pytest.approx(expected, nan_ok=True)
    # every scene comes to rest inside the 3 s, after some sticking and slipping
    assert table["at_rest"].all() and (table["stick_slip_cycles"] >= 1).all()
    assert (table["stick_time"] > 0.0).all() and (table["events"] >= 2).all()


def test_auto_with_a_tolerance_runs_radau5_per_scene_and_agrees_with_the_exact_motion():
    sets = {"nodes.mass.x0": [0.05, 0.3, 0.5]}
    adaptive = simulate_many(RELEASE, sets, rtol=1e-9, atol=1e-12, dt=None, t_end=2.0,
                             method="auto")
    # the file's dt (1e-4) is the output grid: rows on t_n = n dt (not the batched
    # closed form, which auto runs with dt alone)
    assert adaptive.backend == "serial"
    assert set(adaptive.table["method"]) == {"radau5"}
    exact = simulate_many(RELEASE, sets, method="exact", t_end=2.0)  # on the same grid
    a, b = adaptive.table, exact.table
    np.testing.assert_allclose(a["x_end.mass"], b["x_end.mass"], atol=1e-8)
    np.testing.assert_allclose(a["stick_time"], b["stick_time"], atol=2e-4)
    np.testing.assert_allclose(a["dissipated_energy"], b["dissipated_energy"], rtol=1e-4)
    assert list(a["stick_slip_cycles"]) == list(b["stick_slip_cycles"])
    assert list(a["at_rest"]) == list(b["at_rest"]) == [True, False, False]  # at 2 s
    np.testing.assert_allclose(a["v_end.mass"], b["v_end.mass"], atol=1e-8)


def test_step_points_summary_closes_the_energy_balance():
    # no forcing: what the dashpots dissipated is what the springs and masses lost,
    # k x^2 / 2 + m v^2 / 2 from the start to the end (exact for the exact motion)
    def scene(values):
        return Scene([Mass("mass", m=1.0, x0=values["x0"])],
                     [Element("spring", get_law("linear_spring").bind(k=100.0),
                              "ground", "mass"),
                      Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0),
                              "ground", "mass")])

    x0s = [0.05, 0.3, 0.5]
    res = simulate_many(scene, {"x0": x0s}, method="radau5", rtol=1e-8, t_end=4.0)
    t = res.table
    lost = 50.0 * (np.array(x0s) ** 2 - t["x_end.mass"] ** 2) - 0.5 * t["v_end.mass"] ** 2
    np.testing.assert_allclose(t["dissipated_energy"], lost, rtol=1e-6)
    # all come to rest (x0 = 0.5 at 3.145 s): the stick time on the step points is the
    # time after the last event, the stop
    assert t["at_rest"].all() and list(t["stick_slip_cycles"]) == [1, 1, 1]
    for i, x0 in enumerate(x0s):
        sol = simulate(scene({"x0": x0}), method="radau5", rtol=1e-8, t_end=4.0)
        stop = max(ev.t for ev in sol.events)
        assert t["stick_time"].iloc[i] == pytest.approx(4.0 - stop, abs=1e-12)


def test_the_template_s_tolerances_serve_radau5_only():
    data = tomllib.loads(CHAIN.read_text())
    data["solver"] |= {"t_end": 1.0}
    del data["solver"]["dt"]
    res = simulate_many(data, {"elements.s2.parameters.k": [15.0, 20.0]})
    row = res.table.iloc[1]
    from lumped.io import scene_from_dict

    sol = simulate(scene_from_dict(data)[0], method="radau5", rtol=1e-8, atol=1e-11,
                   t_end=1.0)  # the file's rtol, atol
    assert row["method"] == "radau5" and row["steps"] == sol.stats["steps"]
    assert row["x_end.m3"] == sol.x["m3"][-1]
    # a fixed-step method given here ignores the file's rtol/atol
    fixed = simulate_many(data, {"elements.s2.parameters.k": [20.0]}, method="bdf1",
                          dt=1e-3)
    assert fixed.table["method"].iloc[0] == "bdf1" and fixed.table["steps"].iloc[0] == 1000


def test_a_scene_that_fails_is_a_row():
    res = simulate_many(RELEASE, {"elements.dashpot.F0": [0.0, 5.0]}, method="radau5",
                        rtol=1e-6, t_end=0.5)
    assert list(res.table["status"]) == ["success", "inconsistent"]
    bad = res.table.iloc[1]
    assert "breaks its law" in bad["message"]
    assert bad["steps"] == 0 and bad["t_reached"] == 0.0 and bad["x_end.mass"] == 0.5


@pytest.mark.parametrize("kwargs, error, message", [
    ({"method": "bdf2", "dt": 1e-3, "rtol": 1e-6}, ValueError,
     r"`rtol` is a tolerance of the adaptive method 'radau5'; the fixed-step method "
     r"'bdf2' takes `dt`, got rtol=1e-06"),
    ({"method": "closed-bdf1", "dt": 1e-3, "atol": 1e-9}, ValueError,
     r"`atol` is a tolerance .* 'closed-bdf1' takes `dt`, got atol=1e-09"),
    ({"method": "bdf1"}, ValueError, r"`dt` is required for the fixed-step method 'bdf1'"),
    ({}, ValueError, r"give `dt` \(a fixed-step method\) or `rtol`/`atol`.*got neither"),
    ({"rtol": -1e-6}, ValueError, r"`rtol` must be positive, got -1e-06"),
    ({"rtol": 1e-6, "atol": float("nan")}, ValueError, r"`atol`"),
    ({"rtol": "1e-6"}, TypeError, r"`rtol`"),
    ({"rtol": 1e-6, "t_end": None}, ValueError, r"give `t_end`"),
])
def test_bad_steps_and_tolerances_are_refused_naming_them(kwargs, error, message):
    kwargs = {"t_end": 1.0} | kwargs
    with pytest.raises(error, match=message):
        simulate_many(_chain, {"k2": [20.0]}, **kwargs)


def test_a_fixed_step_sweep_still_needs_dt_from_somewhere():
    data = tomllib.loads(RELEASE.read_text())
    del data["solver"]["dt"]
    with pytest.raises(ValueError, match="got neither"):
        simulate_many(data, {"nodes.mass.x0": [0.1]})  # auto, no dt, no tolerance
    res = simulate_many(data, {"nodes.mass.x0": [0.1]}, rtol=1e-6)
    assert res.table["method"].iloc[0] == "radau5"


def test_command_line_rtol(tmp_path, capsys):
    out = tmp_path / "study"
    code = main(["sweep", str(RELEASE), "--grid", "nodes.mass.x0=0.1,0.5", "--out", str(out),
                 "--t-end", "1", "--rtol", "1e-6", "--atol", "1e-9"])
    assert code == 0
    assert "2 scenes (serial, radau5)" in capsys.readouterr().out
    table = pd.read_csv(out / "sweep.csv")
    assert list(table["method"]) == ["radau5", "radau5"]
    assert main(["sweep", str(RELEASE), "--grid", "nodes.mass.x0=0.1", "--out", str(out),
                 "--method", "bdf2", "--rtol", "1e-6"]) == 2
    assert "`rtol` is a tolerance" in capsys.readouterr().err
