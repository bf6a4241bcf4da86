"""``simulate_many``: run a family of scenes and return one tidy table.

Two paths, chosen per sweep:

* **batched and compiled**: the template is the paper's oscillator and every swept path
  is one of its numbers (:mod:`lumped.sweep.closed`); the closed-form method
  (``auto``, ``closed-bdf1``, ``closed-bdf2``) runs all scenes as rows of one array in
  compiled code, in parallel over the cores;
* **per scene**: anything else runs :func:`lumped.simulate` once per scene, in a pool
  of processes (or serially), and summarises each solution
  (:mod:`lumped.sweep.per_scene`).

Either runs on a Dask cluster instead with ``client=`` or ``backend="dask"``.
"""

from __future__ import annotations

import sys
from collections.abc import Callable, Mapping
from pathlib import Path
from typing import Any

from .closed import CLOSED_METHODS, closed_dask, closed_local, closed_parameters, plan_closed
from .params import ParameterSets, apply, parameter_sets
from .per_scene import scenes_dask, scenes_local
from .result import SweepResult
from .summary import RESULT_COLUMNS, closed_record

__all__ = ["simulate_many", "BACKENDS"]

#: Values of ``backend``.
BACKENDS = ("local", "dask")


def simulate_many(
    template: str | Path | Mapping[str, Any] | Callable[[dict], Any],
    parameters: Mapping[str, Any] | list[Mapping[str, Any]],
    *,
    method: str | None = None,
    dt: float | None = None,
    t_end: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    keep_trajectories: bool = False,
    backend: str = "local",
    client: Any = None,
    n_jobs: int | None = None,
    progress: bool | None = None,
    steady_amplitude: str | None = None,
) -> SweepResult:
    """Simulate every scene of a sweep and tabulate what each did.

    Parameters
    ----------
    template : path, dict or callable
        A scene file (``.toml`` path), the dict of its parsed tables, or a *builder*
        ``builder(values: dict) -> Scene`` called with each parameter set. A file or
        dict's ``[solver]`` table gives defaults for ``method``, ``dt``, ``t_end``,
        ``rtol``, ``atol`` (its ``rtol``/``atol`` serve an adaptive method only: a
        fixed-step ``method`` given here ignores them).
    parameters : dict or list of dict
        A grid ``{path: values}`` (Cartesian product; the first path varies slowest) or
        one ``{path: value}`` per scene. Paths are dotted keys into the scene file, e.g.
        ``"nodes.mass.force.amplitude"``, ``"elements.dashpot.parameters.tau"``; with a
        builder they are whatever the builder reads.
    method, dt, t_end, rtol, atol
        As for :func:`lumped.simulate`, here or in the template's ``[solver]`` table
        (``method`` defaults to it, else ``"auto"``); ``t_end`` is required. A
        fixed-step method needs ``dt`` and refuses ``rtol``/``atol``. ``rtol`` and/or
        ``atol`` run the adaptive ``radau5`` (``method="radau5"``, or ``"auto"``: then
        every scene runs per scene, never on the batched closed form), with ``dt`` its
        output grid, without ``dt`` its step points; ``radau5`` with neither runs at its
        default tolerances. ``"auto"`` needs ``dt`` or a tolerance. The rows of an
        adaptive run are summarised on the intervals between its samples
        (:mod:`lumped.sweep.summary`).
    keep_trajectories : bool
        Also return every :class:`~lumped.Solution` (runs per scene).
    backend : {"local", "dask"}
        ``"dask"`` without ``client`` starts a ``LocalCluster`` for this call.
    client : dask.distributed.Client, optional
        Run on this cluster (implies ``backend="dask"``).
    n_jobs : int, optional
        Local parallelism: numba threads for the compiled path, processes for the
        per-scene path. Default: all cores (numba's thread count); the per-scene path
        stays in this process for fewer than 8 scenes or a builder that cannot be pickled.
    progress : bool, optional
        Show a progress bar (tqdm); default: only when stderr is a terminal.
    steady_amplitude : str, optional
        An element (``"a+b"`` for elements in parallel) or a node: add the columns of
        :mod:`lumped.sweep.steady` (``steady_omega``, ``steady_amplitude``,
        ``steady_cycles``, ``energy_per_cycle``, ``zeta_eq``), the steady amplitude
        under the scene's one sine forcing or sine ground motion; over a grid of its
        ``omega`` this is the amplitude-frequency curve (``res.heatmap(
        "steady_amplitude", ...)`` plots it). Runs per scene.

    Returns
    -------
    SweepResult
        ``.table`` (pandas DataFrame, one row per scene), ``.to_xarray()``, ``.write()``,
        ``.heatmap()``. A scene that fails is a row with its ``status`` and ``message``
        and its numbers up to the failure; it never stops the sweep.

    Raises
    ------
    ValueError, TypeError
        Bad arguments, or a parameter value the scene (file) refuses, naming it.

    Examples
    --------
    >>> from lumped.sweep import simulate_many
    >>> res = simulate_many("examples/forcing-F2.toml",
    ...                     {"nodes.mass.force.amplitude": [0.5, 10.0]}, t_end=2.0)
    ... # doctest: +SKIP
    >>> res = simulate_many("examples/bingham-chain-3.toml",   # [solver]: radau5, rtol
    ...                     {"elements.s2.parameters.k": [15.0, 20.0, 25.0]},
    ...                     rtol=1e-6)  # doctest: +SKIP
    """
    from lumped._validate import as_int_at_least
    from lumped.solvers import registry, steps_for

    try:
        import pandas  # noqa: F401  (the result table; checked before any work)
    except ImportError:
        raise ImportError("lumped.sweep needs pandas: pip install 'lumped[sweep]'") from None
    builder, data, settings = _template(template)
    sets = parameter_sets(parameters)
    clash = [n for n in sets.names if n in RESULT_COLUMNS or n.split(".")[0] in RESULT_COLUMNS]
    if clash:
        raise ValueError(f"parameter name {clash[0]!r} is also a result column; rename it")
    method = method if method is not None else settings.get("method", "auto")
    if not isinstance(method, str) or method not in registry.METHODS:
        raise ValueError(f"`method` must be one of {registry.METHODS}, got {method!r}")
    dt, t_end, rtol, atol = _steps_and_tolerances(method, dt, t_end, rtol, atol, settings)
    adaptive = rtol is not None or atol is not None or method not in (
        "auto", *registry.FIXED_STEP_METHODS)
    n = steps_for(dt, t_end) if dt is not None else 0
    if backend not in BACKENDS:
        raise ValueError(f"`backend` must be one of {BACKENDS}, got {backend!r}")
    if n_jobs is not None:
        n_jobs = as_int_at_least("n_jobs", n_jobs, 1)
    if client is not None:
        backend = "dask"
    show = sys.stderr.isatty() if progress is None else bool(progress)

    plan = None
    if steady_amplitude is not None and not isinstance(steady_amplitude, str):
        raise TypeError(f"`steady_amplitude` must be an element or node name, "
                        f"got {steady_amplitude!r}")
    if (builder is None and method in CLOSED_METHODS and not adaptive and not keep_trajectories
            and steady_amplitude is None):
        plan = plan_closed(data, sets.names)
    if plan is not None:
        params = closed_parameters(plan, data, sets)
        bdf2 = CLOSED_METHODS[method]
        name = "closed-bdf2" if bdf2 else "closed-bdf1"
        if backend == "dask":
            out = _with_cluster(client, lambda c: closed_dask(c, params, dt, n, bdf2, show))
            where = "dask/compiled"
        else:
            out = closed_local(params, dt, n, bdf2, n_jobs, show)
            where = "compiled"
        records = [closed_record(row, n, dt, name, plan.node) for row in out]
        trajectories = None
    else:
        if builder is None:
            _validate_rows(data, sets)
        source = builder if builder is not None else data
        job = (source, method, dt, t_end, rtol, atol, keep_trajectories, steady_amplitude)
        if backend == "dask":
            results = _with_cluster(client, lambda c: scenes_dask(c, job, sets, show))
            where = "dask/per-scene"
        else:
            results, where = scenes_local(job, sets, n_jobs, show)
        records = [r[0] for r in results]
        trajectories = [r[1] for r in results] if keep_trajectories else None
    return SweepResult(_frame(sets, records), sets.names, sets.grid, trajectories, where)


