r"""The semismooth Newton of :mod:`lumped.solvers.newton.semismooth`, written for numba.

The same algorithm, step for step and operation for operation, as
:func:`lumped.solvers.newton.semismooth.newton_solve` with its :class:`FactorCache` (read that
module for the maths: the residual test ``|G_i| <= rtol S_i + atol``, the update test,
the directional retry at a kink, the update test scaled by the terms an unknown enters,
the watchdog ``free_steps`` and the backtracking line search on the merit
``max_i |G_i| / (S_i + atol / rtol)``), and the LU factorisation with singleton-row
pivots of :func:`lumped.solvers.newton.linalg.lu_factor` (a stuck dashpot's row ``v = 0`` gives
``v = 0`` exactly: eq. (19) of the paper comes out exact). The differences are only in
the data layout:

* every vector and matrix is a preallocated numpy array (no allocation inside a step);
  :func:`workspace` returns them;
* the system is a callback ``evaluate(u, p, G, J, S, roundoff)`` that writes the
  residual, the generalised Jacobian and the row scales in place (``p``: the step's
  parameters, see :mod:`lumped.codegen.jit`);
* systems of any size use the small LU below (the pure-Python solver hands systems above
  8 unknowns to LAPACK, so there the two agree to round-off, not bit for bit).

Everything is compiled here and cached on disk; the scene's ``evaluate`` comes in as a
function pointer (see :mod:`lumped.solvers.bdf.core_jit`), so one compiled Newton serves
every scene. Without numba (or with ``NUMBA_DISABLE_JIT=1``) everything runs as plain
Python, slowly, with the same results.

Return codes (:data:`CODE_NAMES`): 0 success, 1 max_iters, 2 diverged, 3 singular,
4 non_finite, the values of :class:`lumped.solvers.newton.semismooth.NewtonCode`.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.jit import njit

__all__ = [
    "CODE_NAMES",
    "N_VECTORS",
    "N_MATRICES",
    "workspace",
    "lu_factor_into",
    "lu_solve_into",
    "inverse_into",
    "newton",
]

#: Return code -> :class:`lumped.solvers.newton.semismooth.NewtonCode` value.
CODE_NAMES = ("success", "max_iters", "diverged", "singular", "non_finite")
SUCCESS, MAX_ITERS, DIVERGED, SINGULAR, NON_FINITE = 0, 1, 2, 3, 4

# rows of the vector workspace
WS_G, WS_S, WS_DU, WS_UN, WS_GN, WS_SN, WS_UA, WS_GA, WS_SA, WS_PR, WS_GD, WS_SD, WS_D2, WS_UC, WS_GC, WS_SC = range(16)
#: Vectors in the workspace of :func:`newton`.
N_VECTORS = 16
# matrices of the matrix workspace
WS_J, WS_JN, WS_JA, WS_JD, WS_JC, WS_LUD = range(6)
#: Matrices in the workspace of :func:`newton`.
N_MATRICES = 6


def workspace(n: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Zeroed ``(vectors, matrices, perm)`` arrays for :func:`newton` on ``n`` unknowns."""
    return (np.zeros((N_VECTORS, n)), np.zeros((N_MATRICES, n, n)),
            np.zeros(n, dtype=np.int64))


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
def copy_into(src, dst) -> None:
    for i in range(src.shape[0]):
        dst[i] = src[i]


