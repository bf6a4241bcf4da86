r"""Output of the adaptive method: the dense output of its accepted steps, the row layout
of ``data``, and the first step size.
"""

from __future__ import annotations

import bisect
import math

import numpy as np

from .radau import dense_weights

__all__ = ["DenseOutput", "row_of", "initial_step"]


class DenseOutput:
    """The collocation polynomials of the accepted steps: ``t -> rows like data``."""

    def __init__(self, N: int, E: int) -> None:
        self.N, self.E = N, E
        self.t0: list[float] = []
        self.h: list[float] = []
        self.y0: list[list[float]] = []
        self.D: list[list[list[float]]] = []

    def add(self, t: float, h: float, y0: list[float], Y: list[list[float]]) -> None:
        self.t0.append(t)
        self.h.append(h)
        self.y0.append(y0)
        self.D.append([[Yk[j] - y0[j] for j in range(len(y0))] for Yk in Y])

    def row(self, i: int, s: float) -> list[float]:
        l1, l2, l3 = dense_weights(s)
        y0 = self.y0[i]
        D1, D2, D3 = self.D[i]
        return [y0[j] + (l1 * D1[j] + l2 * D2[j] + l3 * D3[j]) for j in range(len(y0))]

    def __call__(self, t) -> np.ndarray:
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        N, E = self.N, self.E
        out = np.empty((len(ts), 1 + 2 * N + E))
        if not self.t0:
            raise ValueError("no step was taken: the dense output is empty")
        t_lo = self.t0[0]
        t_hi = self.t0[-1] + self.h[-1]
        for r, tt in enumerate(ts):
            tt = float(tt)
            if not (t_lo <= tt <= t_hi):
                raise ValueError(f"`t` = {tt!r} is outside the solved interval "
                                 f"[{t_lo!r}, {t_hi!r}]")
            i = max(bisect.bisect_right(self.t0, tt) - 1, 0)
            y = self.row(i, (tt - self.t0[i]) / self.h[i])
            out[r, 0] = tt
            for p in range(N):
                out[r, 1 + 2 * p] = y[p]
                out[r, 2 + 2 * p] = y[N + p]
            out[r, 1 + 2 * N:] = y[2 * N:]
        return out


def row_of(t: float, x: list[float], v: list[float], F: list[float]) -> list[float]:
    row = [t]
    for p in range(len(x)):
        row += [x[p], v[p]]
    return row + list(F)


def initial_step(x, v, acc, is_mass, rtol, atol, span) -> float:
    """A first step from the sizes of the state and its derivative (as scipy does)."""
    d0 = d1 = 0.0
    n = 0
    for i in range(len(x)):
        sc = atol + rtol * abs(x[i])
        d0 += (x[i] / sc) ** 2
        d1 += (v[i] / sc) ** 2
        n += 1
        if is_mass[i]:
            sc = atol + rtol * abs(v[i])
            d0 += (v[i] / sc) ** 2
            d1 += (acc[i] / sc) ** 2
            n += 1
    d0, d1 = math.sqrt(d0 / n), math.sqrt(d1 / n)
    h0 = 1e-6 * span if d0 < 1e-5 or d1 < 1e-5 else 0.01 * d0 / d1
    return min(h0, 0.1 * span) * rtol ** 0.2 / 1e-6 ** 0.2 if h0 > 0 else 1e-6 * span