# ------------------------------------------------------------------------ template


def _template(template: object) -> tuple[Callable | None, dict | None, dict]:
    """``(builder, scene-file dict, [solver] settings)`` of a template."""
    from lumped.io import read_scene_file, scene_from_dict

    if isinstance(template, (str, Path)):
        from lumped.io.scene_inputs import resolve_files

        data = resolve_files(read_scene_file(template), Path(template).parent)
        _, settings = scene_from_dict(data, source=str(template))
        return None, data, settings
    if isinstance(template, Mapping):
        _, settings = scene_from_dict(dict(template), source="<template>")
        return None, dict(template), settings
    if callable(template):
        return template, None, {}
    raise TypeError("`template` must be a scene file path, a scene-file dict or a builder "
                    f"callable, got {type(template).__name__}")


def _steps_and_tolerances(method: str, dt: Any, t_end: Any, rtol: Any, atol: Any,
                          settings: Mapping[str, Any]) -> tuple:
    """``(dt, t_end, rtol, atol)`` of a sweep: the arguments over the template's
    ``[solver]`` table, checked against ``method`` (see :func:`simulate_many`)."""
    from lumped._validate import as_positive
    from lumped.solvers.registry import FIXED_STEP_METHODS

    given = {name: value for name, value in (("rtol", rtol), ("atol", atol))
             if value is not None}
    if method in FIXED_STEP_METHODS and given:
        name, value = next(iter(given.items()))
        raise ValueError(f"`{name}` is a tolerance of the adaptive method 'radau5'; the "
                         f"fixed-step method {method!r} takes `dt`, got {name}={value!r}")
    if method not in FIXED_STEP_METHODS:  # the file's tolerances serve an adaptive method
        rtol = rtol if rtol is not None else settings.get("rtol")
        atol = atol if atol is not None else settings.get("atol")
    dt = dt if dt is not None else settings.get("dt")
    t_end = t_end if t_end is not None else settings.get("t_end")
    if t_end is None:
        raise ValueError("give `t_end` (or a [solver] table in the template), got None")
    t_end = as_positive("t_end", t_end)
    dt = None if dt is None else as_positive("dt", dt)
    rtol = None if rtol is None else as_positive("rtol", rtol)
    atol = None if atol is None else as_positive("atol", atol)
    if dt is None and method in FIXED_STEP_METHODS:
        raise ValueError(f"`dt` is required for the fixed-step method {method!r} (here or "
                         "in the template's [solver] table), got None")
    if dt is None and rtol is None and atol is None and method == "auto":
        raise ValueError("give `dt` (a fixed-step method) or `rtol`/`atol` (the adaptive "
                         "method 'radau5'), here or in the template's [solver] table; "
                         "got neither")
    return dt, t_end, rtol, atol


