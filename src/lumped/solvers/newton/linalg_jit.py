r"""Small dense linear algebra for the compiled Newton, written for numba: the twin of
:mod:`lumped.solvers.newton.linalg`.

Owns :func:`lu_factor_into` (LU with singleton-row pivots, operation for operation as
:func:`lumped.solvers.newton.linalg.lu_factor`: a stuck dashpot's row ``v = 0`` gives
``v = 0`` exactly), :func:`lu_solve_into`, :func:`inverse_into` and :func:`copy_into`, all
on preallocated numpy arrays (no allocation inside a step). Used by
:mod:`lumped.solvers.newton.semismooth_jit`, the compiled BDF and Radau steps and the
generated fast-path modules (:mod:`lumped.solvers.bdf.fast_codegen`).
"""

from __future__ import annotations

import math

from ...codegen.jit import njit

__all__ = ["copy_into", "inverse_into", "lu_factor_into", "lu_solve_into"]


@njit(cache=True)
def lu_factor_into(A, LU, perm) -> bool:
    """Factor ``A`` into ``LU`` (packed unit-lower and upper factors) and ``perm``.

    Column ``k``'s pivot is the first singleton row (its only nonzero among the active
    columns ``k..n-1`` is in column ``k``), else the largest entry. Returns False when a
    pivot is zero or not finite (``A`` singular). As
    :func:`lumped.solvers.newton.linalg.lu_factor`, operation for operation.
    """
    n = A.shape[0]
    for i in range(n):
        perm[i] = i
        for j in range(n):
            LU[i, j] = A[i, j]
    for k in range(n):
        p = k
        best = abs(LU[k, k])
        for i in range(k + 1, n):
            a = abs(LU[i, k])
            if a > best:
                best = a
                p = i
        if best > 0.0:
            for i in range(k, n):
                if LU[i, k] != 0.0:
                    single = True
                    for j in range(k + 1, n):
                        if LU[i, j] != 0.0:
                            single = False
                            break
                    if single:
                        p = i
                        best = abs(LU[i, k])
                        break
        if not (best > 0.0) or best == math.inf:
            return False
        if p != k:
            for j in range(n):
                tmp = LU[k, j]
                LU[k, j] = LU[p, j]
                LU[p, j] = tmp
            ip = perm[k]
            perm[k] = perm[p]
            perm[p] = ip
        piv = LU[k, k]
        for i in range(k + 1, n):
            f = LU[i, k]
            if f != 0.0:
                f /= piv
                LU[i, k] = f
                for j in range(k + 1, n):
                    LU[i, j] -= f * LU[k, j]
    return True


@njit(cache=True, inline="always")
def lu_solve_into(LU, perm, b, y) -> None:
    """``y = A^{-1} b`` with the factors of :func:`lu_factor_into` (``y`` may not be ``b``)."""
    n = LU.shape[0]
    for i in range(n):
        y[i] = b[perm[i]]
    for i in range(1, n):
        s = y[i]
        for j in range(i):
            s -= LU[i, j] * y[j]
        y[i] = s
    for i in range(n - 1, -1, -1):
        s = y[i]
        for j in range(i + 1, n):
            s -= LU[i, j] * y[j]
        y[i] = s / LU[i, i]


@njit(cache=True)
def inverse_into(LU, perm, b, y, inv) -> None:
    """``inv = A^{-1}`` from the factors of :func:`lu_factor_into`, column by column
    (``A^{-1} e_c`` by :func:`lu_solve_into`; ``b, y`` are work vectors). A singleton
    pivot of 1 (the row ``v = 0`` of a stuck dashpot) gives an exact row of ``inv``."""
    n = LU.shape[0]
    for c in range(n):
        for r in range(n):
            b[r] = 0.0
        b[c] = 1.0
        lu_solve_into(LU, perm, b, y)
        for r in range(n):
            inv[r, c] = y[r]


@njit(cache=True, inline="always")
def copy_into(src, dst) -> None:
    """``dst[:n] = src`` for a vector ``src`` of length ``n``, element by element."""
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True, inline="always")
def copy_matrix_into(src, dst) -> None:
    """``dst[:n, :m] = src`` for an ``n x m`` matrix ``src``, element by element.

    (A row assignment ``dst[i] = src[i]`` would compile numba's broadcasting checks and
    their error messages, about a second of a first run's compile.)"""
    for i in range(src.shape[0]):
        for j in range(src.shape[1]):
            dst[i, j] = src[i, j]
