r"""One entry point: ``simulate(scene, method=..., t_end=..., dt=...) -> Solution``.

The methods live in :data:`lumped.solvers.registry.METHOD_REGISTRY` (see
:mod:`lumped.solvers.registry` for the built-in ones); ``simulate`` validates the
arguments, resolves ``auto``, runs the method and wraps its
:class:`~lumped.solvers.status.RawRun` into a :class:`~lumped.result.Solution`.
"""

from __future__ import annotations

from types import MappingProxyType
from typing import Any

from ._validate import as_positive
from .result import Solution
from .scene import Scene
from .solvers import registry
from .solvers.newton.options import NewtonOptions
from .solvers.registry import RunSettings, resolve_method

__all__ = ["simulate"]


def simulate(
    scene: Scene,
    *,
    method: str = "auto",
    t_end: float,
    dt: float | None = None,
    rtol: float | None = None,
    atol: float | None = None,
    throw: bool = True,
    options: NewtonOptions | None = None,
    **extra: Any,
) -> Solution:
    """Simulate ``scene`` from ``t = 0`` to ``t_end``.

    Parameters
    ----------
    scene : Scene
    method : str
        One of :data:`lumped.solvers.registry.METHODS`; default ``"auto"``, which runs
        what the arguments ask for (:func:`lumped.solvers.registry.resolve_method`):
        ``rtol``/``atol`` or neither, the adaptive ``radau5``; ``dt`` alone, a fixed-step
        method (``closed-bdf2`` on the paper's oscillator, else ``bdf2``, as on a scene
        with moving supports).
    t_end : float
        Final time (``> 0``).
    dt : float, optional
        Step size; required by the fixed-step methods (all built-in ones), whose grid is
        ``t_n = n dt`` with :func:`lumped.grid.steps_for` ``(dt, t_end)``
        steps.
    rtol, atol : float, optional
        Relative and absolute tolerances of an adaptive method (positive, finite).
    throw : bool
        On a failed step raise :class:`~lumped.solvers.status.SolverError` (default) --
        naming the time, the element or node, and the residual -- or, if ``False``,
        return the solution up to the last good step with ``status`` and ``message`` set.
    options : NewtonOptions, optional
        Newton tolerances and budgets.
    **extra
        Method-specific keywords, passed to the runner in ``RunSettings.extra``.

    Returns
    -------
    Solution

    Raises
    ------
    ValueError
        For a bad argument (the message names it), e.g. a fixed-step method without
        ``dt``.
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"`scene` must be a Scene, got {type(scene).__name__}")
    if not isinstance(method, str) or method not in registry.METHODS:
        raise ValueError(f"`method` must be one of {registry.METHODS}, got {method!r}")
    t_end = as_positive("t_end", t_end)
    dt = None if dt is None else as_positive("dt", dt)
    rtol = None if rtol is None else as_positive("rtol", rtol)
    atol = None if atol is None else as_positive("atol", atol)
    concrete = resolve_method(scene, method, dt=dt, rtol=rtol, atol=atol)
    if dt is None and concrete in registry.FIXED_STEP_METHODS:
        why = ""
        if method == "auto":  # say why auto chose a fixed-step method
            from .solvers.eventdriven.setup import scope_error

            why = f" (`auto` runs it on this scene: {scope_error(scene)})"
        raise ValueError(f"`dt` is required for the fixed-step method {concrete!r}{why}, "
                         "got None")
    if method == "auto" and concrete in registry.FIXED_STEP_METHODS and (
            rtol is not None or atol is not None):
        from .solvers.eventdriven.setup import scope_error

        raise ValueError(f"`auto` runs the fixed-step method {concrete!r} on this scene "
                         f"({scope_error(scene)}): it takes `dt`, not `rtol`/`atol` (got "
                         f"rtol={rtol!r}, atol={atol!r})")
    settings = RunSettings(t_end=t_end, dt=dt, rtol=rtol, atol=atol, throw=throw,
                           options=options, extra=MappingProxyType(dict(extra)))
    raw = registry.METHOD_REGISTRY[concrete](scene, settings)
    data = raw.data
    if data.ndim == 1:  # pragma: no cover - defensive
        data = data.reshape(1, -1)
    return Solution(
        columns=scene.columns(), data=data, node_names=scene.node_names,
        element_names=scene.element_names, method=concrete, stats=raw.stats,  # (copied)
        status=raw.status, message=raw.message,
        located_events=_located_events(raw), indeterminate=dict(raw.indeterminate),
        scene=scene, dense=raw.dense,
    )


def _located_events(raw) -> tuple | None:
    """The runner's events if it reports any (a method that locates events); else ``None``,
    and the Solution reads the branch switches off the samples (the fixed-step methods,
    or a run in which no event was located: then the samples show none either)."""
    return tuple(raw.events) if raw.events else None
