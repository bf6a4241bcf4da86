r"""Our methods as benchmark entries: :class:`Method` (a registry entry), :class:`Solved`
(what a timed solve returns), the closed-form and the generic semismooth-Newton steps,
and :func:`tolerance_method`, which turns any ``simulate`` method driven by
``rtol``/``atol`` into an entry.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from .._validate import as_positive
from ..solvers.closed.integrate import integrate
from .scenes import GRID_DT, BenchScene, Ladders, generic_scene

__all__ = [
    "Solved",
    "Method",
    "steady_loop",
    "tolerance_method",
    "x_on_grid",
]


def steady_loop(method: str) -> dict[str, Any]:
    """The ``simulate`` keywords that time ``method`` as the bench does: a compiled
    ``jit-*`` method on its fast loop (``fast=True``), the steady state of a structure
    run before, which an untimed warm-up compiles (the default runs a new structure's
    first million steps on the port); ``{}`` for every other method."""
    return {"fast": True} if method.startswith("jit-") else {}


@dataclass(frozen=True)
class Solved:
    """What a method's solve returns for scoring: ``x`` on the common grid (or its nodes)."""

    t: np.ndarray
    x: np.ndarray
    steps: int
    nfev: int


@dataclass(frozen=True)
class Method:
    """A registry entry.

    Attributes
    ----------
    name : str
        Column name in the tables.
    kind : {"step", "scipy", "tol"}
        ``"step"`` methods are swept over ``Ladders.dts``; ``"scipy"`` ones (the
        tanh-regularised peers) over ``Ladders.eps x Ladders.rtols``; ``"tol"`` ones (driven
        by ``rtol`` and ``atol = rtol * L``) over ``rtols``, or ``Ladders.tol_rtols`` when
        ``rtols`` is ``None``.
    solve : callable
        ``solve(scene, setting, ladders) -> callable``; the returned zero-argument
        callable performs the timed solve and returns a :class:`Solved`.
    ours : bool
        ``True`` for the methods of this package.
    slow : bool
        A ``"step"`` method whose steps cost tens of microseconds: it skips the ``dt``
        of the ladder below ``Ladders.slow_min_dt`` (a time budget; the table then
        shows what the remaining ladder reaches).
    rtols : tuple of float, optional
        A ``"tol"`` method's own ladder of ``rtol``.
    warmup : bool
        Call the solve once, untimed, before timing it (a JIT compile, or filling an
        on-disk cache, is not part of the measured time).
    new_numbers : bool
        After the warm timing, time runs with new numbers (the user's column): the
        scene's ``k`` scaled by a factor never used before in the process
        (:func:`lumped.bench.new_numbers.new_factor`), a new one and a new scene object
        for each run (see :mod:`lumped.bench.runner`). For methods that compile per
        scene or keep caches.
    default : bool
        Run by default (``lumped bench`` without ``--methods``); ``False`` for an entry
        that is run only when named.
    """

    name: str
    kind: str
    solve: Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]
    ours: bool = True
    slow: bool = False
    rtols: tuple[float, ...] | None = None
    warmup: bool = False
    new_numbers: bool = False
    default: bool = True


def closed_form_method(method: str, engine: str = "python"
                 ) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    """The closed form (:func:`lumped.solvers.closed.integrate.integrate`) with an explicit
    ``engine``: ``"auto"`` would switch to the compiled loop once
    :mod:`lumped.solvers.closed.closed_form_jit` is imported, and one table would mix the two."""

    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        dt = setting["dt"]

        def run() -> Solved:
            traj = integrate(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.force,
                             dt=dt, t_end=scene.t_end, method=method, engine=engine)
            return Solved(traj.t, traj.x, traj.stats["steps"], traj.stats["steps"])

        return run

    return solve


