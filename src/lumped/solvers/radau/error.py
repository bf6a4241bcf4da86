r"""The local error of a Radau IIA step (RADAU5's filtered estimate), its scaled norm
with the forces of the guarded elements, and the first step size.

Owns :class:`ErrorEstimate` (the methods :meth:`~ErrorEstimate.error` and
:meth:`~ErrorEstimate.error_norm` of :class:`lumped.solvers.radau.stage.StageSystem`),
:data:`FORCE_TOL_FACTOR` and :func:`initial_step`. The unknowns are laid out as in
:mod:`lumped.solvers.radau.stage`: ``U[k*n + i]`` is ``V_k,i`` for a node ``i < N`` and
``U[k*n + N + e]`` is ``F_k,e``, ``n = N + E``.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence

from .cone_split import linear_solver
from .tableau import E_ERR, MU_REAL, A

__all__ = ["ErrorEstimate", "FORCE_TOL_FACTOR", "initial_step"]

#: How much looser the forces of guarded elements are held than ``x`` and ``v``.
FORCE_TOL_FACTOR = 100.0


class ErrorEstimate:
    """The error estimate of a step on the stage values of
    :class:`~lumped.solvers.radau.stage.StageSystem`, which it is a base of: it reads the
    system's ``N``, ``E``, ``n``, ``m``, ``ea``, ``eb`` and ``spring``."""

    N: int
    E: int
    n: int
    m: list[float]
    ea: list[int]
    eb: list[int]
    spring: list[bool]

    def error(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
              net_n: list[float], jac_n: list[tuple[float, float]]) -> list[float] | None:
        r"""The filtered local error estimate of RADAU5, ``(e_x (N), e_v (N), e_F (E))``.

        Solves ``(mu/h M - J) e = f(y_n) + M sum_k E_k Z_k / h`` with ``Z_k = Y_k - y_n``:
        rows ``x' = v`` per node, momentum per mass (the junction balances and the laws
        have ``M = 0`` and right side 0: ``y_n`` is consistent), with the laws
        linearised at ``y_n`` (``jac_n[e] = (dR/dq, dR/dF)``); minimum norm if singular.
        """
        N, E, n = self.N, self.E, self.n
        m, ea, eb, spring = self.m, self.ea, self.eb, self.spring
        size = 2 * N + E
        M = [[0.0] * size for _ in range(size)]
        rhs = [0.0] * size
        g = MU_REAL / h
        for i in range(N):
            zx = 0.0
            zv = 0.0
            for k in range(3):
                s = 0.0
                for j in range(3):
                    s += A[k][j] * U[j * n + i]
                zx += E_ERR[k] * s  # (X_k - x_n) / h
                zv += E_ERR[k] * (U[k * n + i] - v_n[i])
            M[i][i] = g
            M[i][N + i] = -1.0
            rhs[i] = v_n[i] + zx
            if m[i] > 0.0:
                M[N + i][N + i] = g * m[i]
                rhs[N + i] = net_n[i] + m[i] * zv / h
        for e in range(E):
            col = 2 * N + e
            a, b = ea[e], eb[e]
            if a >= 0:
                M[N + a][col] -= 1.0
            if b >= 0:
                M[N + b][col] += 1.0
            Rq, RF = jac_n[e]
            off = 0 if spring[e] else N
            if b >= 0:
                M[col][off + b] -= Rq
            if a >= 0:
                M[col][off + a] += Rq
            M[col][col] = -RF
        return linear_solver(M)(rhs)

    def error_norm(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                   F_n: list[float], err: list[float], rtol: float, atol: float,
                   dF_n: list[float] | None, watched: Sequence[int], F_ref: float) -> float:
        r"""RMS of the scaled error: ``x`` of every node and ``v`` of every mass from ``err``
        (:meth:`error`), and the forces of the ``watched`` elements (those whose guards
        decide the events) when their slope ``dF_n`` at ``t_n`` is known (the previous
        step's polynomial): ``gamma_0 (h F'_n + sum_k E_k (F_k - F_n))``, the embedded
        estimate of their polynomial, unfiltered (a force is as smooth as the rates that
        set it). Scales: ``atol + rtol max(|y_n|, |y_n+1|)``, for forces
        ``rtol_F max(|F_n|, |F_n+1|, F_ref)`` with ``rtol_F = min(1e-3, 100 rtol)``: the
        forces' polynomial only has to show a guard's sign change, whose time is then
        found on exact end-of-step values."""
        N, n, m = self.N, self.n, self.m
        A3 = A[2]
        acc = 0.0
        cnt = 0
        for i in range(N):
            x_new = x_n[i] + h * (A3[0] * U[i] + A3[1] * U[n + i] + A3[2] * U[2 * n + i])
            sc = atol + rtol * max(abs(x_n[i]), abs(x_new))
            acc += (err[i] / sc) ** 2
            cnt += 1
            if m[i] > 0.0:
                sc = atol + rtol * max(abs(v_n[i]), abs(U[2 * n + i]))
                acc += (err[N + i] / sc) ** 2
                cnt += 1
        if dF_n is not None:
            g0 = 1.0 / MU_REAL
            rtol_F = min(1e-3, FORCE_TOL_FACTOR * rtol)
            for e in watched:
                k0 = N + e
                Fe = F_n[e]
                est = h * dF_n[e]
                for k in range(3):
                    est += E_ERR[k] * (U[k * n + k0] - Fe)
                sc = rtol_F * max(abs(Fe), abs(U[2 * n + k0]), F_ref)
                acc += (g0 * est / sc) ** 2
                cnt += 1
        return math.sqrt(acc / cnt)


def initial_step(x, v, acc, is_mass, rtol, atol, span) -> float:
    """A first step from the sizes of the state and its derivative (as scipy does), at
    least the run's step floor at ``t = 0``, ``16 eps 1e-3 span``
    (:func:`lumped.solvers.eventdriven.setup.step_floor`).

    The estimate ``0.01 d0 / d1`` reads a state below its tolerance (``d0 < 1``: a mass at
    ``x0 = 2e-15`` against ``atol = 1e-13``) against a large acceleration (``10 / atol``)
    as a step of ``3e-19``, below the floor ``1.8e-18`` of a run to ``0.5``: the run
    stopped before its first step and backward Euler bridged it (a mass breaking out
    from rest under a load, ``rtol = 1e-10``). The floor is a step the loop takes.
    """
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
    h = min(h0, 0.1 * span) * rtol ** 0.2 / 1e-6 ** 0.2 if h0 > 0 else 1e-6 * span
    return max(h, 16.0 * sys.float_info.epsilon * (span * 1e-3))
