r"""The compiled pieces of one Radau IIA step of ``radau5`` (for
:mod:`lumped.solvers.eventdriven.loop_jit`): the error estimate and its norm, the guard test on
the collocation polynomial, the fold test (the forcing: :mod:`lumped.solvers.radau.forces_jit`).

Ports, operation for operation, of :meth:`lumped.solvers.radau.error.ErrorEstimate.error`,
:meth:`~lumped.solvers.radau.error.ErrorEstimate.error_norm`,
:meth:`lumped.solvers.radau.stage.StageSystem.element_nodes`,
:func:`lumped.solvers.modes.crossing_root.first_root_py` (only the test that some sample
is negative) and :func:`lumped.solvers.modes.guards.fold_crossed`; the unknowns are laid out as in
:mod:`lumped.solvers.radau.stage` (``U[k*n + i]`` a node's stage velocity, ``U[k*n + N + e]`` an
element's stage force). The scene's kernels, ``branch_law(e, i, q, F, lawc)`` and
``branch_guards(e, i, q, F, out, lawc)`` of :mod:`lumped.codegen.jit`, come in as
functions, or as their addresses (:func:`lumped.codegen.function_types.function_at`) in
:func:`step_error` and :func:`crossed`: those two are compiled apart, once per machine
(:func:`error_address`, :func:`crossed_address`), and the loop calls them through their
addresses, so that LLVM optimises and emits their code once, not again inside the loop's
module.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.function_types import compiled_address, function_at, guards_type, law_type
from ...codegen.jit import njit, numba_enabled
from ..implicit.branch_check_jit import dead_band_sign, sign_bit
from ..newton.linalg_jit import lu_factor_into, lu_solve_into
from .error import FORCE_TOL_FACTOR
from .forces_jit import forces
from .tableau import E_ERR, MU_REAL, SAMPLES, C

__all__ = ["element_nodes", "folded", "folded_at", "fold_test", "crossed", "step_error",
           "start_time", "finite", "error_address", "crossed_address"]

_C0, _C1, _C2 = C
_E0, _E1, _E2 = E_ERR
_SAMPLES = tuple(SAMPLES)
# the denominators of radau.dense_weights
_D1 = _C0 * (_C0 - _C1) * (_C0 - _C2)
_D2 = _C1 * (_C1 - _C0) * (_C1 - _C2)
_D3 = _C2 * (_C2 - _C0) * (_C2 - _C1)


@njit(cache=True)
def _elem_at(spring, A, h, x_n, v_n, U, n, i, k) -> float:
    """Node ``i``'s position (spring) or velocity at polynomial node ``k`` (-1: the
    start), 0 for the ground (:meth:`StageSystem.element_nodes`)."""
    if i < 0:
        return 0.0
    if spring:
        if k < 0:
            return x_n[i]
        return x_n[i] + h * (A[k, 0] * U[i] + A[k, 1] * U[n + i] + A[k, 2] * U[2 * n + i])
    return v_n[i] if k < 0 else U[k * n + i]


@njit(cache=True)
def element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, e, q, F) -> None:
    """``q`` and ``F`` of element ``e`` at ``s = 0, c_1, c_2, 1`` into ``q[:4]``,
    ``F[:4]`` (:meth:`StageSystem.element_nodes`)."""
    for k in range(4):
        q[k] = (_elem_at(spring[e], A, h, x_n, v_n, U, n, eb[e], k - 1)
                - _elem_at(spring[e], A, h, x_n, v_n, U, n, ea[e], k - 1))
    F[0] = F_n[e]
    for k in range(3):
        F[k + 1] = U[k * n + N + e]


@njit(cache=True)
def folded(branch_law, lawc, ea, eb, spring, modes, checked, A, h, x_n, v_n, F_n, U, N, n, q,
            F) -> bool:
    """A checked element's law crosses a fold along the step
    (:func:`lumped.solvers.modes.guards.fold_crossed` on the held branch's kernel)."""
    for c in range(checked.shape[0]):
        e = checked[c]
        element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, e, q, F)
        _, Rq0, RF0 = branch_law(e, modes[e], q[0], F[0], lawc)
        for k in range(3):
            _, Rq1, RF1 = branch_law(e, modes[e], q[k + 1], F[k + 1], lawc)
            if _left_branch(branch_law, lawc, e, modes[e], q[k], F[k], Rq0, RF0, q[k + 1],
                            F[k + 1], Rq1, RF1):
                return True
            Rq0, RF0 = Rq1, RF1
    return False


