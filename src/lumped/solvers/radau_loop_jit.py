r"""The inner loop of ``radau5`` compiled with numba: consecutive steps with the modes held.

:func:`advance` takes Radau IIA steps from ``t`` towards the next stop (a forcing
breakpoint or ``t_end``) with every element held on its mode's branch, exactly as the
reference loop of :func:`lumped.solvers.adaptive.run_radau5` takes them, operation for
operation (the numbers agree bit for bit):

1. the stage Newton (:func:`lumped.solvers.radau_jit.stage_solve`) with the scales
   ``atol + rtol |v_i|`` and ``rtol max(|F_e|, F_ref)``, ``F_ref = max(F_seen, m_min
   (max |v| + atol / rtol) / h)``;
2. the filtered error estimate of RADAU5 and its norm (ports of
   :meth:`~lumped.solvers.radau.StageSystem.error` and
   :meth:`~lumped.solvers.radau.StageSystem.error_norm`): ``(mu / h M - J) e = f(y_n) + M
   sum_k E_k Z_k / h``, RMS of ``e / (atol + rtol max(|y_n|, |y_n+1|))`` over ``x``, the
   masses' ``v`` and the guarded elements' forces;
3. Gustafsson's predictive step control, ``h_new = h / max(quot, facgus)``;
4. the guards of the watched elements on the step's collocation polynomial at the
   samples ``s = k / 8`` of :data:`lumped.solvers.events.SAMPLES` (only *detected*: the
   root and the landing are the reference's);
5. the accepted step's dense-output record ``(t_n, h, y_n, Y_k - y_n)`` and its output row.

It returns to Python, with the state as at the top of the reference loop's pass that
must run next, when any of these holds (the code in ``ist[REASON]``): the next step
would reach the stop (:data:`STOP`), a guard turns negative in a candidate step
(:data:`CROSSING`: Python redoes that step and lands on the event), a checked law
(not a known monotone one) crosses a fold of its graph (:data:`FOLD`: Python redoes the
step and stops with its message), a Jacobian is
singular but finite (:data:`SINGULAR`: Python's minimum-norm solve), the step size is
below its floor (:data:`FLOOR`), the output arrays are full (:data:`FULL`),
``max_steps`` or the stall limit (:data:`LIMIT`).

State in and out: ``x, v, F, dF`` (arrays), ``fst`` (floats, indices ``T .. TWO``)
and ``ist`` (ints, indices ``HAVE_ACC .. REASON``).  The forcing is ``(fkind, fpar)`` of
:func:`lumped.solvers.bdf_jit_core.forcing_into` (kinds 0 none, 1 constant, 2 sine burst;
a tabulated forcing is not taken here).
"""

from __future__ import annotations

import math

import numpy as np

from ..codegen.jit import njit, numba_enabled
from .bdf_jit_core import _bit, _sign, forcing_into
from .events import SAMPLES
from .newton_jit import lu_factor_into, lu_solve_into
from .radau import E_ERR, END_SLOPES, FORCE_TOL_FACTOR, MU_REAL, C
from .radau_jit import stage_solve

__all__ = ["advance", "compiled_advance", "loop_workspace", "STOP", "CROSSING", "SINGULAR",
           "FLOOR", "FULL", "LIMIT", "REASONS", "law_type", "guards_type"]

# fst: float state
(T, H, F_SEEN, H_ACC, ERR_ACC, H_GOOD, T_STOP, T_FINAL, RTOL, ATOL, M_MIN, PREV_BREAK,
 TWO, A_ERR) = range(14)
# ist: int state and counters
(HAVE_ACC, HAVE_DF, STALLED, STEPS, REJECTED, NEWTON_ITERATIONS, FACTORIZATIONS, NFEV, NJEV,
 MAX_NEWTON_ITERATIONS, MAX_STEPS, N_OUT, REASON, SINGLE, A_ITS, A_NFAC, A_OK) = range(17)
STOP, CROSSING, SINGULAR, FLOOR, FULL, LIMIT, ATTEMPT, FOLD = range(1, 9)
REASONS = {STOP: "stop", CROSSING: "crossing", SINGULAR: "singular", FLOOR: "floor",
           FULL: "full", LIMIT: "limit", ATTEMPT: "attempt",
           FOLD: "fold"}

