"""Amplitude-frequency sweeps (issue 28): the steady amplitude of a linear oscillator on a
shaken base against its closed form, serially, on Dask and from the command line."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from lumped.sweep import simulate_many

TEMPLATE = {
    "solver": {"method": "bdf2", "dt": 2e-3, "t_end": 12.0},
    "nodes": {"m": {"mass": 1.0}},
    "elements": {
        "spring": {"law": "linear_spring", "between": ["ground", "m"],
                   "parameters": {"k": 100.0}},
        "damper": {"law": "bingham", "between": ["ground", "m"],
                   "parameters": {"gamma": 0.5, "tau": 0.0}},
    },
    "ground": {"motion": {"kind": "sine", "amplitude": 1.0, "omega": 5.0}},
}
OMEGAS = [4.0, 8.0, 10.0, 14.0]


def _exact(w):  # |X| of x'' + 2 x' + 100 x = -sin(w t)
    return 1.0 / np.abs(100.0 - w ** 2 + 2j * w)


@pytest.mark.parametrize("target", ["m", "spring+damper"])
def test_steady_amplitude_against_the_closed_form(target):
    res = simulate_many(TEMPLATE, {"ground.motion.omega": OMEGAS}, steady_amplitude=target)
    table = res.table
    assert res.backend == "serial" and res.ok
    np.testing.assert_allclose(table["steady_omega"].astype(float), OMEGAS)
    amp = table["steady_amplitude"].astype(float).to_numpy()
    np.testing.assert_allclose(amp, _exact(np.array(OMEGAS)), rtol=5e-3)  # bdf2, a transient e^-t
    assert (table["steady_cycles"] >= 3).all()
    if target != "m":  # pi c w X^2 per cycle for the dashpot c = 2 (with the spring: 0)
        np.testing.assert_allclose(table["energy_per_cycle"].astype(float),
                                   np.pi * 2.0 * np.array(OMEGAS) * amp ** 2, rtol=5e-3)


def test_a_scene_without_one_sine_frequency_says_so():
    template = {k: v for k, v in TEMPLATE.items() if k != "ground"}
    res = simulate_many(template, {"nodes.m.x0": [0.1]}, steady_amplitude="m")
    row = res.table.iloc[0]
    assert row["steady_cycles"] == 0 and pd.isna(row["steady_amplitude"])
    assert "exactly one sine frequency" in row["message"]


def test_on_dask_as_in_process():
    distributed = pytest.importorskip("dask.distributed")
    grid = {"ground.motion.omega": OMEGAS[:2]}
    local = simulate_many(TEMPLATE, grid, steady_amplitude="m")
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as client:
        remote = simulate_many(TEMPLATE, grid, steady_amplitude="m", client=client)
    assert remote.backend == "dask/per-scene"
    pd.testing.assert_frame_equal(local.table, remote.table)


def test_the_command_plots_the_amplitude_frequency_curve(tmp_path):
    pytest.importorskip("matplotlib")
    from lumped.cli import main

    scene = tmp_path / "base.toml"
    scene.write_text("""
[solver]
method = "bdf2"
dt = 2e-3
t_end = 12.0
[nodes.m]
mass = 1.0
[elements.spring]
law = "linear_spring"
between = ["ground", "m"]
parameters = { k = 100.0 }
[elements.damper]
law = "bingham"
between = ["ground", "m"]
parameters = { gamma = 0.5, tau = 0.0 }
[ground]
motion = { kind = "sine", amplitude = 1.0, omega = 5.0 }
""")
    code = main(["sweep", str(scene), "--grid", "ground.motion.omega=6,10",
                 "--steady-amplitude", "m", "--out", str(tmp_path / "out"), "--quiet"])
    assert code == 0
    assert (tmp_path / "out" / "steady_amplitude.png").stat().st_size > 0
    table = pd.read_csv(tmp_path / "out" / "sweep.csv")
    np.testing.assert_allclose(table["steady_amplitude"], _exact(np.array([6.0, 10.0])),
                               rtol=5e-3)
