r"""Convergence tests of the compiled Newton, written for numba: the twin of
:mod:`lumped.solvers.newton.criteria`.

Owns the residual and update tests (:func:`residual_ok`, :func:`update_ok`,
:func:`update_ok_scaled`), the round-off test :func:`at_roundoff`, the line search's
:func:`merit`, the probe :func:`hair`, the finiteness tests in the order Python's
``sum`` adds (:func:`finite_sum`, :func:`finite_matrix`, :func:`finite_matrix_rows`),
the Jacobian comparison :func:`same` and :func:`worst_row`, on numpy arrays, each
operation for operation as the reference (:mod:`lumped.solvers.newton.criteria` and the
tests inside :func:`lumped.solvers.newton.semismooth.newton_solve`).
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.jit import njit
from .criteria import ROUNDOFF

__all__ = ["at_roundoff", "finite_matrix", "finite_matrix_rows", "finite_sum", "hair", "merit",
           "residual_ok", "same", "update_ok", "update_ok_scaled", "worst_row"]


@njit(cache=True, inline="always")
def finite_sum(a) -> bool:
    """``isfinite(sum(a))`` in the order Python's ``sum`` adds (the reference's test)."""
    s = 0.0
    for x in a.flat:
        s += x
    return math.isfinite(s)


@njit(cache=True, inline="always")
def finite_matrix(J) -> bool:
    """``isfinite(sum(map(sum, J)))``: row sums added up, as the reference does."""
    s = 0.0
    for i in range(J.shape[0]):
        r = 0.0
        for j in range(J.shape[1]):
            r += J[i, j]
        s += r
    return math.isfinite(s)


@njit(cache=True, inline="always")
def same(A, B) -> bool:
    """Entrywise equality of two matrices (NaN differs from everything)."""
    for i in range(A.shape[0]):
        for j in range(A.shape[1]):
            if not A[i, j] == B[i, j]:
                return False
    return True


@njit(cache=True, inline="always")
def residual_ok(G, S, rtol: float, atol: float) -> bool:
    for i in range(G.shape[0]):
        if not abs(G[i]) <= rtol * S[i] + atol:
            return False
    return True


@njit(cache=True, inline="always")
def at_roundoff(G, S) -> bool:
    """``|G_i| <= ROUNDOFF * S_i`` for every row (the reference's ``at_roundoff``)."""
    for i in range(G.shape[0]):
        if not abs(G[i]) <= ROUNDOFF * S[i]:
            return False
    return True


@njit(cache=True, inline="always")
def update_ok(du, u, rtol: float, atol: float) -> bool:
    for i in range(u.shape[0]):
        if not abs(du[i]) <= rtol * abs(u[i]) + atol:
            return False
    return True


@njit(cache=True, inline="always")
def update_ok_scaled(du, u, J, S, rtol: float, atol: float) -> bool:
    """The update test against ``max(|u_j|, min_i S_i / |J_ij|)`` (the reference's
    ``update_ok_scaled``)."""
    n = u.shape[0]
    for j in range(n):
        a = abs(du[j])
        if a <= rtol * abs(u[j]) + atol:
            continue
        T = math.inf
        for i in range(n):
            c = abs(J[i, j])
            if c > 0.0 and S[i] / c < T:
                T = S[i] / c
        if not a <= rtol * T + atol:
            return False
    return True


@njit(cache=True, inline="always")
def merit(G, S, floor: float) -> float:
    m = 0.0
    for i in range(G.shape[0]):
        r = abs(G[i]) / (S[i] + floor)
        if r > m:
            m = r
    return m


@njit(cache=True, inline="always")
def hair(u: float, d: float) -> float:
    """``u - 1e-8 d``, at least one ulp away from ``u`` when ``d != 0``."""
    p = u - 1e-8 * d
    if p == u and d != 0.0:
        p = np.nextafter(u, -math.inf if d > 0.0 else math.inf)
    return p


@njit(cache=True, inline="always")
def worst_row(G, S, rtol: float, atol: float) -> int:
    """Index of the largest ``|G_i| / (rtol S_i + atol)`` (a NaN counts as largest)."""
    worst = 0
    ratio = -1.0
    for i in range(G.shape[0]):
        r = abs(G[i]) / (rtol * S[i] + atol)
        if not r <= ratio:
            worst = i
            ratio = r
            if not math.isfinite(r):
                break
    return worst


@njit(cache=True, inline="always")
def finite_matrix_rows(J) -> bool:
    """``all(finite(row) for row in J)``: every row's sum finite."""
    for i in range(J.shape[0]):
        r = 0.0
        for j in range(J.shape[1]):
            r += J[i, j]
        if not math.isfinite(r):
            return False
    return True
