r"""The semismooth Newton of :mod:`lumped.solvers.newton.semismooth`, written for numba.

The same algorithm, step for step and operation for operation, as
:func:`lumped.solvers.newton.semismooth.newton_solve` with its
:class:`~lumped.solvers.newton.linalg.FactorCache` (read that module for the maths: the
residual test ``|G_i| <= rtol S_i + atol``, the update test, the directional retry at a
kink, the update test scaled by the terms an unknown enters, the round-off test, the
watchdog ``free_steps`` and the backtracking line search on the merit
``max_i |G_i| / (S_i + atol / rtol)``), and the LU factorisation with singleton-row pivots of
:func:`lumped.solvers.newton.linalg.lu_factor` (a stuck dashpot's row ``v = 0`` gives
``v = 0`` exactly: eq. (19) of the paper comes out exact). The differences are only in
the data layout:

* every vector and matrix is a preallocated numpy array (no allocation inside a step);
  :func:`workspace` returns them;
* the system is a callback ``evaluate(u, p, G, J, S, roundoff)`` that writes the
  residual, the generalised Jacobian and the row scales in place (``p``: the step's
  parameters, see :mod:`lumped.codegen.jit`);
* systems of any size use the small LU of :mod:`lumped.solvers.newton.linalg_jit` (the
  pure-Python solver hands systems above 8 unknowns to LAPACK, so there the two agree to
  round-off, not bit for bit).

Everything is compiled here and cached on disk; the scene's ``evaluate`` comes in as a
function pointer (see :mod:`lumped.solvers.bdf.core_jit`), so one compiled Newton serves
every scene. Without numba (or with ``NUMBA_DISABLE_JIT=1``) everything runs as plain
Python, slowly, with the same results.

Return codes (:data:`CODE_NAMES`): 0 success, 1 max_iters, 2 diverged, 3 singular,
4 non_finite, the values of :class:`lumped.solvers.newton.options.NewtonCode`.

This module owns the iteration (:func:`newton`), its return codes and its workspace
layout; the compiled LU is in :mod:`lumped.solvers.newton.linalg_jit`, the compiled
convergence tests in :mod:`lumped.solvers.newton.criteria_jit`.
"""

from __future__ import annotations

import numpy as np

from ...codegen.jit import njit
from .criteria_jit import (
    at_roundoff,
    finite_matrix,
    finite_matrix_rows,
    finite_sum,
    hair,
    merit,
    residual_ok,
    same,
    update_ok,
    update_ok_scaled,
)
from .linalg_jit import copy_into, copy_matrix_into, lu_factor_into, lu_solve_into

__all__ = [
    "CODE_NAMES",
    "N_VECTORS",
    "N_MATRICES",
    "workspace",
    "newton",
]

#: Return code -> :class:`lumped.solvers.newton.options.NewtonCode` value.
CODE_NAMES = ("success", "max_iters", "diverged", "singular", "non_finite")
SUCCESS, MAX_ITERS, DIVERGED, SINGULAR, NON_FINITE = 0, 1, 2, 3, 4

# rows of the vector workspace
(WS_G, WS_S, WS_DU, WS_UN, WS_GN, WS_SN, WS_UA, WS_GA, WS_SA, WS_PR, WS_GD, WS_SD, WS_D2, WS_UC,
 WS_GC, WS_SC) = range(16)
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
                    copy_matrix_into(Jc, J)
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
            if at_roundoff(G, S):
                # the rows the full correction does not reduce are solved: the
                # correction without them decides
                un, Gn, Sn, Jn = wv[WS_UN], wv[WS_GN], wv[WS_SN], wm[WS_JN]
                for i in range(n):
                    un[i] = u[i] - du[i]
                evaluate(un, p, Gn, Jn, Sn, roundoff)
                n_res += 1
                if finite_sum(Gn):
                    Gk = wv[WS_GA]
                    kept = False
                    for i in range(n):
                        if abs(Gn[i]) >= abs(G[i]):
                            Gk[i] = 0.0
                            kept = kept or G[i] != 0.0
                        else:
                            Gk[i] = G[i]
                    if kept:
                        d4 = wv[WS_D2]
                        lu_solve_into(cLU, cperm, Gk, d4)
                        if finite_sum(d4) and (update_ok(d4, u, rtol, atol) or
                                               update_ok_scaled(d4, u, J, S, rtol, atol)):
                            for i in range(n):
                                u[i] = u[i] - d4[i]
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
                    copy_matrix_into(Ja, Jn)
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
            copy_matrix_into(Jn, J)
            iters += 1
            code = DIVERGED
            break
        have_prev = True
        copy_matrix_into(J, wm[WS_JC])  # J_prev
        copy_into(un, u)
        copy_into(Gn, G)
        copy_into(Sn, S)
        copy_matrix_into(Jn, J)
        norm = -1.0
        iters += 1
    counts[0] = iters
    counts[1] = n_res
    counts[2] = n_jac
    counts[3] = n_fact
    return code
