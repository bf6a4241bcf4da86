"""lumped.sweep.simulate_many: the batched compiled path against simulate() per scene,
failed scenes as rows, grids and lists, validation, files."""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.sweep import parameter_sets, parse_grid_spec, simulate_many

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
F2 = EXAMPLES / "forcing-F2.toml"
RELEASE = EXAMPLES / "release-0.5.toml"
GRID = {"nodes.mass.force.amplitude": [0.5, 3.0, 10.0],
        "elements.dashpot.parameters.tau": [0.5, 1.0]}
NUMBERS = ("x_end.mass", "v_end.mass", "stick_time", "dissipated_energy")
COUNTS = ("steps", "stick_slip_cycles", "events")


def assert_same_table(a: pd.DataFrame, b: pd.DataFrame, rel: float) -> None:
    assert list(a.columns) == list(b.columns)
    assert list(a["status"]) == list(b["status"])
    for col in COUNTS:
        assert list(a[col]) == list(b[col]), col
    for col in NUMBERS:
        np.testing.assert_allclose(a[col], b[col], rtol=rel, atol=rel, err_msg=col)
    assert list(a["at_rest"]) == list(b["at_rest"])


def test_compiled_batch_equals_simulate_per_scene():
    """The compiled batch and simulate(closed-bdf2) per scene give the same table."""
    fast = simulate_many(F2, GRID, t_end=2.0, dt=1e-3)
    slow = simulate_many(F2, GRID, t_end=2.0, dt=1e-3, keep_trajectories=True)
    assert fast.backend == "compiled" and slow.backend == "serial"
    assert_same_table(fast.table, slow.table, rel=1e-13)
    assert (fast.table["x_end.mass"] == slow.table["x_end.mass"]).all()  # same steps
    # something happens in this grid: sticks, slips, reversals
    assert fast.table["stick_slip_cycles"].max() >= 2
    assert len(slow.trajectories) == 6 and slow.trajectories[3].method == "closed-bdf2"


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_closed_form_agrees_with_the_generic_newton_solver(method):
    closed = simulate_many(F2, GRID, t_end=2.0, dt=1e-3, method=f"closed-{method}")
    generic = simulate_many(F2, GRID, t_end=2.0, dt=1e-3, method=method)
    assert generic.backend == "serial"
    assert_same_table(closed.table.drop(columns="method"),
                      generic.table.drop(columns="method"), rel=1e-9)


def test_grid_layout_and_dataset():
    res = simulate_many(F2, GRID, t_end=1.0, dt=1e-3)
    names = list(GRID)
    assert list(res.table.columns[:2]) == names
    # row-major: the last path varies fastest
    assert list(res.table[names[1]]) == [0.5, 1.0] * 3
    ds = res.to_xarray()
    assert ds["x_end.mass"].dims == tuple(names)
    assert ds["x_end.mass"].shape == (3, 2)
    assert ds["x_end.mass"].sel({names[0]: 10.0, names[1]: 1.0}).item() == \
        res.table["x_end.mass"].iloc[5]
    assert res.ok


def test_zero_forcing_template_and_list_of_sets():
    sets = [{"nodes.mass.x0": x0, "nodes.mass.force": f} for x0, f in
            [(0.5, 0.0), (0.5, 2.0), (0.001, 0.0), (-0.3, -5.0)]]
    res = simulate_many(RELEASE, sets, t_end=2.0, dt=1e-3)
    assert res.backend == "compiled" and res.grid is None
    ref = simulate_many(RELEASE, sets, t_end=2.0, dt=1e-3, keep_trajectories=True)
    assert_same_table(res.table, ref.table, rel=1e-13)
    # x0 = 0.001 is inside the stick band |k x0| <= tau: never moves
    row = res.table.iloc[2]
    assert row["stick_time"] == 2.0 and row["rest_position.mass"] == 0.001
    assert res.to_xarray()["x_end.mass"].dims == ("scene",)


