"""Tables in compiled code (:data:`lumped.scene.forcing_jit.FORCE_LINEAR`): a force read
from a table and the inertial force of a ground motion read from a record evaluate in
compiled code, and with numpy (:func:`~lumped.scene.forcing_jit.loads_at`), to the Python
callable's numbers bit for bit, and ``radau5`` runs such
scenes in its compiled loop with the Python loop's numbers."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.codegen.jit import numba_enabled
from lumped.io import Table
from lumped.scene import GroundMotion, SineBurst
from lumped.scene.forcing_jit import (
    FORCE_LINEAR,
    FORCE_SINE,
    LINEAR_HEAD,
    forcing_arrays,
    forcing_into,
    linear_row,
    loads_at,
)
from lumped.scene.inertial import combine_forcing, inertial_forcing


def _table(seed: int, n: int, quantity: str, outside: str = "zero") -> Table:
    rng = np.random.default_rng(seed)
    t = np.cumsum(rng.uniform(0.01, 0.2, n)) - 0.05
    return Table(t, rng.normal(0.0, 3.0, n), quantity=quantity, outside=outside)


def _scene(forcing_table, ground: GroundMotion | None) -> Scene:
    forces = {"m": forcing_table} if forcing_table is not None else None
    return Scene([Mass("m", 2.0), Mass("n", 1.0)],
                 [Element("slider", get_law("coulomb").bind(tau=1.5, r=1e3), "ground", "m"),
                  Element("k", get_law("linear_spring").bind(k=40.0), "ground", "m"),
                  Element("link", get_law("linear_spring").bind(k=25.0), "m", "n"),
                  Element("d", get_law("bingham").bind(gamma=2.0, tau=0.5), "m", "n")],
                 forces, ground_motion=ground)


def _check_compiled_values(scene: Scene, times: list[float]) -> None:
    fkind, fpar, _ = forcing_arrays(scene, 1.0, 0, linear=True)
    assert (fkind == FORCE_LINEAR).any()
    f = np.zeros(len(scene.nodes))
    rows = []
    for t in times:
        assert forcing_into(0, t, fkind, fpar, fpar, f) == -1
        for i, fn in enumerate(scene.forcing):
            if fkind[i] == FORCE_LINEAR:
                assert f[i] == fn(t), (i, t)
        rows.append(f.copy())
    # and with numpy at all the times at once (the dense output's), the same doubles
    assert np.array_equal(loads_at(fkind, fpar, np.array(times), scene.forcing), rows)


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 40),
       outside=st.sampled_from(["zero", "hold"]),
       quantity=st.sampled_from(["acceleration", "velocity", "displacement"]))
def test_compiled_tables_give_the_python_numbers(seed, n, outside, quantity):
    force = _table(seed, n, "force", outside)
    ground = GroundMotion(**{quantity: _table(seed + 1, n, quantity, outside)})
    rng = np.random.default_rng(seed)
    knots = force.times.tolist() + ground.spec.times.tolist()
    lo, hi = min(knots) - 1.0, max(knots) + 1.0
    times = knots + rng.uniform(lo, hi, 200).tolist() + [lo, hi]
    _check_compiled_values(_scene(force, None), times)
    _check_compiled_values(_scene(None, ground), times)


@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 40),
       quantity=st.sampled_from(["acceleration", "velocity", "displacement"]),
       applied=st.sampled_from(["constant", "sine", "sine off"]))
def test_compiled_sums_of_a_load_and_a_record_give_the_python_numbers(seed, n, quantity,
                                                                       applied):
    # an applied force beside a ground record, and a force table beside a sine ground
    # acceleration: one row each, the Python sum's numbers
    rng = np.random.default_rng(seed)
    load = (float(rng.normal(0.0, 2.0)) if applied == "constant"
            else SineBurst(float(rng.normal(0.0, 2.0)), float(rng.uniform(0.5, 9.0)),
                           float(rng.uniform(0.0, 3.0)) if applied == "sine off"
                           else float("inf")))
    ground = GroundMotion(**{quantity: _table(seed + 1, n, quantity)})
    force = _table(seed, n, "force")
    knots = force.times.tolist() + ground.spec.times.tolist()
    lo, hi = min(knots) - 1.0, max(knots) + 1.0
    times = knots + rng.uniform(lo, hi, 200).tolist() + [lo, hi]
    if isinstance(load, SineBurst):
        times += [load.t_off] if np.isfinite(load.t_off) else []
        # (the sum a sine ground acceleration makes with a force table on a mass)
        _check_compiled_values(_scene(combine_forcing(force, load), None), times)
    _check_compiled_values(_scene(load, ground), times)


def test_only_interpolated_tables_are_encoded():
    assert linear_row(lambda t: t) is None
    row = linear_row(Table([0.0, 1.0, 3.0], [0.0, 2.0, -2.0], quantity="force"))
    assert row[:LINEAR_HEAD].tolist() == [3.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0]
    held = linear_row(dataclasses.replace(
        Table([0.0, 1.0, 3.0], [0.5, 2.0, -2.0], quantity="force"), outside="hold"))
    assert held[3:5].tolist() == [0.5, -2.0]
    # a sum is encoded when one part is a table and the other a constant or a sine burst
    record = GroundMotion(acceleration=_table(2, 6, "acceleration"))
    assert linear_row(combine_forcing(_table(3, 5, "force"), inertial_forcing(2.0, record)))\
        is None  # two tables
    assert linear_row(combine_forcing(lambda t: t, inertial_forcing(2.0, record))) is None
    row = linear_row(combine_forcing(SineBurst(2.0, 3.0, 1.5), inertial_forcing(2.0, record)))
    assert row[5:LINEAR_HEAD].tolist() == [float(FORCE_SINE), 2.0, 3.0, 1.5]
    # the fixed-step methods still sample a table on their grid
    fkind, _, ftab = forcing_arrays(_scene(_table(1, 5, "force"), None), 0.1, 10)
    assert fkind[0] != FORCE_LINEAR and ftab.shape == (11, 2)


@pytest.mark.skipif(not numba_enabled(), reason="needs numba")
@pytest.mark.parametrize("case", ["force table", "ground record", "load and record",
                                  "table beside a sine"])
def test_radau5_runs_tables_in_its_compiled_loop_with_the_python_numbers(case):
    ts = np.linspace(0.0, 2.0, 81)
    record = Table(ts, 4.0 * np.sin(5.0 * ts) * np.exp(-ts), quantity="acceleration")
    if case == "force table":
        scene = _scene(Table(ts, 6.0 * np.sin(3.0 * ts), quantity="force"), None)
    elif case == "ground record":
        scene = _scene(None, GroundMotion(acceleration=record))
    elif case == "load and record":  # a load beside the record: their sum
        scene = _scene(SineBurst(3.0, 4.0, 1.2), GroundMotion(acceleration=record))
    else:  # a table on one mass, a sine (the ground's inertial force) on the other: a
        # sine's row in a wider fpar (radau5 raised a ValueError here before)
        scene = _scene(Table(ts, 6.0 * np.sin(3.0 * ts), quantity="force"),
                       GroundMotion(acceleration=SineBurst(2.0, 5.0, 1.7)))
    kw = dict(method="radau5", t_end=2.5, rtol=1e-7)
    ref = simulate(scene, compiled=False, **kw)
    fast = simulate(scene, compiled=True, **kw)
    assert fast.stats["loop"] == "compiled"
    # the table's points are step ends; inside the record they are kinks (no events)
    # (within the step floor: a point an ulp from a sine's switch-off is one time)
    gaps = np.abs(ref.t[None, :] - ts[1:-1, None]).min(axis=1)
    assert gaps.max() <= 1e-14
    assert ref.stats["events"] < 80
    assert np.array_equal(fast.data, ref.data)
    assert fast.stats["steps"] == ref.stats["steps"] and fast.stats["nfev"] == ref.stats["nfev"]
