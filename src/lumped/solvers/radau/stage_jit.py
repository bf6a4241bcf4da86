r"""The Radau IIA stage system and its Newton solve, compiled with numba.

A port, operation for operation, of :meth:`lumped.solvers.radau.stage.StageSystem.evaluate`
and :meth:`~lumped.solvers.radau.stage.StageSystem.solve` (the adaptive method ``radau5``,
read them for the maths): the stage residual of the scene's DAE with every element held
on one smooth branch (its *mode*), ``U[k*n + i] = V_k,i`` for a node, ``U[k*n + N + e] =
F_k,e`` for an element (``n = N + E``, stages ``k = 0, 1, 2``)::

    m_i / h sum_l w_kl (V_l,i - v_n,i) - net_i(t_n + c_k h, F_k) = 0   (masses)
                                     - net_i(t_n + c_k h, F_k) = 0   (junctions)
    R_e^{(b_e)}(q_e(X_k, V_k), F_k,e) = 0,   X_k = x_n + h sum_l a_kl V_l

and simplified Newton on it (converged when ``max_j |dU_j| / scale_j <= tol``, a junction's
velocity also at its round-off,
:func:`~lumped.solvers.radau.roundoff_jit.roundoff_worst_jit`; the Jacobian refactored
when the contraction rate exceeds 1/2). Same LU as the reference (singleton rows first), so
the two give the same numbers bit for bit.

The scene's branch kernels come in as a function pointer, ``branch_law(e, i, q, F, lawc)`` of
the scene's generated module (:mod:`lumped.codegen.jit`), so the step is compiled once
for every scene (:func:`compiled_stage_solve`, cached on disk). The Butcher matrix ``A``
and ``W = A^{-1}`` are arguments (``numpy`` arrays of the reference's constants).
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.function_types import BRANCH_LAW_TYPE, compiled_address, function_at
from ...codegen.jit import njit, numba_enabled
from ..newton.linalg_jit import lu_factor_into, lu_solve_into
from .roundoff_jit import roundoff_worst_jit

__all__ = ["BRANCH_LAW_TYPE", "stage_evaluate", "stage_solve", "compiled_stage_solve",
           "roundoff_test", "with_impact_sign", "stage_solve_at", "stage_address", "STAGE_TYPE"]


@njit(cache=True)
def stage_evaluate(branch_law, lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h, x_n, v_n,
                   f, G, J) -> None:
    """Residual ``G`` and Jacobian ``J`` of the stage system at ``U`` (``f[k, i]``: the
    external force on node ``i`` at stage ``k``; ``modes[e]``: element ``e``'s branch;
    ``lock_q[e, i]``: the elongation branch ``i`` of spring ``e`` locks, ``nan`` if none,
    :func:`lumped.codegen.jit.position_locks`)."""
    N = masses.shape[0]
    E = ea.shape[0]
    n = N + E
    for r in range(3 * n):
        G[r] = 0.0
        for c in range(3 * n):
            J[r, c] = 0.0
    for k in range(3):
        base = k * n
        for i in range(N):
            m = masses[i]
            if m > 0.0:
                acc = 0.0
                for j in range(3):
                    acc += W[k, j] * (U[j * n + i] - v_n[i])
                    J[base + i, j * n + i] = m / h * W[k, j]
                G[base + i] = m / h * acc - f[k, i]
            else:
                G[base + i] = -f[k, i]
        for e in range(E):
            col = base + N + e
            Fe = U[col]
            a = ea[e]
            b = eb[e]
            if a >= 0:
                G[base + a] -= Fe
                J[base + a, col] = -1.0
            if b >= 0:
                G[base + b] += Fe
                J[base + b, col] = 1.0
            qa = 0.0
            qb = 0.0
            lock = lock_q[e, modes[e]] if spring[e] else math.nan
            if lock == lock:  # a held position lock: on the velocity level
                if b >= 0:
                    for j in range(3):
                        qb += A[k, j] * U[j * n + b]
                if a >= 0:
                    for j in range(3):
                        qa += A[k, j] * U[j * n + a]
            elif spring[e]:
                if b >= 0:
                    s = 0.0
                    for j in range(3):
                        s += A[k, j] * U[j * n + b]
                    qb = x_n[b] + h * s
                if a >= 0:
                    s = 0.0
                    for j in range(3):
                        s += A[k, j] * U[j * n + a]
                    qa = x_n[a] + h * s
            else:
                qb = U[base + b] if b >= 0 else 0.0
                qa = U[base + a] if a >= 0 else 0.0
            if lock == lock:  # R(L + dq) = R(L) + dR/dq dq: an affine lock, exactly
                R, Rq, RF = branch_law(e, modes[e], lock, Fe, lawc)
                R += Rq * (h * (qb - qa))
            else:
                R, Rq, RF = branch_law(e, modes[e], qb - qa, Fe, lawc)
            G[col] = R
            J[col, col] = RF
            if spring[e]:
                for j in range(3):
                    g = Rq * h * A[k, j]
                    if b >= 0:
                        J[col, j * n + b] += g
                    if a >= 0:
                        J[col, j * n + a] -= g
            else:
                if b >= 0:
                    J[col, base + b] += Rq
                if a >= 0:
                    J[col, base + a] -= Rq


def stage_solve(branch_law, lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h, x_n, v_n, f,
                scale, tol, max_iters, G, J, LU, perm, b, du, out) -> bool:
    """Simplified Newton on the stage system from ``U`` (overwritten); ``out`` receives
    ``(iterations, factorisations, singular)`` (``out[2] = 1`` when a factorisation
    failed: a singular or non-finite Jacobian, left in ``J``). Returns False when Newton
    failed (singular, non-finite or no convergence): the caller shrinks the step.

    ``out[3]`` (read) is the address of :func:`roundoff_worst_jit` compiled
    (:func:`roundoff_test`; :func:`workspace` puts it there), negated on the first step
    after an impact (its ``after_impact``: :func:`with_impact_sign`), or 0 for a scene without
    junctions (``m_i = 0``), where that test returns ``worst`` as it is: the shared loop
    of ``radau5`` passes 0 there, and a machine whose scenes have no junction never
    compiles it."""
    out[2] = 0
    stage_evaluate(branch_law, lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h, x_n, v_n, f,
                   G, J)
    ok = lu_factor_into(J, LU, perm)
    nfac = 1
    prev = math.inf
    size = U.shape[0]
    for it in range(1, max_iters + 1):
        out[0] = it
        out[1] = nfac
        if not ok:
            out[2] = 1
            return False
        for j in range(size):
            b[j] = -G[j]
        lu_solve_into(LU, perm, b, du)
        worst = 0.0
        for j in range(size):
            d = du[j]
            U[j] += d
            r = abs(d) / scale[j]
            if not r <= worst:
                worst = r
        if not math.isfinite(worst):
            return False
        if worst <= tol:
            return True
        stage_evaluate(branch_law, lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h, x_n,
                       v_n, f, G, J)
        if out[3] != 0:  # a junction's velocity at its round-off (none without junctions)
            worst = _roundoff_at(abs(out[3]))(du, U, J, scale, masses, spring, f, tol, worst,
                                              h, out[3] < 0)
        if worst <= tol:
            return True
        if worst > 0.5 * prev:
            ok = lu_factor_into(J, LU, perm)
            nfac += 1
        prev = worst
    out[0] = max_iters
    out[1] = nfac
    return False


_COMPILED: list = []
_solve = njit(cache=True, inline="always")(stage_solve)


def stage_solve_at(law_addr, lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h, x_n, v_n,
                   f, scale, tol, max_iters, G, J, LU, perm, b, du, out) -> bool:
    """:func:`stage_solve` on the scene's ``branch_law`` at ``law_addr``
    (:func:`lumped.codegen.function_types.function_at`), compiled apart
    (:func:`stage_address`): the shared loop calls it through its address, so the loop's
    own module holds none of its code."""
    return _solve(_law_at(law_addr), lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h,
                  x_n, v_n, f, scale, tol, max_iters, G, J, LU, perm, b, du, out)


def compiled_stage_solve():
    """:func:`stage_solve` compiled once for every scene (from numba's disk cache after
    the first time on a machine); the plain function without numba."""
    if not numba_enabled():
        return stage_solve
    if not _COMPILED:
        from numba import types as T

        v, m = T.float64[::1], T.float64[:, ::1]
        iv = T.int64[::1]
        sig = T.boolean(BRANCH_LAW_TYPE, v, v, iv, iv, T.boolean[::1], m, iv, m, m, v, T.float64,
                        v, v, m, v, T.float64, T.int64, v, m, m, iv, v, v, iv)
        _COMPILED.append(njit(sig, cache=True)(stage_solve))
    return _COMPILED[0]


def workspace(N: int, E: int) -> tuple[np.ndarray, ...]:
    """``(G, J, LU, perm, b, du, out)`` for :func:`stage_solve` on ``N`` nodes and ``E``
    elements (``out``: 3 counters and :func:`roundoff_test`)."""
    s = 3 * (N + E)
    out = np.array([0, 0, 0, roundoff_test()], dtype=np.int64)
    return (np.zeros(s), np.zeros((s, s)), np.zeros((s, s)), np.zeros(s, dtype=np.int64),
            np.zeros(s), np.zeros(s), out)


if numba_enabled():
    from numba import types as _T

    _v, _m = _T.float64[:], _T.float64[:, :]  # (any layout: the loop passes views)
    #: The numba function type of :func:`roundoff_worst_jit`.
    ROUNDOFF_TYPE = _T.FunctionType(_T.float64(_v, _v, _m, _v, _v, _T.boolean[:], _m,
                                               _T.float64, _T.float64, _T.float64,
                                               _T.boolean))
    _roundoff_at = function_at(ROUNDOFF_TYPE)
    _law_at = function_at(BRANCH_LAW_TYPE)
    _vc, _ma, _iv = _T.float64[::1], _T.float64[:, ::1], _T.int64[::1]
    #: The numba function type of :func:`stage_solve_at` (the loop's views: 1-D slices
    #: contiguous, 2-D ones of any layout).
    STAGE_TYPE = _T.FunctionType(_T.boolean(
        _T.int64, _vc, _vc, _iv, _iv, _T.boolean[::1], _ma, _iv, _ma, _ma, _vc, _T.float64, _vc,
        _vc, _m, _vc, _T.float64, _T.int64, _vc, _m, _m, _iv, _vc, _vc, _iv))
else:  # pragma: no cover - without numba: the address 1 stands for the Python function
    ROUNDOFF_TYPE = STAGE_TYPE = None

    def _roundoff_at(addr):
        return roundoff_worst_jit
_ROUNDOFF: list = []


def roundoff_test() -> int:
    """The address of :func:`roundoff_worst_jit` compiled (once per process; numba's disk
    cache after the first time on a machine), 1 without numba (the Python function)."""
    if not numba_enabled():
        return 1
    return compiled_address(_ROUNDOFF, roundoff_worst_jit.py_func, ROUNDOFF_TYPE)


def with_impact_sign(address: int, after_impact: bool) -> int:
    """The round-off test's ``address`` as :func:`stage_solve` reads it from ``out[3]``:
    negated on the first step after an impact (``after_impact`` of
    :func:`roundoff_worst_jit`), ``0`` (no junctions) kept."""
    return -abs(address) if after_impact else abs(address)


_STAGE: list = []


def stage_address() -> int:
    """The address of :func:`stage_solve_at` compiled (once per process; numba's disk cache
    after the first time on a machine), for the shared loop of ``radau5``
    (:func:`lumped.solvers.eventdriven.loop_jit.advance`)."""
    return compiled_address(_STAGE, stage_solve_at, STAGE_TYPE)
