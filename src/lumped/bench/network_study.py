r"""Accuracy study of a network scene (issue 8, "beyond one mass"): the displacements of
every node on a grid, the fixed-step BDF2 ladder with its observed order, and the limit
``dt -> 0`` that the ladder supports (Richardson extrapolation or the finest run).

BDF2 has the expansion ``y_h = y + C h^p + o(h^p)`` with ``p = 2`` on a smooth solution,
so the extrapolant

.. math::  R_h = \frac{2^p\, y_{h/2} - y_h}{2^p - 1}

removes the leading term, and ``p`` is observed from three runs as
``log2(|y_h - y_{h/2}| / |y_{h/2} - y_{h/4}|)``. Across stick-slip events the fixed
steps do not land on the events: the error then depends on where each event falls
inside its step, a fraction that jumps as ``h`` is halved, so the constant ``C`` is not
a smooth function of ``h`` and no extrapolation removes it. :func:`bdf2_limit` uses the
extrapolant only where the observed orders are all near 2; otherwise it takes the
finest run as the limit, with a first-order envelope of the ladder's differences as its
error estimate (exact for an error ``C h``; the study prints the orders it saw).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from ..scene import Scene

__all__ = [
    "BdfLadder",
    "BdfLimit",
    "bdf2_ladder",
    "bdf2_limit",
    "grid",
    "node_x",
    "richardson",
]


def grid(t_end: float, grid_dt: float) -> np.ndarray:
    """``t_i = i grid_dt`` for ``0 <= t_i <= t_end`` (``t_end`` a multiple of ``grid_dt``)."""
    n = int(round(t_end / grid_dt))
    if abs(n * grid_dt - t_end) > 1e-9 * t_end:
        raise ValueError(f"`t_end` = {t_end!r} is not a multiple of `grid_dt` = {grid_dt!r}")
    return np.arange(n + 1) * grid_dt


def node_x(sol, scene: Scene, t: np.ndarray | None = None) -> np.ndarray:
    """``x`` of every node of ``scene`` (columns in node order) from a
    :class:`~lumped.result.Solution`: its dense output at ``t``, or its samples if ``t``
    is ``None``."""
    cols = [sol.columns.index(f"x_{name}") for name in scene.node_names]
    rows = sol.data if t is None else np.asarray(sol.sol(t), dtype=float)
    return rows[:, cols]


def richardson(coarse: np.ndarray, fine: np.ndarray, order: float) -> np.ndarray:
    r"""``(2^p y_{h/2} - y_h) / (2^p - 1)``: the extrapolant of order ``p`` from the run at
    ``h`` (``coarse``) and at ``h/2`` (``fine``)."""
    if not (isinstance(order, (int, float)) and order > 0):
        raise ValueError(f"`order` must be a number > 0, got {order!r}")
    w = 2.0 ** order
    return (w * fine - coarse) / (w - 1.0)


@dataclass
class BdfLadder:
    """BDF2 runs at ``dts`` (each half the last), sampled on the common grid."""

    dts: list[float]
    x: list[np.ndarray]      # per dt: (n_grid, n_nodes)
    steps: list[int]

    def differences(self) -> list[float]:
        """``max |y_h - y_{h/2}|`` for consecutive runs."""
        return [float(np.max(np.abs(b - a))) for a, b in zip(self.x[:-1], self.x[1:],
                                                             strict=True)]

    def orders(self) -> list[float]:
        """Observed order ``log2`` of consecutive difference ratios (``nan`` at 0)."""
        d = self.differences()
        return [math.log2(a / b) if a > 0 and b > 0 else math.nan
                for a, b in zip(d[:-1], d[1:], strict=True)]


def bdf2_ladder(scene: Scene, t_end: float, dts: Sequence[float], grid_dt: float, *,
                method: str = "jit-bdf2") -> BdfLadder:
    """Fixed-step BDF2 (``method`` ``"bdf2"`` or ``"jit-bdf2"``, the same numbers) at each
    ``dt`` (each must divide ``grid_dt``), the node displacements on the common grid."""
    from ..simulate import simulate

    g = grid(t_end, grid_dt)
    out = BdfLadder([], [], [])
    for dt in dts:
        stride = int(round(grid_dt / dt))
        if stride < 1 or abs(stride * dt - grid_dt) > 1e-9 * grid_dt:
            raise ValueError(f"`dts`: {dt!r} does not divide the grid step {grid_dt!r}")
        sol = simulate(scene, method=method, dt=dt, t_end=t_end)
        x = node_x(sol, scene)[::stride]
        if len(x) != len(g):  # pragma: no cover - simulate lands on t_end
            raise RuntimeError(f"{method} at dt = {dt!r} gave {len(x)} grid rows, "
                               f"expected {len(g)}")
        out.dts.append(float(dt))
        out.x.append(x)
        out.steps.append(int(sol.stats["steps"]))
        del sol
    return out


@dataclass(frozen=True)
class BdfLimit:
    """The ladder's estimate of ``lim_{dt -> 0}`` BDF2 and how it was made."""

    x: np.ndarray
    error_estimate: float
    how: str                 # "richardson p=2" | "finest run"
    orders: tuple[float, ...]


def bdf2_limit(ladder: BdfLadder, *, smooth_tol: float = 0.25) -> BdfLimit:
    """The limit the ladder supports (see the module notes).

    If the last two observed orders are within ``smooth_tol`` of 2: the order-2
    Richardson extrapolant of the two finest runs, with the difference of the last two
    extrapolants as its error estimate. Otherwise the finest run ``y_H``, with the
    first-order envelope ``max_k (|y_{h_k} - y_{h_k/2}| / (h_k/2)) H`` as its error
    estimate: for an error ``C h`` each difference is ``C h_k / 2``, so this is ``C H``
    with the largest ``C`` any halving showed. Needs at least three runs.
    """
    if len(ladder.x) < 3:
        raise ValueError(f"`ladder` needs at least 3 runs, got {len(ladder.x)}")
    orders = ladder.orders()
    tail = orders[-2:]
    if all(math.isfinite(p) and abs(p - 2.0) <= smooth_tol for p in tail):
        fine = richardson(ladder.x[-2], ladder.x[-1], 2.0)
        prev = richardson(ladder.x[-3], ladder.x[-2], 2.0)
        return BdfLimit(fine, float(np.max(np.abs(fine - prev))), "richardson p=2",
                        tuple(orders))
    d, h = ladder.differences(), ladder.dts
    envelope = max(dk / hk for dk, hk in zip(d, h[1:], strict=True)) * h[-1]
    return BdfLimit(ladder.x[-1], envelope, "finest run", tuple(orders))
