r"""Our methods as benchmark entries: :class:`Method` (a registry entry), :class:`Solved`
(what a timed solve returns), the closed-form and the generic semismooth-Newton steps.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from ..solvers.closed_form import integrate
from .scenes import BenchScene, Ladders, generic_scene

__all__ = [
    "Solved",
    "Method",
]


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
    kind : {"step", "scipy"}
        ``"step"`` methods are swept over ``Ladders.dts``; ``"scipy"`` ones over
        ``Ladders.eps x Ladders.rtols``.
    solve : callable
        ``solve(scene, setting, ladders) -> callable``; the returned zero-argument
        callable performs the timed solve and returns a :class:`Solved`.
    ours : bool
        ``True`` for the methods of this package.
    slow : bool
        A ``"step"`` method whose steps cost tens of microseconds: it skips the ``dt``
        of the ladder below ``Ladders.slow_min_dt`` (a time budget; the table then
        shows what the remaining ladder reaches).
    """

    name: str
    kind: str
    solve: Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]
    ours: bool = True
    slow: bool = False


def _closed_form(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        dt = setting["dt"]

        def run() -> Solved:
            traj = integrate(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.force,
                             dt=dt, t_end=scene.t_end, method=method)
            return Solved(traj.t, traj.x, traj.stats["steps"], traj.stats["steps"])

        return run

    return solve


def _generic(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    """The generic semismooth-Newton BDF steps of :func:`lumped.simulate.simulate`."""

    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        from ..simulate import simulate

        sc = generic_scene(scene)
        dt = setting["dt"]

        def run() -> Solved:
            sol = simulate(sc, method=method, dt=dt, t_end=scene.t_end, throw=True)
            x = sol.column("x_mass")
            return Solved(sol.t, x, int(sol.stats.get("steps", len(x) - 1)),
                          int(sol.stats.get("residual_evals", 0)))

        return run

    return solve