def test_failed_scenes_are_rows_never_nan():
    # the state overflows for k = 1e300: non_finite, values of the last good step
    res = simulate_many(RELEASE, {"elements.spring.parameters.k": [100.0, 1e300],
                                  "nodes.mass.x0": [1e10]}, t_end=0.5, dt=1e-3)
    good, bad = res.table.iloc[0], res.table.iloc[1]
    assert good["status"] == "success" and bad["status"] == "non_finite"
    assert "non-finite" in bad["message"] and bad["steps"] < 500
    assert not bad["at_rest"] and pd.isna(bad["rest_position.mass"])
    numeric = res.table.select_dtypes("number").drop(columns="rest_position.mass")
    assert np.isfinite(numeric.to_numpy(float)).all()
    assert not res.ok
    # per scene: an initial force that breaks the law is an "inconsistent" row
    res = simulate_many(RELEASE, {"elements.dashpot.F0": [0.0, 5.0]}, t_end=0.5, dt=1e-3)
    assert list(res.table["status"]) == ["success", "inconsistent"]
    assert "breaks its law" in res.table["message"].iloc[1]
    assert res.table["x_end.mass"].iloc[1] == 0.5  # the initial state


def test_bad_parameters_are_refused_naming_them():
    with pytest.raises(ValueError, match=r"'elements.dashpot.parameters.tau' = -1.0"):
        simulate_many(F2, {"elements.dashpot.parameters.tau": [1.0, -1.0]}, t_end=1.0)
    with pytest.raises(ValueError, match="no table 'nodes.nomass'"):
        simulate_many(F2, {"nodes.nomass.x0": [1.0]}, t_end=1.0)
    with pytest.raises(ValueError, match="empty grid"):
        simulate_many(F2, {}, t_end=1.0)
    with pytest.raises(ValueError, match="`dt` must be positive"):
        simulate_many(F2, {"nodes.mass.x0": [0.0]}, dt=-1.0)
    with pytest.raises(ValueError, match="`method` must be one of"):
        simulate_many(F2, {"nodes.mass.x0": [0.0]}, method="rk4")
    with pytest.raises(ValueError, match="`backend` must be one of"):
        simulate_many(F2, {"nodes.mass.x0": [0.0]}, backend="mpi")
    with pytest.raises(ValueError, match="no-such.toml: no such scene file"):
        simulate_many(EXAMPLES / "no-such.toml", {"nodes.mass.x0": [0.0]})
    with pytest.raises(ValueError, match="'steps' is also a result column"):
        simulate_many(_builder, {"steps": [1, 2]}, dt=1e-3, t_end=0.1)
    with pytest.raises(TypeError, match="`template` must be"):
        simulate_many(42, {"nodes.mass.x0": [0.0]})
    with pytest.raises(ValueError, match=r"parameter set 1 .*mass.*must be positive"):
        simulate_many(F2, [{"nodes.mass.mass": 1.0}, {"nodes.mass.mass": -2.0}], method="bdf1")


def _builder(values: dict) -> Scene:
    """A template as code: the paper's oscillator with a given mass and stiffness."""
    return Scene([Mass("mass", m=values["m"], x0=0.5)],
                 [Element("spring", get_law("linear_spring").bind(k=values["k"]),
                          "ground", "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0),
                          "ground", "mass")])


def test_builder_template_matches_the_file_template():
    grid = {"m": [0.5, 2.0], "k": [50.0, 100.0]}
    built = simulate_many(_builder, grid, dt=1e-3, t_end=1.0)
    file_grid = {"nodes.mass.mass": grid["m"], "elements.spring.parameters.k": grid["k"]}
    filed = simulate_many(RELEASE, file_grid, dt=1e-3, t_end=1.0)
    assert_same_table(built.table.iloc[:, 2:].rename(columns=str),
                      filed.table.iloc[:, 2:], rel=1e-13)


def test_process_pool_gives_the_serial_table():
    sets = [{"nodes.mass.x0": x} for x in np.linspace(-0.5, 0.5, 8)]
    serial = simulate_many(RELEASE, sets, method="bdf1", dt=2e-3, t_end=0.5, n_jobs=1)
    pooled = simulate_many(RELEASE, sets, method="bdf1", dt=2e-3, t_end=0.5, n_jobs=2)
    assert serial.backend == "serial" and pooled.backend == "processes"
    pd.testing.assert_frame_equal(serial.table, pooled.table)


def test_progress_bar_only_on_request(capsys):
    simulate_many(F2, GRID, t_end=0.2, dt=1e-3)
    assert capsys.readouterr().err == ""
    simulate_many(F2, GRID, t_end=0.2, dt=1e-3, progress=True)
    assert "6/6" in capsys.readouterr().err