def folded_at(law_addr, lawc, ea, eb, spring, modes, checked, A, h, x_n, v_n, F_n, U, N, n, q,
              F) -> bool:
    """:func:`folded` on the scene's ``branch_law`` at ``law_addr``, compiled apart
    (:func:`fold_test`): the compiled loop calls it through its address, so it is compiled
    only for a scene with a law that is not a known monotone one."""
    return folded(_law_at(law_addr), lawc, ea, eb, spring, modes, checked, A, h, x_n, v_n, F_n,
                  U, N, n, q, F)


if numba_enabled():
    _law_at = function_at(law_type())
    _guards_at = function_at(guards_type())
    from numba import types as _T

    _f8, _i8, _v = _T.float64, _T.int64, _T.float64[::1]
    _iv, _b, _mc, _ma = _i8[::1], _T.boolean[::1], _f8[:, ::1], _f8[:, :]
    #: The numba function type of :func:`folded_at`.
    FOLDED_TYPE = _T.FunctionType(_T.boolean(
        _i8, _v, _iv, _iv, _b, _iv, _iv, _mc, _f8, _v, _v, _v, _v, _i8, _i8, _f8[:], _f8[:]))
    #: The numba function type of :func:`step_error`.
    ERROR_TYPE = _T.FunctionType(_f8(
        _i8, _v, _v, _iv, _iv, _b, _iv, _iv, _mc, _v, _f8, _f8, _v, _v, _v, _v, _i8, _iv, _mc,
        _i8, _v, _f8, _f8, _f8, _ma, _ma, _iv, _v, _v, _f8))
    #: The numba function type of :func:`crossed`.
    CROSSED_TYPE = _T.FunctionType(_T.boolean(
        _i8, _v, _iv, _iv, _b, _iv, _iv, _mc, _f8, _v, _v, _v, _v, _i8, _i8, _ma, _ma, _v))
else:  # pragma: no cover - without numba
    FOLDED_TYPE = ERROR_TYPE = CROSSED_TYPE = None
_FOLD: list = []


def fold_test() -> int:
    """The address of :func:`folded_at` compiled (once per process; numba's disk cache after
    the first time on a machine), for :func:`lumped.solvers.eventdriven.loop_jit.advance`."""
    return compiled_address(_FOLD, folded_at, FOLDED_TYPE)


@njit(cache=True)
def _left_branch(branch_law, lawc, e, mode, q0, F0, Rq0, RF0, q1, F1, Rq1, RF1) -> bool:
    """:func:`lumped.solvers.bdf.core_jit.left_branch` (the fold test of
    :mod:`lumped.solvers.implicit.branch_check`) on element ``e``'s branch ``mode``."""
    s0 = abs(Rq0) + abs(RF0)
    s1 = abs(Rq1) + abs(RF1)
    mq = _bit(Rq0, s0) | _bit(Rq1, s1)
    mf = _bit(RF0, s0) | _bit(RF1, s1)
    if mq == 3 or mf == 3:
        return True
    dq = q1 - q0
    dF = F1 - F0
    off = 0.0
    for k in range(2):
        Rq = Rq0 if k == 0 else Rq1
        RF = RF0 if k == 0 else RF1
        total = abs(Rq * dq) + abs(RF * dF)
        if total > 0.0:
            off = max(off, abs(Rq * dq + RF * dF) / total)
    if off <= 0.5:
        return False
    for s in (0.25, 0.5, 0.75):
        _, Rq, RF = branch_law(e, mode, q0 + s * dq, F0 + s * dF, lawc)
        sc = abs(Rq) + abs(RF)
        mq |= _bit(Rq, sc)
        mf |= _bit(RF, sc)
        if mq == 3 or mf == 3:
            return True
    return False


