"""The per-scene path of a sweep: :func:`lumped.simulate` once per parameter set.

Each set builds its scene (:func:`scene_of`), runs it and becomes one record
(:func:`run_one`; a failed run is a record with its status, never an exception). The sets
run in this process, in a pool of spawned processes (:func:`scenes_local`), or as tasks
on a Dask cluster (:func:`scenes_dask`).
"""

from __future__ import annotations

import os
import pickle
from concurrent.futures import ProcessPoolExecutor, as_completed
from multiprocessing import get_context
from typing import Any

from .params import ParameterSets, apply
from .progress import progress_bar
from .summary import failed_record, solution_record

__all__ = ["run_one", "scene_of", "scenes_local", "scenes_dask", "JIT_TASKS_PER_WORKER"]


def run_one(job: tuple, values: dict) -> tuple[dict, Any]:
    """Build and simulate one scene; a failed run is a record, not an exception."""
    source, method, dt, t_end, rtol, atol, keep, steady = job
    record, sol = simulate_one(source, method, dt, t_end, rtol, atol,
                                keep or steady is not None, values)
    if steady is not None:
        from .steady import empty_steady, forcing_omega, steady_record

        if sol is None:
            try:
                omega = forcing_omega(scene_of(source, values))
            except ValueError:
                omega = None
            record |= empty_steady(omega)
        else:
            try:
                record |= steady_record(sol, sol.scene, steady)
            except ValueError as err:
                record |= empty_steady()
                record["message"] = (record["message"] + "; " if record["message"]
                                     else "") + f"steady_amplitude: {err}"
    return record, (sol if keep else None)


def scene_of(source: Any, values: dict) -> Any:
    """The scene of one parameter set (a builder's, or the template's with ``values``)."""
    from lumped import Scene
    from lumped.io import scene_from_dict

    if callable(source):
        scene = source(dict(values))
        if not isinstance(scene, Scene):
            raise TypeError(f"the builder must return a Scene, got {type(scene).__name__} "
                            f"for {values!r}")
        return scene
    return scene_from_dict(apply(source, values), source="<template>")[0]


def simulate_one(source: Any, method: str, dt: float | None, t_end: float,
                  rtol: float | None, atol: float | None, keep: bool,
                  values: dict) -> tuple[dict, Any]:
    from lumped import InconsistentInitialForce, SolverError, simulate

    scene = scene_of(source, values)
    try:
        sol = simulate(scene, method=method, dt=dt, t_end=t_end, rtol=rtol, atol=atol,
                       throw=False)
    except InconsistentInitialForce as err:
        return failed_record(scene, method, dt, "inconsistent", str(err)), None
    except SolverError as err:
        return failed_record(scene, method, dt, err.status.value, str(err)), None
    except FloatingPointError as err:  # a method that raises rather than stopping early
        return failed_record(scene, method, dt, "non_finite", str(err)), None
    except (ArithmeticError, ValueError, RuntimeError) as err:
        return failed_record(scene, method, dt, "error", f"{type(err).__name__}: {err}"), None
    return solution_record(sol, scene, dt), (sol if keep else None)


def _run_rows(job: tuple, rows: list[dict]) -> list[tuple[dict, Any]]:
    return [run_one(job, values) for values in rows]


#: Parameter points a worker runs before it is replaced, for the ``jit-*`` methods. The
#: compiled code is one module per structure (a new parameter set compiles nothing), but
#: each new set keeps its generated Python kernels (about 0.1 MB, docs/benchmarks.md,
#: "Memory and time per new parameter set"); a new worker costs one import (about 2 s).
JIT_TASKS_PER_WORKER = 2000


def tasks_per_worker(method: str) -> int | None:
    """``max_tasks_per_child`` of the sweep's process pool for ``method``."""
    return JIT_TASKS_PER_WORKER if method.startswith("jit-") else None


def scenes_local(job: tuple, sets: ParameterSets, n_jobs: int | None,
                   show: bool) -> tuple[list, str]:
    rows = sets.as_dicts()
    workers = n_jobs if n_jobs is not None else (os.cpu_count() or 1)
    if len(rows) < 8 and n_jobs is None:
        workers = 1
    if workers > 1:
        try:
            pickle.dumps(job)
        except Exception:  # a lambda or local builder: stay in this process
            workers = 1
    bar = progress_bar(len(rows), show)
    results: list = [None] * len(rows)
    if workers == 1:
        for i, values in enumerate(rows):
            results[i] = run_one(job, values)
            bar.update(1)
        bar.close()
        return results, "serial"
    # spawn, not fork: numba's threading layer is not fork-safe once it has run
    with ProcessPoolExecutor(max_workers=workers, mp_context=get_context("spawn"),
                             max_tasks_per_child=tasks_per_worker(job[1])) as pool:
        futures = {pool.submit(run_one, job, values): i for i, values in enumerate(rows)}
        for fut in as_completed(futures):
            results[futures[fut]] = fut.result()
            bar.update(1)
    bar.close()
    return results, "processes"


def scenes_dask(client: Any, job: tuple, sets: ParameterSets, show: bool) -> list:
    from dask.distributed import as_completed as dask_completed

    rows = sets.as_dicts()
    [job_future] = client.scatter([job], broadcast=True)
    futures = {client.submit(run_one, job_future, values, pure=False): i
               for i, values in enumerate(rows)}
    results: list = [None] * len(rows)
    bar = progress_bar(len(rows), show)
    for fut in dask_completed(futures):
        results[futures[fut]] = fut.result()
        bar.update(1)
    bar.close()
    return results