def generic_method(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    """The generic semismooth-Newton BDF steps of :func:`lumped.simulate.simulate`."""

    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        from ..simulate import simulate

        sc = generic_scene(scene)
        dt = setting["dt"]
        fast = steady_loop(method)

        def run() -> Solved:
            sol = simulate(sc, method=method, dt=dt, t_end=scene.t_end, throw=True, **fast)
            x = sol.column("x_mass")
            return Solved(sol.t, x, int(sol.stats.get("steps", len(x) - 1)),
                          int(sol.stats.get("residual_evals", 0)))

        return run

    return solve


def tolerance_method(
    name: str, simulate_method: str, rtols: Sequence[float] | None = None, *,
    warmup: bool = True, new_numbers: bool = True, **options: Any,
) -> Method:
    """A bench entry for any :func:`lumped.simulate` method driven by ``rtol``/``atol``.

    Each setting runs ``simulate(scene, method=simulate_method, t_end=..., rtol=rtol,
    atol=rtol * L, **options)`` on the scene built by :func:`generic_scene` and scores
    ``x`` on the common grid through the solution's dense output ``sol.sol(t)`` (rows laid
    out like ``sol.data``), or at its samples when they are that grid.

    Parameters
    ----------
    name : str
        Column name in the tables.
    simulate_method : str
        A method registered in :data:`lumped.solvers.registry.METHOD_REGISTRY`.
    rtols : sequence of float, optional
        The ladder of ``rtol`` (default: ``Ladders.tol_rtols``).
    warmup : bool
        One untimed call first (default ``True``: a compiled method's first call compiles).
    new_numbers : bool
        Also time one run with new numbers per setting (default ``True``; see
        :class:`Method`).
    **options
        Further keywords for ``simulate``.

    Add the result to the benchmark with :func:`lumped.bench.register_bench_method`.
    """
    if not isinstance(simulate_method, str) or not simulate_method:
        raise ValueError(f"`simulate_method` must be a method name, got {simulate_method!r}")
    ladder = None if rtols is None else tuple(as_positive("rtols", r) for r in rtols)

    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        from ..simulate import simulate

        sc = generic_scene(scene)
        rtol, atol = setting["rtol"], setting["atol"]
        grid_dt = setting.get("grid_dt", GRID_DT)
        t_grid = np.arange(int(round(scene.t_end / grid_dt)) + 1) * grid_dt

        def run() -> Solved:
            sol = simulate(sc, method=simulate_method, t_end=scene.t_end, rtol=rtol,
                           atol=atol, **options)
            if not sol.ok:
                raise RuntimeError(f"{simulate_method}: {sol.status.value}: {sol.message}")
            x = x_on_grid(sol, t_grid)
            st = sol.stats
            return Solved(t_grid, x, int(st.get("steps", 0)),
                          int(st.get("nfev", st.get("residual_evals", 0))))

        return run

    return Method(name, "tol", solve, ours=True, rtols=ladder, warmup=warmup,
                  new_numbers=new_numbers)


def x_on_grid(sol: Any, t_grid: np.ndarray, node: str = "mass") -> np.ndarray:
    """``x_<node>`` of a :class:`~lumped.result.Solution` at the times ``t_grid``.

    Uses the method's own dense output ``sol.sol(t)`` when it has one (rows laid out like
    ``sol.data``; a :class:`~lumped.result.Solution` has one when ``sol.dense`` is set,
    its cubic Hermite fallback between fixed-step samples is not used); otherwise the
    samples themselves, which must then be ``t_grid``. Raises ``ValueError`` when neither
    applies (no interpolation is made up here).
    """
    col = sol.columns.index(f"x_{node}")
    dense = getattr(sol, "sol", None)
    if callable(dense) and getattr(sol, "dense", dense) is not None:
        rows = np.asarray(dense(t_grid), dtype=float)
        if rows.ndim != 2 or rows.shape != (len(t_grid), len(sol.columns)):
            raise ValueError(f"`sol.sol(t)` returned shape {rows.shape}, expected "
                             f"({len(t_grid)}, {len(sol.columns)})")
        return rows[:, col]
    t = sol.t
    if len(t) == len(t_grid) and np.allclose(t, t_grid, rtol=0.0, atol=1e-9 * t_grid[-1]):
        return np.asarray(sol.data[:, col], dtype=float)
    raise ValueError(f"method {sol.method!r} has no dense output (`sol.sol`) and its "
                     f"{len(t)} samples are not the {len(t_grid)}-point grid")