@njit(cache=True)
def _bit(x, scale) -> int:
    """The sign bit of ``x`` with a dead band (``sign_bit(dead_band_sign(x, scale))``),
    called: its two helpers are inlined at numba's IR level, once here rather than at
    each of :func:`_left_branch`'s ten uses (a second of a first run's compile)."""
    return sign_bit(dead_band_sign(x, scale))


def crossed(guards_addr, lawc, ea, eb, spring, modes, watched, A, h, x_n, v_n, F_n, U, N, n,
            qn, Fn, gbuf) -> bool:
    """True when a watched guard (shifted by its round-off tolerance) is negative at a
    sample of the step: :func:`lumped.solvers.modes.crossing_root.first_root_py`'s test, on
    the scene's ``branch_guards`` at ``guards_addr``. Compiled apart
    (:func:`crossed_address`): the shared loop calls it through its address."""
    branch_guards = _guards_at(guards_addr)
    for w in range(watched.shape[0]):
        element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, watched[w], qn[w], Fn[w])
    for s in _SAMPLES:
        l1 = s * (s - _C1) * (s - _C2) / _D1
        l2 = s * (s - _C0) * (s - _C2) / _D2
        l3 = s * (s - _C0) * (s - _C1) / _D3
        for w in range(watched.shape[0]):
            e = watched[w]
            q0 = qn[w, 0]
            f0 = Fn[w, 0]
            qs = q0 + (l1 * (qn[w, 1] - q0) + l2 * (qn[w, 2] - q0) + l3 * (qn[w, 3] - q0))
            Fs = f0 + (l1 * (Fn[w, 1] - f0) + l2 * (Fn[w, 2] - f0) + l3 * (Fn[w, 3] - f0))
            tol = 64.0 * 2.220446049250313e-16 * (1.0 + abs(qs) + abs(Fs))
            count = branch_guards(e, modes[e], qs, Fs, gbuf, lawc)
            for j in range(count):
                if gbuf[j] + tol < 0.0:
                    return True
    return False


@njit(cache=True)
def finite(J) -> bool:
    for r in range(J.shape[0]):
        for c in range(J.shape[1]):
            if not math.isfinite(J[r, c]):
                return False
    return True


@njit(cache=True, inline="always")
def start_time(t, prev_break) -> float:
    """Where the step from ``t`` reads the forcing: right after a breakpoint, ``t`` else."""
    return np.nextafter(t, math.inf) if t == prev_break else t