_EPS = 2.220446049250313e-16
_MAX_NEWTON = 10
_C0, _C1, _C2 = C
_E0, _E1, _E2 = E_ERR
_S1, _S2, _S3 = END_SLOPES
_SAMPLES = tuple(SAMPLES)
# the denominators of radau.dense_weights
_D1 = _C0 * (_C0 - _C1) * (_C0 - _C2)
_D2 = _C1 * (_C1 - _C0) * (_C1 - _C2)
_D3 = _C2 * (_C2 - _C0) * (_C2 - _C1)

_stage = njit(cache=True)(stage_solve)


@njit(cache=True, inline="always")
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


@njit(cache=True, inline="always")
def _element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, e, q, F) -> None:
    """``q`` and ``F`` of element ``e`` at ``s = 0, c_1, c_2, 1`` into ``q[:4]``,
    ``F[:4]`` (:meth:`StageSystem.element_nodes`)."""
    for k in range(4):
        q[k] = (_elem_at(spring[e], A, h, x_n, v_n, U, n, eb[e], k - 1)
                - _elem_at(spring[e], A, h, x_n, v_n, U, n, ea[e], k - 1))
    F[0] = F_n[e]
    for k in range(3):
        F[k + 1] = U[k * n + N + e]


@njit(cache=True)
def _folded(branch_law, ea, eb, spring, modes, checked, A, h, x_n, v_n, F_n, U, N, n, q,
            F) -> bool:
    """A checked element's law crosses a fold along the step
    (:func:`lumped.solvers.events.fold_crossed` on the held branch's kernel)."""
    for c in range(checked.shape[0]):
        e = checked[c]
        _element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, e, q, F)
        _, Rq0, RF0 = branch_law(e, modes[e], q[0], F[0])
        for k in range(3):
            _, Rq1, RF1 = branch_law(e, modes[e], q[k + 1], F[k + 1])
            if _left_branch(branch_law, e, modes[e], q[k], F[k], Rq0, RF0, q[k + 1],
                            F[k + 1], Rq1, RF1):
                return True
            Rq0, RF0 = Rq1, RF1
    return False


@njit(cache=True, inline="always")
def _left_branch(branch_law, e, mode, q0, F0, Rq0, RF0, q1, F1, Rq1, RF1) -> bool:
    """:func:`lumped.solvers.bdf_jit_core.left_branch` (the fold test of
    :mod:`lumped.solvers.branch_check`) on element ``e``'s branch ``mode``."""
    s0 = abs(Rq0) + abs(RF0)
    s1 = abs(Rq1) + abs(RF1)
    mq = _bit(_sign(Rq0, s0)) | _bit(_sign(Rq1, s1))
    mf = _bit(_sign(RF0, s0)) | _bit(_sign(RF1, s1))
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
        _, Rq, RF = branch_law(e, mode, q0 + s * dq, F0 + s * dF)
        sc = abs(Rq) + abs(RF)
        mq |= _bit(_sign(Rq, sc))
        mf |= _bit(_sign(RF, sc))
        if mq == 3 or mf == 3:
            return True
    return False


@njit(cache=True)
def _crossed(branch_guards, ea, eb, spring, modes, watched, A, h, x_n, v_n, F_n, U, N, n,
             qn, Fn, gbuf) -> bool:
    """True when a watched guard (shifted by its round-off tolerance) is negative at a
    sample of the step: :func:`lumped.solvers.events.first_crossing_on`'s test."""
    for w in range(watched.shape[0]):
        _element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, watched[w], qn[w], Fn[w])
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
            count = branch_guards(e, modes[e], qs, Fs, gbuf)
            for j in range(count):
                if gbuf[j] + tol < 0.0:
                    return True
    return False


@njit(cache=True)
def _error_norm(branch_law, masses, ea, eb, spring, modes, watched, A, U, h, x_n, v_n, F_n,
                net_n, dF, have_dF, rtol, atol, F_ref, M, LU, perm, rhs, err, two) -> float:
    """The scaled RMS error of the step (``StageSystem.error`` then ``error_norm``);
    NaN for a non-finite system, -1.0 for a singular finite one (Python's minimum norm).

    ``two`` is 2.0, a run-time value: CPython's ``y ** 2`` is the C library's ``pow``, which
    differs from ``y * y`` in the last bit now and then, and numba (LLVM) turns a constant
    exponent 2 into ``y * y``."""
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
        q_e = (_elem_at(spring[e], A, h, x_n, v_n, U, n, b, -1)
               - _elem_at(spring[e], A, h, x_n, v_n, U, n, a, -1))
        _R, Rq, RF = branch_law(e, modes[e], q_e, F_n[e])
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
    if have_dF:
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


