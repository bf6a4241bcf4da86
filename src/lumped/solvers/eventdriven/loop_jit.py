r"""The inner loop of ``radau5`` compiled with numba: consecutive steps with the modes held.

:func:`advance` takes Radau IIA steps from ``t`` towards the next stop (a forcing breakpoint
or ``t_end``) with every element held on its mode's branch, operation for operation as the
reference loop of :class:`lumped.solvers.eventdriven.run.Radau5Run` (bit for bit):

the stage Newton (:func:`lumped.solvers.radau.stage_jit.stage_solve`; scales ``atol +
rtol |v_i|`` and ``rtol max(|F_e|, F_ref)``, ``F_ref = max(F_seen, m_min (max |v| + atol /
rtol) / h)``), RADAU5's filtered error estimate and its RMS norm
(:func:`lumped.solvers.radau.step_jit.step_error`), Gustafsson's predictive step control,
the watched guards on the collocation polynomial at ``s = k / 8`` (only *detected*: the
root and the landing are the reference's) and the accepted step's dense-output record
``(t_n, h, y_n, Y_k - y_n)`` and output row.

With ``ist[FIRST] = 1`` the first step follows an event: its dense output starts from
:mod:`lumped.solvers.eventdriven.first_step_jit`'s forces (``held`` in ``iw[3]``, the forces in
``ws[10]``), and a defect above 1 redoes it shorter (``ist[DEFECT_REJECTED]``).

It returns to Python, the state as at the top of the reference's pass that must run next,
with ``ist[REASON]`` (:data:`REASONS`): a room to the stop below the step floor
(:data:`STOP`; else it takes the step to the stop and returns after it, :data:`STOPPED`),
a guard negative in a candidate step (:data:`CROSSING`: Python redoes it and lands), a
fold of a law not known monotone (:data:`FOLD`), a singular finite Jacobian
(:data:`SINGULAR`: the minimum-norm solve), a step below its floor (:data:`FLOOR`), full
output arrays (:data:`FULL`), ``ist[MAX_STEPS]`` tries
(:meth:`~lumped.solvers.eventdriven.budget.WorkBudget.compiled_cap`) or the stall limit
(:data:`LIMIT`), the eighth Newton failure in a row (:data:`DAMPED`: the line search),
``CREEP_STEPS`` accepted steps in a row shorter than ``max(step floor,
fst[CREEP_FLOOR])`` (:data:`CREEP`, after that step: the reference's creep test, which
stops the run), a held branch's force at its flat end (:data:`FLAT`: the stage guess of
:mod:`lumped.solvers.radau.flat_start`). With ``ist[SINGLE] = 1`` it makes one attempt of
size ``h`` for the Python loop (:data:`ATTEMPT`): ``ist[A_OK]`` (1 solved, 0 Newton
failed, -1 singular), ``ist[A_ITS]``, ``ist[A_NFAC]``, ``fst[A_ERR]``, the stage values
in ``ws[0]``; the crossing's root is :func:`lumped.solvers.eventdriven.attempt_root_jit.
attempt_root`'s, compiled apart.

State in and out: ``x, v, F, dF``, ``fst`` (floats, ``T .. CREEP_FLOOR``), ``ist`` (ints,
``HAVE_ACC .. DEFECT_REJECTED``); the forcing: :func:`lumped.solvers.radau.forces_jit.
forces`'s ``(fkind, fpar, table)``. The stage solve, error estimate, guard test and
first-step check are called through their addresses (``iw[1, STAGE_AT .. FIRST_AT]``):
numba would link a called function's code into this loop's module and emit it again.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.function_types import function_at, scalar_loops
from ...codegen.jit import njit, numba_enabled
from ...codegen.templates import GUARD_ROOM
from ..modes.on_demand import compiled_once
from ..radau import stage_jit, step_jit
from ..radau.flat_start import AT_END
from ..radau.forces_jit import forces
from ..radau.stage import DAMPED_AFTER, MAX_NEWTON, STALL_PASSES
from ..radau.step_jit import FOLDED_TYPE, finite, start_time
from ..radau.tableau import END_SLOPES, C
from . import first_step_jit
from .creep import CREEP_STEPS

__all__ = ["advance", "advance_argument_types", "compiled_advance", "loop_workspace", "STOP",
           "CROSSING", "SINGULAR", "FLOOR", "FULL", "LIMIT", "ATTEMPT", "FOLD", "DAMPED", "CREEP",
           "FLAT", "REASONS"]

# fst: float state
(T, H, F_SEEN, H_ACC, ERR_ACC, H_GOOD, T_STOP, T_FINAL, RTOL, ATOL, M_MIN, PREV_BREAK,
 TWO, A_ERR, A_ROOT, CREEP_FLOOR) = range(16)
# ist: int state and counters
(HAVE_ACC, HAVE_DF, STALLED, STEPS, REJECTED, NEWTON_ITERATIONS, FACTORIZATIONS, NFEV, NJEV,
 MAX_NEWTON_ITERATIONS, MAX_STEPS, N_OUT, REASON, SINGLE, A_ITS, A_NFAC, A_OK,
 A_HIT, A_W, A_J, BI, CREEPING, FIRST, DEFECT_REJECTED) = range(24)
(STOP, CROSSING, SINGULAR, FLOOR, FULL, LIMIT, ATTEMPT, FOLD, STOPPED, DAMPED,
 CREEP, FLAT) = range(1, 13)
REASONS = {STOP: "stop", CROSSING: "crossing", SINGULAR: "singular", FLOOR: "floor",
           FULL: "full", LIMIT: "limit", ATTEMPT: "attempt", STOPPED: "stopped",
           FOLD: "fold", DAMPED: "damped", CREEP: "creep", FLAT: "flat"}

STAGE_AT, ERROR_AT, CROSSED_AT, FIRST_AT = 4, 5, 6, 7  # iw[1, ...]: addresses (module notes)
_EPS = 2.220446049250313e-16
_C0, _C1, _C2 = C
_S1, _S2, _S3 = END_SLOPES


def advance(law_addr, guards_addr, fold_addr, lawc, masses, ea, eb, spring, lock_q, modes,
            watched, checked, A, W, fkind, fpar, table, breaks, kinks, flat, x, v, F, dF, fst,
            ist, T0, HS, Y0, D, ROWS, ws, wm, iw) -> None:
    """Steps with the modes held until a reason to return (see the module notes).

    ``law_addr``, ``guards_addr``, ``fold_addr`` (0 without ``checked`` elements): the
    addresses of the scene's ``branch_law``, ``branch_guards`` and of the fold test
    (:func:`~lumped.solvers.radau.step_jit.fold_test`), ``lawc`` the law constants.
    ``breaks`` and ``kinks`` (1 or 0): the forcing's breakpoints and which are kinks
    (:func:`~lumped.solvers.eventdriven.setup.time_events`; a step onto a kink goes on),
    ``ist[BI]`` the next one. ``flat`` (``E x 2``): ``(s, d)`` of each held branch flat at
    its end (:meth:`lumped.solvers.radau.flat_start.FlatEnds.table`). ``ws``, ``wm``,
    ``iw``: :func:`loop_workspace`."""
    stage_solve = _stage_at(iw[1, STAGE_AT])
    step_error = _error_at(iw[1, ERROR_AT])
    crossed = _crossed_at(iw[1, CROSSED_AT])
    first_check = _first_at(iw[1, FIRST_AT])
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
    perm, out, permm = iw[0, :size], iw[1, :4], iw[2, :ny]  # (out[3]: stage_solve's)
    held, F0 = iw[3, :E], ws[10, :E]  # (the first step after an event: first_step_jit)
    rtol, atol, m_min = fst[RTOL], fst[ATOL], fst[M_MIN]
    t_stop, t_final, prev_break = fst[T_STOP], fst[T_FINAL], fst[PREV_BREAK]
    t, h, F_seen = fst[T], fst[H], fst[F_SEEN]
    cap = T0.shape[0]
    while True:
        reason = 0
        single = ist[SINGLE] == 1
        to_stop = False
        if single:
            pass
        elif ist[STALLED] + 1 > STALL_PASSES or ist[STEPS] + ist[REJECTED] >= ist[MAX_STEPS]:
            reason = LIMIT
        elif ist[N_OUT] >= cap:
            reason = FULL
        elif t + 1.0001 * h >= t_stop or h >= t_stop - t:
            # the step to the stop, as the Python loop takes it (h = the room left); a
            # room below the step floor is Python's (it may change the mode there)
            if t_stop - t < 16.0 * _EPS * max(abs(t), t_final * 1e-3):
                reason = STOP
            else:
                h = t_stop - t
                to_stop = True
        elif h < 16.0 * _EPS * max(abs(t), t_final * 1e-3):
            reason = FLOOR
        if not single and not reason:
            for e in range(E):  # (flat_start.at_flat_end: the same numbers)
                s_ = flat[e, 0]
                if s_ == s_:
                    sF = s_ * F[e]
                    if abs(sF + flat[e, 1]) <= AT_END * max(abs(sF), abs(flat[e, 1])):
                        reason = FLAT
        if reason:
            break
        if not single:
            ist[STALLED] += 1
        for k in range(3):
            ck = _C0 if k == 0 else (_C1 if k == 1 else _C2)
            forces(t + ck * h, fkind, fpar, table, ftmp)
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
        ok = stage_solve(law_addr, lawc, masses, ea, eb, spring, lock_q, modes, A, W, U, h, x, v,
                         fk, scale, 1e-3, MAX_NEWTON, G, J, LU, perm, b, du, out)
        its = out[0]
        nfac = out[1]
        if single:  # one attempt for the Python loop: its outcome, nothing accepted
            F_seen = F_new
            ist[A_ITS] = its
            ist[A_NFAC] = nfac
            reason = ATTEMPT
            ist[A_OK] = 0
            if ok or (out[2] == 1 and finite(J)):
                ist[A_OK] = -1  # singular: Python's minimum-norm solve
            if ok:
                fst[A_ERR] = step_error(law_addr, lawc, masses, ea, eb, spring, modes, watched,
                                         A, U, h, start_time(t, prev_break), x, v, F, dF,
                                         ist[HAVE_DF], fkind, fpar, table, net, rtol, atol,
                                         F_ref, M, LUm, permm, rhs, err, fst[TWO])
                if fst[A_ERR] != -1.0:
                    ist[A_OK] = 1
                    ist[A_HIT] = 0  # (the crossing's root: attempt_root, called after)
            break
        if not ok and out[2] == 1:
            if finite(J):
                ist[STALLED] -= 1
                reason = SINGULAR
                break
        if not ok and ist[STALLED] >= DAMPED_AFTER:
            # the eighth failure in a row: Python redoes this pass with its line-search
            # fallback (the loops stay the same)
            ist[STALLED] -= 1
            reason = DAMPED
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
        err_norm = step_error(law_addr, lawc, masses, ea, eb, spring, modes, watched, A, U, h,
                               start_time(t, prev_break), x, v, F, dF, ist[HAVE_DF], fkind,
                               fpar, table, net, rtol, atol, F_ref, M, LUm, permm, rhs, err,
                               fst[TWO])
        if err_norm == -1.0:  # singular: undo this pass's counters, Python redoes it
            ist[STALLED] -= 1
            ist[NEWTON_ITERATIONS] -= its
            ist[FACTORIZATIONS] -= nfac
            ist[NFEV] -= its + 1
            ist[NJEV] -= nfac
            reason = SINGULAR
            break
        fac = 0.9 * (2 * MAX_NEWTON + 1) / (2 * MAX_NEWTON + its)
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
        hit = watched.shape[0] > 0 and crossed(guards_addr, lawc, ea, eb, spring, modes, watched,
                                               A, h, x, v, F, U, N, n, qn, Fn, gbuf)
        if hit or (checked.shape[0] > 0 and _folded_at(fold_addr)(
                law_addr, lawc, ea, eb, spring, modes, checked, A, h, x, v, F, U, N, n, qn[0],
                Fn[0])):
            # Python redoes this pass (and lands on the event, or stops at the fold)
            ist[STALLED] -= 1
            ist[NEWTON_ITERATIONS] -= its
            ist[FACTORIZATIONS] -= nfac
            ist[NFEV] -= its + 1
            ist[NJEV] -= nfac
            reason = CROSSING if hit else FOLD
            break
        first = ist[FIRST] == 1
        if first:  # the first step after an event: its dense output's start and defect
            d = first_check(law_addr, guards_addr, lawc, ea, eb, spring, modes, held, A, h, x,
                            v, F, U, N, n, rtol, atol, F_seen, qn[0], Fn[0], gbuf, F0)
            if d > 1.0:
                ist[REJECTED] += 1
                ist[DEFECT_REJECTED] += 1
                h *= max(0.1, min(0.5, 0.8 / d))
                ist[HAVE_ACC] = 0
                continue
        Fs = F0 if first else F  # accept: the dense record (t, h, y_n, Y_k - y_n), the row
        o = ist[N_OUT]
        T0[o] = t
        HS[o] = h
        for i in range(N):
            Y0[o, i] = x[i]
            Y0[o, N + i] = v[i]
        for e in range(E):
            Y0[o, 2 * N + e] = Fs[e]
        for k in range(3):
            for i in range(N):
                s_ = 0.0
                for j in range(3):
                    s_ += A[k, j] * U[j * n + i]
                D[o, k, i] = (x[i] + h * s_) - x[i]
                D[o, k, N + i] = U[k * n + i] - v[i]
            for e in range(E):
                D[o, k, 2 * N + e] = U[k * n + N + e] - Fs[e]
        for e in range(E):
            dF[e] = (_S1 * (U[N + e] - F[e]) + _S2 * (U[n + N + e] - F[e])
                     + _S3 * (U[2 * n + N + e] - F[e])) / h
        ist[HAVE_DF] = 1
        ist[FIRST] = 0
        t = t_stop if to_stop else t + h
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
        # the creep test (step.StepPass._accept; the step floor at the step's start)
        short = t - T0[o] < max(16.0 * _EPS * max(abs(T0[o]), t_final * 1e-3), fst[CREEP_FLOOR])
        ist[CREEPING] = ist[CREEPING] + 1 if short else 0
        if ist[CREEPING] >= CREEP_STEPS:
            reason = CREEP
            break
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
        if to_stop:
            bi = ist[BI]
            if bi < breaks.shape[0] and t == breaks[bi] and kinks[bi] == 1:
                # a kink of the forcing: the held mode goes on (Python's time_event), the
                # error estimate starts afresh
                bi += 1
                ist[BI] = bi
                prev_break = t
                fst[PREV_BREAK] = t
                t_stop = breaks[bi] if bi < breaks.shape[0] else t_final
                fst[T_STOP] = t_stop
                ist[HAVE_DF] = 0
                ist[HAVE_ACC] = 0
                continue
            # Python handles what happens at the stop (a time event, the end)
            reason = STOPPED
            break
    fst[T] = t
    fst[H] = h
    fst[F_SEEN] = F_seen
    ist[REASON] = reason


if numba_enabled():
    _folded_at = function_at(FOLDED_TYPE)
    _stage_at = function_at(stage_jit.STAGE_TYPE)
    _error_at, _crossed_at = function_at(step_jit.ERROR_TYPE), function_at(step_jit.CROSSED_TYPE)
    _first_at = function_at(first_step_jit.FIRST_TYPE)

_COMPILED: list = []
_LOOKED: list = []  # (numba's disk cache looked at for it: compiled_advance)


def compiled_advance(compile: bool = True):
    """:func:`advance` compiled once for every scene (numba's disk cache after the first
    time on a machine), or ``None`` without numba; ``compile=False``: only loaded from
    numba's disk cache (looked at once a process)."""
    if not numba_enabled():
        return None
    if not _COMPILED:
        if not compile:
            looked, _LOOKED[:] = bool(_LOOKED), [True]
            return None if looked else compiled_once(_COMPILED, advance, _signature, False,
                                                     no_cfunc_wrapper=True)
        with scalar_loops():
            _COMPILED.append(njit(_signature(), cache=True, no_cfunc_wrapper=True)(advance))
    return _COMPILED[0]


