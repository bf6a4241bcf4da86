r"""The rows of the adaptive method's output: the row layout of ``data`` (``t``, then ``x_i,
v_i`` per node, then ``F_e``: :func:`row_of`), the rows of a run's accepted steps
(:class:`Rows`) and a run's ``data`` (:func:`output_data`: the step points, or the dense
output on the grid of ``dt``).
"""

from __future__ import annotations

import numpy as np

from ...grid import steps_for
from .dense import DenseOutput

__all__ = ["Rows", "output_data", "row_of"]


class Rows:
    """The output rows of the accepted steps, one list at a time (:meth:`append`), as an
    array block (:meth:`extend`) or written in place (:meth:`block`, :meth:`commit`), in
    an array that grows by doubling."""

    def __init__(self) -> None:
        self._buf = np.empty((0, 0))
        self._n = 0

    def _reserve(self, k: int, width: int) -> None:
        if self._n + k > self._buf.shape[0] or self._buf.shape[1] != width:
            grown = np.empty((max(self._n + k, 2 * self._buf.shape[0], 64), width))
            if self._n:
                grown[:self._n] = self._buf[:self._n]
            self._buf = grown

    def append(self, row: list[float]) -> None:
        self._reserve(1, len(row))
        self._buf[self._n] = row
        self._n += 1

    def extend(self, block: np.ndarray) -> None:
        k = len(block)
        if k:
            self.block(k, block.shape[1])[:] = block
            self.commit(k)

    def block(self, k: int, width: int) -> np.ndarray:
        """A view of room for the next ``k`` rows of ``width`` values (kept by
        :meth:`commit`)."""
        self._reserve(k, width)
        return self._buf[self._n:self._n + k]

    def commit(self, k: int) -> None:
        self._n += k

    def first(self) -> list[float]:
        return self._buf[0].tolist()

    def set_first(self, row: list[float]) -> None:
        self._buf[0] = row

    def array(self) -> np.ndarray:
        return self._buf[:self._n]


def row_of(t: float, x: list[float], v: list[float], F: list[float]) -> list[float]:
    row = [t]
    for p in range(len(x)):
        row += [x[p], v[p]]
    return row + list(F)


def output_data(rows: Rows, dense: DenseOutput, dt: float | None, t_end: float,
                t: float) -> np.ndarray:
    """``data`` of a run that reached ``t``: the accepted step points, or with ``dt`` the
    dense output on ``t_n = n dt`` (up to ``t``; the first row exactly the initial one)."""
    data = rows.array()
    if dt is not None and len(dense):
        grid = np.arange(steps_for(dt, t_end) + 1) * dt
        grid = grid[grid <= t + 1e-12 * max(1.0, t)]
        # the last step ends at t_n + h, an ulp from t at times
        grid[-1] = min(grid[-1], t, dense.span()[1])
        data = dense(grid)
        data[0] = rows.first()
    return data
