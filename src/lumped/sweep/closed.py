"""The compiled batched path of a sweep: closed-form scenes as rows of a parameter array.

When the template is the paper's oscillator (one mass, a ``linear_spring`` and a
``bingham`` dashpot to ground; zero, constant or sine-burst forcing) and every swept
path is one of its numbers, the scenes never become :class:`~lumped.scene.Scene`
objects: each is one row ``(m, k, 1/gamma, tau, x0, v0, kind, p0, p1, p2)`` of an array
that :func:`lumped.solvers.closed.closed_form_jit.summary_batch` runs in parallel over the
cores (numba ``prange``), or in chunks on Dask workers.

Every swept value is still checked by the scene-file reader (one call per distinct
value of each path, since each of these numbers is checked on its own), so a value the
reader refuses is refused here with the reader's message.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from .params import ParameterSets, apply
from .progress import progress_bar

__all__ = ["ClosedPlan", "plan_closed", "closed_parameters", "run_chunk", "CLOSED_METHODS",
           "closed_local", "closed_dask"]

#: Scenes per compiled chunk (one progress-bar update, one Dask task).
_MIN_CHUNK = 64

#: Scenario-steps below which the compiled batch runs on one thread (starting numba's
#: thread pool costs more than such a batch).
_MIN_PARALLEL_WORK = 1_000_000

#: Sweep methods the batched closed form serves, with their BDF2 flag.
CLOSED_METHODS = {"auto": True, "closed-bdf2": True, "closed-bdf1": False}

_FIELDS = ("m", "k", "inv_gamma", "tau", "x0", "v0", "kind", "p0", "p1", "p2")


@dataclass(frozen=True)
class ClosedPlan:
    """How the swept paths map onto the columns of the parameter array."""

    node: str
    base: tuple[float, ...]
    columns: dict[str, tuple[int, Callable[[float], float]]]
    force_constant: bool  # the force itself is swept: kind becomes constant


def plan_closed(template: Mapping[str, Any], names: tuple[str, ...]) -> ClosedPlan | None:
    """A :class:`ClosedPlan` when the batched closed form covers the sweep, else ``None``."""
    from lumped.io import scene_from_dict
    from lumped.solvers import closed_form_oscillator
    from lumped.solvers.closed.closed_form_jit import FORCE_SAMPLED, FORCE_SINE, forcing_code

    if "ground" in template:  # the inertial force -m a_g moves with the swept numbers
        return None
    scene, _ = scene_from_dict(dict(template), source="<template>")
    found = closed_form_oscillator(scene)
    if isinstance(found, str):
        return None
    osc = found[0]
    mass = scene.nodes[0]
    code = forcing_code(scene.forcing[0])
    if code[0] == FORCE_SAMPLED:
        return None
    spring = next(el.name for el in scene.elements if el.law_name == "linear_spring")
    dashpot = next(el.name for el in scene.elements if el.law_name == "bingham")
    node = f"nodes.{mass.name}"
    same = float
    paths: dict[str, tuple[int, Callable[[float], float]]] = {
        f"{node}.mass": (0, same), f"{node}.x0": (4, same), f"{node}.v0": (5, same),
        f"elements.{spring}.parameters.k": (1, same),
        f"elements.{dashpot}.parameters.gamma": (2, lambda g: 1.0 / float(g)),
        f"elements.{dashpot}.parameters.tau": (3, same),
        f"{node}.force": (7, same),
    }
    if code[0] == FORCE_SINE:
        paths.update({f"{node}.force.amplitude": (7, same), f"{node}.force.omega": (8, same),
                      f"{node}.force.t_off": (9, same)})
    if not set(names) <= set(paths):
        return None
    if f"{node}.force" in names and any(n.startswith(f"{node}.force.") for n in names):
        return None
    base = (osc.m, osc.k, 1.0 / osc.gamma, osc.tau, mass.x0, mass.v0, float(code[0]),
            *code[1:])
    columns = {name: paths[name] for name in names}
    return ClosedPlan(mass.name, base, columns, f"{node}.force" in names)


def closed_parameters(plan: ClosedPlan, template: Mapping[str, Any],
                      sets: ParameterSets) -> np.ndarray:
    """The ``(n_scenes, 10)`` parameter array; every distinct swept value is checked by
    the scene-file reader first (``ValueError`` naming the path and the value)."""
    from lumped.io import scene_from_dict
    from lumped.solvers.closed.closed_form_jit import FORCE_CONSTANT

    for name in sets.names:
        seen: set = set()
        for value in sets.column(name):
            key = repr(value)
            if key in seen:
                continue
            seen.add(key)
            try:
                scene_from_dict(apply(template, {name: value}), source="<template>")
            except (TypeError, ValueError) as err:
                raise ValueError(f"parameter {name!r} = {value!r}: {err}") from None
    params = np.empty((len(sets), len(_FIELDS)))
    params[:] = plan.base
    if plan.force_constant:
        params[:, 6] = FORCE_CONSTANT
        params[:, 8:] = 0.0
    for j, name in enumerate(sets.names):
        col, convert = plan.columns[name]
        params[:, col] = [convert(row[j]) for row in sets.rows]
    return params


def run_chunk(params: np.ndarray, dt: float, n: int, bdf2: bool, parallel: bool) -> np.ndarray:
    """Summaries (``SUMMARY_FIELDS`` per row) of the scenes in ``params``.

    ``parallel=True`` uses every numba thread (``prange``); ``False`` runs on the calling
    thread without the GIL, for Dask workers that already run side by side.
    """
    from lumped.solvers.closed.closed_form_jit import (
        SUMMARY_FIELDS,
        summary_batch,
        summary_batch_serial,
    )

    out = np.empty((len(params), len(SUMMARY_FIELDS)))
    kernel = summary_batch if parallel else summary_batch_serial
    kernel(np.ascontiguousarray(params, dtype=float), float(dt), int(n), bool(bdf2), out)
    return out


def _chunks(n_rows: int, parts: int) -> list[slice]:
    size = max(_MIN_CHUNK, math.ceil(n_rows / max(parts, 1)))
    return [slice(i, min(i + size, n_rows)) for i in range(0, n_rows, size)]


def closed_local(params: np.ndarray, dt: float, n: int, bdf2: bool,
                 n_jobs: int | None, show: bool) -> np.ndarray:
    """The summaries of the rows ``params`` (:func:`run_chunk`) in this process, on up to
    ``n_jobs`` of numba's threads (all with ``None``), in parallel once the batch is
    large enough (:data:`_MIN_PARALLEL_WORK`)."""
    import numba

    previous = numba.get_num_threads()
    if n_jobs is not None:
        numba.set_num_threads(min(n_jobs, numba.config.NUMBA_NUM_THREADS))
    parallel = len(params) >= 2 and len(params) * n >= _MIN_PARALLEL_WORK
    try:
        if not show:
            return run_chunk(params, dt, n, bdf2, parallel=parallel)
        bar = progress_bar(len(params), show)
        parts = []
        for sl in _chunks(len(params), 50):
            parts.append(run_chunk(params[sl], dt, n, bdf2, parallel=parallel))
            bar.update(sl.stop - sl.start)
        bar.close()
        return np.concatenate(parts)
    finally:
        numba.set_num_threads(previous)


def closed_dask(client: Any, params: np.ndarray, dt: float, n: int, bdf2: bool,
                show: bool) -> np.ndarray:
    """The summaries of the rows ``params`` in chunks on ``client``'s workers (four chunks
    a worker), in the rows' order."""
    from dask.distributed import as_completed as dask_completed

    workers = max(len(client.scheduler_info().get("workers", {})), 1)
    slices = _chunks(len(params), 4 * workers)
    futures = {client.submit(run_chunk, params[sl], dt, n, bdf2, False, pure=False): k
               for k, sl in enumerate(slices)}
    parts: list = [None] * len(slices)
    bar = progress_bar(len(params), show)
    for fut in dask_completed(futures):
        k = futures[fut]
        parts[k] = fut.result()
        bar.update(slices[k].stop - slices[k].start)
    bar.close()
    return np.concatenate(parts)