def test_write_and_heatmap(tmp_path):
    res = simulate_many(F2, {"nodes.mass.force.amplitude": [3.0, 10.0],
                             "elements.dashpot.parameters.tau": [0.5, 1.0]},
                        t_end=2.0, dt=1e-3)
    paths = res.write(tmp_path)
    back = pd.read_csv(paths[0])
    assert back["x_end.mass"].tolist() == res.table["x_end.mass"].tolist()  # %.17g
    assert back["rest_position.mass"].isna().tolist() == \
        res.table["rest_position.mass"].isna().tolist()
    pytest.importorskip("pyarrow")
    parquet = next(p for p in paths if p.suffix == ".parquet")
    pd.testing.assert_frame_equal(pd.read_parquet(parquet), res.table)
    pytest.importorskip("matplotlib")
    png = res.heatmap("rest_position", tmp_path / "map.png")
    assert png.read_bytes()[:4] == b"\x89PNG"
    with pytest.raises(ValueError, match="`quantity` must be one of"):
        res.column_for("nonsense")


def test_parameter_sets_and_grid_specs():
    sets = parameter_sets({"a.b": [1, 2], "c.d": np.array([0.5, 1.5, 2.5])})
    assert len(sets) == 6 and sets.rows[1] == (1, 1.5)
    assert parse_grid_spec("nodes.mass.force.amplitude=0:20:5") == \
        ("nodes.mass.force.amplitude", [0.0, 5.0, 10.0, 15.0, 20.0])
    assert parse_grid_spec("a.b=1,2.5") == ("a.b", [1.0, 2.5])
    for bad in ("a.b", "a.b=1:2", "a.b=1:2:0", "a.b=x", "=1", "a..b=1", "a.b=nan"):
        with pytest.raises(ValueError):
            parse_grid_spec(bad)
    with pytest.raises(TypeError, match="`parameters`"):
        parameter_sets("nodes.mass.x0")
    with pytest.raises(ValueError, match=r"`parameters\[1\]`"):
        parameter_sets([{"a.b": 1}, {"c.d": 2}])


def test_dict_template_is_not_modified():
    data = tomllib.loads(F2.read_text())
    before = repr(data)
    simulate_many(data, {"nodes.mass.force.omega": [1.0, math.pi]}, dt=1e-3, t_end=0.5,
                  method="bdf1")
    assert repr(data) == before


_positive = st.floats(0.2, 5.0)
_scene_values = st.fixed_dictionaries({
    "nodes.mass.mass": _positive,
    "nodes.mass.x0": st.floats(-0.2, 0.2),
    "nodes.mass.v0": st.floats(-2.0, 2.0),
    "elements.spring.parameters.k": st.floats(1.0, 400.0),
    "elements.dashpot.parameters.gamma": st.floats(0.05, 1e6),
    "elements.dashpot.parameters.tau": st.floats(0.0, 3.0),
    "nodes.mass.force.amplitude": st.floats(-15.0, 15.0),
    "nodes.mass.force.omega": st.floats(0.5, 60.0),
    "nodes.mass.force.t_off": st.floats(0.0, 0.5),
})


@settings(max_examples=100)  # two sweeps per example (~40 ms): 100 keep CI under 5 s
@given(sets=st.lists(_scene_values, min_size=1, max_size=3),
       method=st.sampled_from(["closed-bdf1", "closed-bdf2"]))
def test_property_batch_rows_equal_simulate_rows(sets, method):
    """Any parameter sets: the compiled batch's row is simulate()'s row (same steps)."""
    fast = simulate_many(F2, sets, method=method, dt=5e-3, t_end=0.5)
    slow = simulate_many(F2, sets, method=method, dt=5e-3, t_end=0.5, keep_trajectories=True)
    assert fast.backend == "compiled"
    for col in ("x_end.mass", "v_end.mass", "stick_time", "at_rest", "status", *COUNTS):
        assert list(fast.table[col]) == list(slow.table[col]), col
    np.testing.assert_allclose(fast.table["dissipated_energy"], slow.table["dissipated_energy"],
                               rtol=1e-12, atol=0.0)
    assert (fast.table["dissipated_energy"] >= 0.0).all()