@njit(cache=True, inline="always")
def _forces(t, fkind, fpar, f) -> None:
    """``f_i(t)`` per node (``scene.external_forces``): 0 where there is no forcing."""
    for i in range(f.shape[0]):
        f[i] = 0.0
    forcing_into(0, t, fkind, fpar, fpar, f)


@njit(cache=True, inline="always")
def _finite(J) -> bool:
    for r in range(J.shape[0]):
        for c in range(J.shape[1]):
            if not math.isfinite(J[r, c]):
                return False
    return True


@njit(cache=True)
def _step_error(branch_law, masses, ea, eb, spring, modes, watched, A, U, h, t, prev_break,
                x, v, F, dF, have_dF, fkind, fpar, net, rtol, atol, F_ref, M, LUm, permm, rhs,
                err, two) -> float:
    """The error norm of the step from ``t`` (the forces right after a breakpoint)."""
    t_n0 = np.nextafter(t, math.inf) if t == prev_break else t
    _forces(t_n0, fkind, fpar, net)
    for e in range(ea.shape[0]):
        if ea[e] >= 0:
            net[ea[e]] += F[e]
        if eb[e] >= 0:
            net[eb[e]] -= F[e]
    return _error_norm(branch_law, masses, ea, eb, spring, modes, watched, A, U, h, x, v, F,
                       net, dF, have_dF == 1, rtol, atol, F_ref, M, LUm, permm, rhs, err, two)


