"""simulate_many on a 2-worker Dask LocalCluster gives the in-process table."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pandas as pd
import pytest

from lumped.sweep import simulate_many

distributed = pytest.importorskip("dask.distributed")

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"
F2 = EXAMPLES / "forcing-F2.toml"


@pytest.fixture(scope="module")
def client():
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                                  dashboard_address=":0") as cluster, \
            distributed.Client(cluster) as c:
        yield c


def test_compiled_grid_on_dask_equals_in_process(client):
    grid = {"nodes.mass.force.amplitude": np.linspace(0.0, 12.0, 25),
            "nodes.mass.force.omega": np.linspace(2.0, 20.0, 12)}
    local = simulate_many(F2, grid, dt=1e-3, t_end=2.0)
    remote = simulate_many(F2, grid, dt=1e-3, t_end=2.0, client=client)
    assert local.backend == "compiled" and remote.backend == "dask/compiled"
    assert len(client.scheduler_info()["workers"]) == 2
    pd.testing.assert_frame_equal(local.table, remote.table)  # same code: bit for bit


def test_per_scene_grid_on_dask_equals_in_process(client):
    grid = {"nodes.mass.force.amplitude": [0.5, 10.0], "nodes.mass.x0": [0.0, 0.1]}
    local = simulate_many(F2, grid, dt=2e-3, t_end=1.0, method="bdf2")
    remote = simulate_many(F2, grid, dt=2e-3, t_end=1.0, method="bdf2", client=client)
    assert remote.backend == "dask/per-scene"
    pd.testing.assert_frame_equal(local.table, remote.table)


def test_dask_backend_without_client_starts_a_local_cluster():
    grid = {"elements.dashpot.parameters.tau": [0.5, 1.0, 2.0]}
    res = simulate_many(F2, grid, dt=1e-3, t_end=1.0, backend="dask")
    assert res.backend == "dask/compiled"
    pd.testing.assert_frame_equal(res.table, simulate_many(F2, grid, dt=1e-3, t_end=1.0).table)