def test_netcdf_round_trip_keeps_every_value_and_string(tmp_path):
    """The NetCDF3 file (xarray's scipy engine) reads back to the same Dataset: the grid's
    axes, floats bit for bit, counters, booleans, and the status and message strings of a
    failed scene (a list of parameter sets gives the ``scene`` dimension)."""
    xr = pytest.importorskip("xarray")
    grid = simulate_many(F2, {"nodes.mass.force.amplitude": [3.0, 10.0],
                              "elements.dashpot.parameters.tau": [0.5, 1.0, 80.0]},
                         t_end=1.0, dt=1e-3)
    sets = simulate_many(RELEASE, [{"elements.dashpot.F0": 0.0}, {"elements.dashpot.F0": 5.0}],
                         t_end=0.5, dt=1e-3)
    assert list(sets.table["status"]) == ["success", "inconsistent"]
    for res, dims in ((grid, ("nodes.mass.force.amplitude", "elements.dashpot.parameters.tau")),
                      (sets, ("scene",))):
        paths = res.write(tmp_path / dims[0], stem="t")
        nc = next(p for p in paths if p.suffix == ".nc")
        with xr.open_dataset(nc) as back:
            back = back.load()
        ds = res.to_xarray()
        assert tuple(back["status"].dims) == dims
        assert back.attrs["parameters"] == ", ".join(res.parameters)
        assert set(back.variables) == set(ds.variables)
        for name in ds.variables:
            a, b = ds[name].values, back[name].values
            if a.dtype.kind in "fiub":
                assert b.dtype.kind == a.dtype.kind, name
                np.testing.assert_array_equal(a, b, err_msg=name)  # NaN == NaN here
            else:
                assert a.tolist() == b.tolist(), name
    assert "breaks its law" in str(back["message"].values[1])


def test_jit_sweep_workers_are_replaced(monkeypatch):
    # each new parameter set of a jit-* method compiles a numba module that its process
    # keeps for good (6 MB): the pool replaces a worker after JIT_TASKS_PER_WORKER points
    import lumped.sweep.per_scene as run

    seen = []

    class Recording(run.ProcessPoolExecutor):
        def __init__(self, *args, **kwargs):
            seen.append(kwargs.get("max_tasks_per_child"))
            super().__init__(*args, **kwargs)

    monkeypatch.setattr(run, "ProcessPoolExecutor", Recording)
    monkeypatch.setattr(run, "JIT_TASKS_PER_WORKER", 1)  # a new worker for every point
    sets = [{"nodes.mass.x0": x} for x in (-0.3, 0.1, 0.4)]
    serial = simulate_many(RELEASE, sets, method="jit-bdf1", dt=2e-3, t_end=0.5, n_jobs=1)
    pooled = simulate_many(RELEASE, sets, method="jit-bdf1", dt=2e-3, t_end=0.5, n_jobs=2)
    plain = simulate_many(RELEASE, sets, method="bdf1", dt=2e-3, t_end=0.5, n_jobs=2)
    assert seen == [1, None]  # the Python reference keeps its workers
    assert pooled.backend == "processes"
    pd.testing.assert_frame_equal(serial.table, pooled.table)
    assert list(plain.table["status"]) == ["success"] * 3


def _chain(values: dict) -> Scene:
    """Two masses in a chain: ground -[spring k1 | bingham]- m1 -[spring k2]- m2."""
    return Scene([Mass("m1", m=1.0, x0=0.0), Mass("m2", m=0.5, x0=values["x2"])],
                 [Element("s1", get_law("linear_spring").bind(k=40.0), "ground", "m1"),
                  Element("d1", get_law("bingham").bind(gamma=0.5, tau=1.0), "ground", "m1"),
                  Element("s2", get_law("linear_spring").bind(k=20.0), "m1", "m2"),
                  Element("d2", get_law("bingham").bind(gamma=1.0, tau=0.3), "m1", "m2")])


def test_multi_node_rows_read_each_node_s_columns():
    # the columns are t, x_m1, v_m1, x_m2, v_m2, F_...: a row reads each node's own pair
    res = simulate_many(_chain, {"x2": [0.2, 0.6]}, method="bdf1", dt=1e-3, t_end=0.3,
                        keep_trajectories=True)
    for (_, row), sol in zip(res.table.iterrows(), res.trajectories, strict=True):
        for node in ("m1", "m2"):
            assert row[f"x_end.{node}"] == sol.x[node][-1]
            assert row[f"v_end.{node}"] == sol.v[node][-1]
        work = sum(float(np.sum(1e-3 * (sol.F[d] * (sol.v[b] - a_v))[1:]))
                   for d, b, a_v in (("d1", "m1", 0.0), ("d2", "m2", sol.v["m1"])))
        assert row["dissipated_energy"] == pytest.approx(work, rel=1e-12)
        assert row["dissipated_energy"] > 0.0