def _signature():
    from numba import types as T_

    return T_.none(*advance_argument_types())


def advance_argument_types() -> tuple:
    """numba's types of :func:`advance`'s arguments, in order."""
    from numba import types as T_

    f8, i8 = T_.float64, T_.int64
    v, m, m3, iv = f8[::1], f8[:, ::1], f8[:, :, ::1], i8[::1]
    return (i8, i8, i8, v, v, iv, iv, T_.boolean[::1], m, iv, iv, iv, m, m, iv, m, i8, v, iv,
            m, v, v, v, v, v, iv, v, v, m, m3, m, m, m3, i8[:, ::1])


def loop_workspace(N: int, E: int, watched: int, cap: int):
    """``(outputs, ws, wm, iw)``: the output arrays ``(T0, HS, Y0, D, ROWS)`` for ``cap``
    steps and the work arrays of :func:`advance` (``ws[8]`` holds a branch's guards: room
    for :data:`~lumped.codegen.templates.GUARD_ROOM`)."""
    ny = 2 * N + E
    s = 3 * (N + E)
    outputs = (np.zeros(cap), np.zeros(cap), np.zeros((cap, ny)), np.zeros((cap, 3, ny)),
               np.zeros((cap, 1 + ny)))
    big = max(s, ny, 4, watched)
    iw = np.zeros((4, max(big, FIRST_AT + 1)), dtype=np.int64)
    iw[1, STAGE_AT] = stage_jit.stage_address()
    iw[1, ERROR_AT], iw[1, CROSSED_AT] = step_jit.error_address(), step_jit.crossed_address()
    return outputs, np.zeros((11, max(big, GUARD_ROOM))), np.zeros((7, big, big)), iw