def advance(branch_law, branch_guards, masses, ea, eb, spring, modes, watched, checked, A, W,
            fkind,
            fpar, x, v, F, dF, fst, ist, T0, HS, Y0, D, ROWS, ws, wm, iw) -> None:
    """Steps with the modes held until a reason to return (see the module notes).

    ``ws`` (vectors), ``wm`` (matrices) and ``iw`` (ints) are :func:`loop_workspace`."""
    N = masses.shape[0]
    E = ea.shape[0]
    n = N + E
    ny = 2 * N + E
    size = 3 * n
    U, scale, b, du, G = ws[0, :size], ws[1, :size], ws[2, :size], ws[3, :size], ws[4, :size]
    rhs, err, net, gbuf, ftmp = ws[5, :ny], ws[6, :ny], ws[7, :N], ws[8], ws[9, :N]
    fk = wm[0, :3, :N]
    J, LU = wm[1, :size, :size], wm[2, :size, :size]
    M, LUm = wm[3, :ny, :ny], wm[4, :ny, :ny]
    nw = max(watched.shape[0], 1)
    qn, Fn = wm[5, :nw, :4], wm[6, :nw, :4]
    perm, out, permm = iw[0, :size], iw[1, :3], iw[2, :ny]
    rtol, atol, m_min = fst[RTOL], fst[ATOL], fst[M_MIN]
    t_stop, t_final, prev_break = fst[T_STOP], fst[T_FINAL], fst[PREV_BREAK]
    t, h, F_seen = fst[T], fst[H], fst[F_SEEN]
    cap = T0.shape[0]
    while True:
        reason = 0
        single = ist[SINGLE] == 1
        if single:
            pass
        elif ist[STALLED] + 1 > 10_000 or ist[STEPS] >= ist[MAX_STEPS]:
            reason = LIMIT
        elif t + 1.0001 * h >= t_stop or h >= t_stop - t:
            reason = STOP
        elif h < 16.0 * _EPS * max(abs(t), t_final * 1e-3):
            reason = FLOOR
        elif ist[N_OUT] >= cap:
            reason = FULL
        if reason:
            break
        if not single:
            ist[STALLED] += 1
        for k in range(3):
            ck = _C0 if k == 0 else (_C1 if k == 1 else _C2)
            _forces(t + ck * h, fkind, fpar, ftmp)
            for i in range(N):
                fk[k, i] = ftmp[i]
        for k in range(3):
            for i in range(N):
                U[k * n + i] = v[i]
            for e in range(E):
                U[k * n + N + e] = F[e]
        F_new = F_seen
        for e in range(E):
            F_new = max(F_new, abs(F[e]))
        for i in range(N):
            F_new = max(F_new, abs(fk[2, i]))
        vmax = 0.0
        for i in range(N):
            vmax = abs(v[i]) if i == 0 else max(vmax, abs(v[i]))
        F_ref = max(F_new, m_min * (vmax + atol / rtol) / h)
        for k in range(3):
            for i in range(N):
                scale[k * n + i] = atol + rtol * abs(v[i])
            for e in range(E):
                scale[k * n + N + e] = rtol * max(abs(F[e]), F_ref)
        ok = _stage(branch_law, masses, ea, eb, spring, modes, A, W, U, h, x, v, fk, scale,
                    1e-3, _MAX_NEWTON, G, J, LU, perm, b, du, out)
        its = out[0]
        nfac = out[1]
        if single:  # one attempt for the Python loop: its outcome, nothing accepted
            F_seen = F_new
            ist[A_ITS] = its
            ist[A_NFAC] = nfac
            reason = ATTEMPT
            ist[A_OK] = 0
            if ok or (out[2] == 1 and _finite(J)):
                ist[A_OK] = -1  # singular: Python's minimum-norm solve
            if ok:
                fst[A_ERR] = _step_error(branch_law, masses, ea, eb, spring, modes, watched,
                                         A, U, h, t, prev_break, x, v, F, dF, ist[HAVE_DF],
                                         fkind, fpar, net, rtol, atol, F_ref, M, LUm, permm,
                                         rhs, err, fst[TWO])
                if fst[A_ERR] != -1.0:
                    ist[A_OK] = 1
            break
        if not ok and out[2] == 1:
            if _finite(J):
                ist[STALLED] -= 1
                reason = SINGULAR
                break
        F_seen = F_new
        ist[NEWTON_ITERATIONS] += its
        ist[FACTORIZATIONS] += nfac
        ist[NFEV] += its + 1
        ist[NJEV] += nfac
        ist[MAX_NEWTON_ITERATIONS] = max(ist[MAX_NEWTON_ITERATIONS], its)
        if not ok:
            ist[REJECTED] += 1
            h *= 0.5
            ist[HAVE_ACC] = 0
            continue
        err_norm = _step_error(branch_law, masses, ea, eb, spring, modes, watched, A, U, h,
                               t, prev_break, x, v, F, dF, ist[HAVE_DF], fkind, fpar, net,
                               rtol, atol, F_ref, M, LUm, permm, rhs, err, fst[TWO])
        if err_norm == -1.0:  # singular: undo this pass's counters, Python redoes it
            ist[STALLED] -= 1
            ist[NEWTON_ITERATIONS] -= its
            ist[FACTORIZATIONS] -= nfac
            ist[NFEV] -= its + 1
            ist[NJEV] -= nfac
            reason = SINGULAR
            break
        fac = 0.9 * (2 * _MAX_NEWTON + 1) / (2 * _MAX_NEWTON + its)
        if not math.isfinite(err_norm):
            ist[REJECTED] += 1
            h *= 0.2
            ist[HAVE_ACC] = 0
            continue
        quot = max(0.125, min(5.0, err_norm ** 0.25 / fac))
        if err_norm > 1.0:
            ist[REJECTED] += 1
            h = h / quot
            ist[HAVE_ACC] = 0
            continue
        crossed = watched.shape[0] > 0 and _crossed(branch_guards, ea, eb, spring, modes,
                                                    watched, A, h, x, v, F, U, N, n, qn, Fn,
                                                    gbuf)
        if crossed or (checked.shape[0] > 0 and _folded(
                branch_law, ea, eb, spring, modes, checked, A, h, x, v, F, U, N, n, qn[0],
                Fn[0])):
            # Python redoes this pass (and lands on the event, or stops at the fold)
            ist[STALLED] -= 1
            ist[NEWTON_ITERATIONS] -= its
            ist[FACTORIZATIONS] -= nfac
            ist[NFEV] -= its + 1
            ist[NJEV] -= nfac
            reason = CROSSING if crossed else FOLD
            break
        # accept: the dense record (t, h, y_n, Y_k - y_n) and the output row
        o = ist[N_OUT]
        T0[o] = t
        HS[o] = h
        for i in range(N):
            Y0[o, i] = x[i]
            Y0[o, N + i] = v[i]
        for e in range(E):
            Y0[o, 2 * N + e] = F[e]
        for k in range(3):
            for i in range(N):
                s_ = 0.0
                for j in range(3):
                    s_ += A[k, j] * U[j * n + i]
                D[o, k, i] = (x[i] + h * s_) - x[i]
                D[o, k, N + i] = U[k * n + i] - v[i]
            for e in range(E):
                D[o, k, 2 * N + e] = U[k * n + N + e] - F[e]
        for e in range(E):
            dF[e] = (_S1 * (U[N + e] - F[e]) + _S2 * (U[n + N + e] - F[e])
                     + _S3 * (U[2 * n + N + e] - F[e])) / h
        ist[HAVE_DF] = 1
        t = t + h
        for i in range(N):
            s_ = 0.0
            for j in range(3):
                s_ += A[2, j] * U[j * n + i]
            x[i] = x[i] + h * s_
            v[i] = U[2 * n + i]
        for e in range(E):
            F[e] = U[2 * n + N + e]
        ist[STEPS] += 1
        ROWS[o, 0] = t
        for i in range(N):
            ROWS[o, 1 + 2 * i] = x[i]
            ROWS[o, 2 + 2 * i] = v[i]
        for e in range(E):
            ROWS[o, 1 + 2 * N + e] = F[e]
        ist[N_OUT] = o + 1
        h_new = h / quot
        if ist[HAVE_ACC] == 1 and err_norm > 0.0:
            facgus = (fst[H_ACC] / h) * (err_norm ** fst[TWO] / fst[ERR_ACC]) ** 0.25 / 0.9
            facgus = max(0.125, min(5.0, facgus))
            h_new = h / max(quot, facgus)
        fst[H_ACC] = h
        fst[ERR_ACC] = max(1e-2, err_norm)
        ist[HAVE_ACC] = 1
        fst[H_GOOD] = h
        ist[STALLED] = 0
        h = h_new
    fst[T] = t
    fst[H] = h
    fst[F_SEEN] = F_seen
    ist[REASON] = reason


