r"""Output of the adaptive method: the dense output of its accepted steps, the row layout
of ``data``, and the first step size.
"""

from __future__ import annotations

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
        self._cache: tuple | None = None

    def add(self, t: float, h: float, y0: list[float], Y: list[list[float]]) -> None:
        self.t0.append(t)
        self.h.append(h)
        self.y0.append(y0)
        self.D.append([[Yk[j] - y0[j] for j in range(len(y0))] for Yk in Y])

    def _arrays(self) -> tuple[np.ndarray, ...]:
        n = len(self.t0)
        if self._cache is None or self._cache[0] != n:
            self._cache = (n, np.array(self.t0), np.array(self.h), np.array(self.y0),
                           np.array(self.D))
        return self._cache[1:]

    def __call__(self, t) -> np.ndarray:
        """Rows ``(t, x_i, v_i per node, F_e)`` at the times ``t`` (vectorised). At a step
        boundary the later step is used (right limits: the forces after an event)."""
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        N = self.N
        if not self.t0:
            raise ValueError("no step was taken: the dense output is empty")
        T0, H, Y0, D = self._arrays()
        t_lo, t_hi = T0[0], T0[-1] + H[-1]
        bad = ~((ts >= t_lo) & (ts <= t_hi))
        if bad.any():
            raise ValueError(f"`t` = {ts[bad][0]!r} is outside the solved interval "
                             f"[{t_lo!r}, {t_hi!r}]")
        i = np.clip(np.searchsorted(T0, ts, side="right") - 1, 0, len(T0) - 1)
        l1, l2, l3 = dense_weights((ts - T0[i]) / H[i])
        y = Y0[i] + (l1[:, None] * D[i, 0] + l2[:, None] * D[i, 1] + l3[:, None] * D[i, 2])
        out = np.empty((len(ts), 1 + y.shape[1]))
        out[:, 0] = ts
        out[:, 1:1 + 2 * N:2] = y[:, :N]
        out[:, 2:2 + 2 * N:2] = y[:, N:2 * N]
        out[:, 1 + 2 * N:] = y[:, 2 * N:]
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