def _validate_rows(data: dict, sets: ParameterSets) -> None:
    """Build every scene of a file template once, refusing bad values before any run."""
    from lumped.io import scene_from_dict

    for i, values in enumerate(sets.as_dicts()):
        try:
            scene_from_dict(apply(data, values), source="<template>")
        except (TypeError, ValueError) as err:
            raise ValueError(f"parameter set {i} {values!r}: {err}") from None


def _with_cluster(client: Any, work: Callable[[Any], Any]) -> Any:
    """Run ``work(client)`` on ``client``, or on a LocalCluster started for this call."""
    if client is not None:
        return work(client)
    from dask.distributed import Client, LocalCluster

    with LocalCluster(processes=False, threads_per_worker=1, dashboard_address=":0") as cl, \
            Client(cl) as own:
        return work(own)


def _frame(sets: ParameterSets, records: list[dict]):
    import pandas as pd

    frame = pd.DataFrame.from_records(
        [dict(zip(sets.names, row, strict=True)) | rec
         for row, rec in zip(sets.rows, records, strict=True)])
    for col in frame.columns:
        if col.startswith("rest_position.") or col in ("steady_omega", "steady_amplitude",
                                                       "energy_per_cycle", "zeta_eq"):
            frame[col] = frame[col].astype("Float64")
    return frame