def step_error(law_addr, lawc, masses, ea, eb, spring, modes, watched, A, U, h, t_n0, x_n, v_n,
               F_n, dF, have_dF, fkind, fpar, table, net_n, rtol, atol, F_ref, M, LU, perm, rhs,
               err, two) -> float:
    """The scaled RMS error of the step from ``t`` (``StageSystem.error`` then
    ``error_norm``), the external forces read at ``t_n0`` (:func:`start_time`; ``fkind,
    fpar, table``: :func:`lumped.solvers.radau.forces_jit.forces`), on the scene's
    ``branch_law`` at ``law_addr``; NaN for a non-finite system, -1.0 for a singular
    finite one (Python's minimum norm). Compiled apart (:func:`error_address`): the shared
    loop calls it through its address.

    ``two`` is 2.0, a run-time value: CPython's ``y ** 2`` is the C library's ``pow``, which
    differs from ``y * y`` in the last bit now and then, and numba (LLVM) turns a constant
    exponent 2 into ``y * y``."""
    branch_law = _law_at(law_addr)
    forces(t_n0, fkind, fpar, table, net_n)
    for e in range(ea.shape[0]):
        if ea[e] >= 0:
            net_n[ea[e]] += F_n[e]
        if eb[e] >= 0:
            net_n[eb[e]] -= F_n[e]
    N = masses.shape[0]
    E = ea.shape[0]
    n = N + E
    size = 2 * N + E
    for r in range(size):
        rhs[r] = 0.0
        for c in range(size):
            M[r, c] = 0.0
    g = MU_REAL / h
    for i in range(N):
        zx = 0.0
        zv = 0.0
        for k in range(3):
            s = 0.0
            for j in range(3):
                s += A[k, j] * U[j * n + i]
            ek = _E0 if k == 0 else (_E1 if k == 1 else _E2)
            zx += ek * s
            zv += ek * (U[k * n + i] - v_n[i])
        M[i, i] = g
        M[i, N + i] = -1.0
        rhs[i] = v_n[i] + zx
        if masses[i] > 0.0:
            M[N + i, N + i] = g * masses[i]
            rhs[N + i] = net_n[i] + masses[i] * zv / h
    for e in range(E):
        col = 2 * N + e
        a = ea[e]
        b = eb[e]
        if a >= 0:
            M[N + a, col] -= 1.0
        if b >= 0:
            M[N + b, col] += 1.0
        # the element's q at the step's start (_elem_at at k = -1, written out: a literal
        # -1 there would compile a second _elem_at for the literal)
        y_n = x_n if spring[e] else v_n
        q_e = (y_n[b] if b >= 0 else 0.0) - (y_n[a] if a >= 0 else 0.0)
        _R, Rq, RF = branch_law(e, modes[e], q_e, F_n[e], lawc)
        off = 0 if spring[e] else N
        if b >= 0:
            M[col, off + b] -= Rq
        if a >= 0:
            M[col, off + a] += Rq
        M[col, col] = -RF
    if not lu_factor_into(M, LU, perm):
        for r in range(size):
            for c in range(size):
                if not math.isfinite(M[r, c]):
                    return math.nan
        return -1.0
    lu_solve_into(LU, perm, rhs, err)
    acc = 0.0
    cnt = 0
    for i in range(N):
        x_new = x_n[i] + h * (A[2, 0] * U[i] + A[2, 1] * U[n + i] + A[2, 2] * U[2 * n + i])
        sc = atol + rtol * max(abs(x_n[i]), abs(x_new))
        acc += (err[i] / sc) ** two
        cnt += 1
        if masses[i] > 0.0:
            sc = atol + rtol * max(abs(v_n[i]), abs(U[2 * n + i]))
            acc += (err[N + i] / sc) ** two
            cnt += 1
    if have_dF == 1:
        g0 = 1.0 / MU_REAL
        rtol_F = min(1e-3, FORCE_TOL_FACTOR * rtol)
        for w in range(watched.shape[0]):
            e = watched[w]
            k0 = N + e
            Fe = F_n[e]
            est = h * dF[e]
            est += _E0 * (U[k0] - Fe)
            est += _E1 * (U[n + k0] - Fe)
            est += _E2 * (U[2 * n + k0] - Fe)
            sc = rtol_F * max(abs(Fe), abs(U[2 * n + k0]), F_ref)
            acc += (g0 * est / sc) ** two
            cnt += 1
    return math.sqrt(acc / cnt)



_ERROR: list = []
_CROSSED: list = []


def error_address() -> int:
    """The address of :func:`step_error` compiled (once per process; numba's disk cache
    after the first time on a machine)."""
    return compiled_address(_ERROR, step_error, ERROR_TYPE)


def crossed_address() -> int:
    """The address of :func:`crossed` compiled, as :func:`error_address`."""
    return compiled_address(_CROSSED, crossed, CROSSED_TYPE)