@njit(cache=True, inline="always")
def residual_ok(G, S, rtol: float, atol: float) -> bool:
    for i in range(G.shape[0]):
        if not abs(G[i]) <= rtol * S[i] + atol:
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
    ``_update_ok_scaled``)."""
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


@njit(cache=True)
def newton(evaluate, p, u, roundoff, rtol, atol, max_iters, max_backtracks, free_steps,
           cJ, cLU, cperm, cvalid, wv, wm, wperm, counts):
    """Solve ``G(u) = 0`` in place from ``u`` (the reference's ``newton_solve``).

    Parameters
    ----------
    evaluate : callable
        ``evaluate(u, p, G, J, S, roundoff)`` writes residual, Jacobian and row scales.
    p : ndarray
        Parameters handed to ``evaluate``.
    u : ndarray
        Initial guess, overwritten with the last iterate.
    cJ, cLU, cperm, cvalid : ndarray
        The factor cache (its Jacobian, factors, permutation, and ``cvalid[0]`` set once
        it holds factors); shared by consecutive solves with the same ``p[0]`` (step).
    wv, wm, wperm : ndarray
        Workspace from :func:`workspace`. On return ``wv[0]`` holds ``G(u)``, ``wv[1]`` the
        row scales and ``wm[0]`` the Jacobian.
    counts : ndarray of int64
        Receives ``iterations, residual_evals, jacobian_evals, factorizations``.

    Returns
    -------
    int
        The code (0 success, see the module notes).
    """
    n = u.shape[0]
    G, S, du = wv[WS_G], wv[WS_S], wv[WS_DU]
    J = wm[WS_J]
    evaluate(u, p, G, J, S, roundoff)
    n_res = 1
    n_jac = 0
    n_fact = 0
    iters = 0
    code = SUCCESS
    if not (finite_sum(G) and finite_sum(u)):
        code = NON_FINITE
    floor = atol / rtol
    norm = -1.0
    have_prev = False
    while code == SUCCESS:
        if not finite_matrix(J):
            code = NON_FINITE
            break
        res_ok = residual_ok(G, S, rtol, atol)
        # J_prev is wm[WS_JC]; its factors are the cache's (stored in that iteration)
        if res_ok and have_prev and same(J, wm[WS_JC]):
            lu_solve_into(cLU, cperm, G, wv[WS_D2])
            if finite_sum(wv[WS_D2]) and update_ok(wv[WS_D2], u, rtol, atol):
                for i in range(n):
                    u[i] = u[i] - wv[WS_D2][i]
                break
        n_jac += 1
        if not (cvalid[0] == 1 and same(cJ, J)):
            n_fact += 1
            if not lu_factor_into(J, cLU, cperm):
                cvalid[0] = 0
                code = SINGULAR
                break
            for i in range(n):
                for j in range(n):
                    cJ[i, j] = J[i, j]
            cvalid[0] = 1
        lu_solve_into(cLU, cperm, G, du)
        if not finite_sum(du):
            code = NON_FINITE
            break
        if res_ok:
            if update_ok(du, u, rtol, atol):
                uc = wv[WS_UC]
                for i in range(n):
                    uc[i] = u[i] - du[i]
                if have_prev and not same(J, wm[WS_JC]):
                    # wm[WS_JC] holds J_prev here (see the end of the loop)
                    Gc, Sc, Jc = wv[WS_GC], wv[WS_SC], wm[WS_JN]
                    evaluate(uc, p, Gc, Jc, Sc, roundoff)
                    n_res += 1
                    if not same(Jc, J) and not (finite_sum(Gc) and residual_ok(Gc, Sc, rtol,
                                                                                atol)):
                        break
                    copy_into(Gc, G)
                    copy_into(Sc, S)
                    copy_into(Jc, J)
                copy_into(uc, u)
                break
            # directional retry: the Jacobian of the piece the step points into
            probe = wv[WS_PR]
            for i in range(n):
                probe[i] = hair(u[i], du[i])
            Jd = wm[WS_JD]
            evaluate(probe, p, wv[WS_GD], Jd, wv[WS_SD], roundoff)
            n_res += 1
            if not same(Jd, J) and finite_matrix_rows(Jd):
                n_jac += 1
                n_fact += 1
                if lu_factor_into(Jd, wm[WS_LUD], wperm):
                    d2 = wv[WS_D2]
                    lu_solve_into(wm[WS_LUD], wperm, G, d2)
                    if finite_sum(d2) and update_ok(d2, u, rtol, atol):
                        for i in range(n):
                            u[i] = u[i] - d2[i]
                        break
            if update_ok_scaled(du, u, J, S, rtol, atol):
                for i in range(n):
                    u[i] = u[i] - du[i]
                break
        if iters >= max_iters:
            code = MAX_ITERS
            break
        lam = 1.0
        if iters >= free_steps and norm < 0.0:
            norm = merit(G, S, floor)
        un, Gn, Sn, Jn = wv[WS_UN], wv[WS_GN], wv[WS_SN], wm[WS_JN]
        accepted = False
        for _ in range(max_backtracks + 1):
            if lam == 1.0:
                for i in range(n):
                    un[i] = u[i] - du[i]
            else:
                for i in range(n):
                    un[i] = u[i] - lam * du[i]
            evaluate(un, p, Gn, Jn, Sn, roundoff)
            n_res += 1
            if (lam == 1.0 and not same(Jn, J) and finite_sum(Gn)
                    and not residual_ok(Gn, Sn, rtol, atol)):
                ua, Ga, Sa, Ja = wv[WS_UA], wv[WS_GA], wv[WS_SA], wm[WS_JA]
                for i in range(n):
                    ua[i] = u[i] - (1.0 - 1e-12) * du[i]
                evaluate(ua, p, Ga, Ja, Sa, roundoff)
                n_res += 1
                if finite_sum(Ga) and residual_ok(Ga, Sa, rtol, atol):
                    copy_into(ua, un)
                    copy_into(Ga, Gn)
                    copy_into(Sa, Sn)
                    copy_into(Ja, Jn)
            if finite_sum(Gn):
                if iters < free_steps or residual_ok(Gn, Sn, rtol, atol):
                    accepted = True
                    break
                if merit(Gn, S, floor) <= (1.0 - 1e-4 * lam) * norm:
                    accepted = True
                    break
            lam *= 0.5
        if not accepted:
            if not finite_sum(Gn):
                code = NON_FINITE
                break
            copy_into(un, u)
            copy_into(Gn, G)
            copy_into(Sn, S)
            copy_into(Jn, J)
            iters += 1
            code = DIVERGED
            break
        have_prev = True
        copy_into(J, wm[WS_JC])  # J_prev
        copy_into(un, u)
        copy_into(Gn, G)
        copy_into(Sn, S)
        copy_into(Jn, J)
        norm = -1.0
        iters += 1
    counts[0] = iters
    counts[1] = n_res
    counts[2] = n_jac
    counts[3] = n_fact
    return code


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