_COMPILED: list = []


def law_type():
    """The numba function type of ``branch_law(e, i, q, F) -> (R, dR/dq, dR/dF)``."""
    from .radau_jit import BRANCH_LAW_TYPE

    return BRANCH_LAW_TYPE


def guards_type():
    """The numba function type of ``branch_guards(e, i, q, F, out) -> count``."""
    from numba import types as T_

    f8 = T_.float64
    return T_.FunctionType(T_.int64(T_.int64, T_.int64, f8, f8, f8[::1]))


def compiled_advance():
    """:func:`advance` compiled once for every scene (numba's disk cache after the first
    time on a machine), or ``None`` without numba."""
    if not numba_enabled():
        return None
    if not _COMPILED:
        from numba import types as T_

        f8 = T_.float64
        v, m, m3 = f8[::1], f8[:, ::1], f8[:, :, ::1]
        iv = T_.int64[::1]
        sig = T_.none(law_type(), guards_type(), v, iv, iv, T_.boolean[::1], iv, iv, iv, m, m,
                      iv, m, v, v, v, v, v, iv, v, v, m, m3, m, m, m3,
                      T_.int64[:, ::1])
        _COMPILED.append(njit(sig, cache=True)(advance))
    return _COMPILED[0]


def loop_workspace(N: int, E: int, watched: int, cap: int):
    """``(outputs, ws, wm, iw)``: the output arrays ``(T0, HS, Y0, D, ROWS)`` for ``cap``
    steps and the work arrays of :func:`advance`."""
    ny = 2 * N + E
    s = 3 * (N + E)
    outputs = (np.zeros(cap), np.zeros(cap), np.zeros((cap, ny)), np.zeros((cap, 3, ny)),
               np.zeros((cap, 1 + ny)))
    big = max(s, ny, 4, watched)
    return (outputs, np.zeros((10, max(big, 64))), np.zeros((7, big, big)),
            np.zeros((3, big), dtype=np.int64))
