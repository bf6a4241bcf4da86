r"""The checks of the first ``radau5`` step after an event, compiled for the shared loop.

After an event the state's forces are the mode probe's, and the first step is checked as
no other (:class:`lumped.solvers.eventdriven.checks.StepChecks`): its dense output
starts from the forces :meth:`~lumped.solvers.eventdriven.checks.StepChecks.
dense_start_forces` gives (the stage forces' quadratic at ``s = 0`` for an element
locked on a mass, moved back along the way to the first stage until its guards admit
it; the probe's force for every other element), and the step is redone shorter when that
output's defect against the held laws (:func:`lumped.solvers.radau.dense_defect.
dense_defect`) exceeds 1. :func:`first_step_check` ports both, operation for operation,
for :func:`lumped.solvers.eventdriven.loop_jit.advance`, which takes that step itself
instead of handing it to the Python loop (one pass of it an event, 60-75 us). It is
compiled apart (:func:`compiled_first_step`, on demand) and called through its address,
as the crossing test of :mod:`lumped.solvers.radau.step_jit`.

The compiled loop takes no locks in parallel (their split is Python's), so the
``cones`` of the Python rule never occur here; nor does it start a step at an impact, or
one with a law whose folds are checked (their fold test reads the start forces too):
the Python loop takes those first steps.
"""

from __future__ import annotations

import math

from ...codegen.function_types import compiled_address, function_at, guards_type, law_type
from ...codegen.jit import numba_enabled
from ..modes.on_demand import from_disk
from ..radau.dense_defect import WEIGHTS, norm2
from ..radau.error import FORCE_TOL_FACTOR
from ..radau.step_jit import element_nodes
from ..radau.tableau import START_WEIGHTS

__all__ = ["FIRST_TYPE", "compiled_first_step", "first_step_check"]

_S0, _S1, _S2 = START_WEIGHTS
(_A1, _A2, _A3), (_B1, _B2, _B3) = WEIGHTS


def first_step_check(law_addr, guards_addr, lawc, ea, eb, spring, modes, held, A, h, x_n,
                     v_n, F_n, U, N, n, rtol, atol, F_ref, q, F, gbuf, F0) -> float:
    """The dense output's start forces into ``F0`` and its largest scaled defect.

    ``held[e]`` is 1 for an element its held branch locks that is not between junctions
    and ground alone (its start force is the quadratic's, admitted by its guards), 0
    else (the probe's force ``F_n[e]``); ``q``, ``F`` (4 each) and ``gbuf`` (a branch's
    guards) are work arrays; ``F_ref`` is the run's force scale (``F_seen``). The scene's
    ``branch_law`` and ``branch_guards`` are at ``law_addr`` and ``guards_addr``."""
    branch_law = _law_at(law_addr)
    branch_guards = _guards_at(guards_addr)
    E = ea.shape[0]
    for e in range(E):  # (dense_start_forces: the probe's force where not held)
        if held[e] == 0:
            F0[e] = F_n[e]
            continue
        s = 0.0  # the stage forces' quadratic at s = 0 (StepChecks.start_forces), which
        s += _S0 * U[N + e]  # element_nodes reads of element e alone
        s += _S1 * U[n + N + e]
        s += _S2 * U[2 * n + N + e]
        F0[e] = s
        element_nodes(ea, eb, spring, A, h, x_n, v_n, F0, U, N, n, e, q, F)
        F0[e] = _admitted(branch_guards, lawc, e, modes[e], q[0], F[0], q[1], F[1], gbuf)
    v_scale = 0.0
    for i in range(N):
        if i == 0 or abs(v_n[i]) > v_scale:
            v_scale = abs(v_n[i])
    for i in range(N):
        if abs(U[2 * n + i]) > v_scale:
            v_scale = abs(U[2 * n + i])
    x_scale = 0.0
    for i in range(N):
        if i == 0 or abs(x_n[i]) > x_scale:
            x_scale = abs(x_n[i])
    x_scale = x_scale + h * v_scale
    sigma_v = atol + rtol * v_scale
    sigma_x = atol + rtol * x_scale
    rtol_F = min(1e-3, FORCE_TOL_FACTOR * rtol)
    worst = 0.0
    for e in range(E):  # (dense_defect)
        element_nodes(ea, eb, spring, A, h, x_n, v_n, F0, U, N, n, e, q, F)
        sigma_q = sigma_x if spring[e] else sigma_v
        top = abs(F[0])
        if abs(F[3]) > top:
            top = abs(F[3])
        if F_ref > top:
            top = F_ref
        sigma_F = rtol_F * top
        R0 = branch_law(e, modes[e], q[0], F[0], lawc)[0]
        for k in range(2):
            w1 = _A1 if k == 0 else _B1
            w2 = _A2 if k == 0 else _B2
            w3 = _A3 if k == 0 else _B3
            qs = q[0] + w1 * (q[1] - q[0]) + w2 * (q[2] - q[0]) + w3 * (q[3] - q[0])
            Fs = F[0] + w1 * (F[1] - F[0]) + w2 * (F[2] - F[0]) + w3 * (F[3] - F[0])
            R, Rq, RF = branch_law(e, modes[e], qs, Fs, lawc)
            norm = _norm2(Rq * sigma_q, RF * sigma_F)
            if not norm > 0.0:
                continue
            d = abs(R - (1.0 - w1 - w2 - w3) * R0) / norm
            if not d <= worst:  # (a NaN defect is the worst)
                worst = d if abs(d) < math.inf else math.inf
    return worst


def _admitted(branch_guards, lawc, e, mode, q0, F0, q1, F1, gbuf) -> float:
    """:func:`lumped.solvers.eventdriven.checks._admitted` on element ``e``'s held branch."""
    if not _lowest(branch_guards(e, mode, q0, F0, gbuf, lawc), gbuf) >= 0.0:
        if _lowest(branch_guards(e, mode, q1, F1, gbuf, lawc), gbuf) >= 0.0:
            lo = 0.0
            hi = 1.0
            for _ in range(60):
                mid = 0.5 * (lo + hi)
                count = branch_guards(e, mode, q0 + mid * (q1 - q0), F0 + mid * (F1 - F0),
                                      gbuf, lawc)
                if _lowest(count, gbuf) >= 0.0:
                    hi = mid
                else:
                    lo = mid
            return F0 + hi * (F1 - F0)
    return F0


def _lowest(count, gbuf) -> float:
    """Python's ``min`` of the first ``count`` guards (its ``default=0.0`` when none):
    the first of equal or unordered values, as ``min`` keeps it."""
    if count == 0:
        return 0.0
    m = gbuf[0]
    for j in range(1, count):
        if gbuf[j] < m:
            m = gbuf[j]
    return m


_FIRST: list = []

if numba_enabled():
    from numba import types as _T

    from ...codegen.jit import njit

    _law_at = function_at(law_type())
    _guards_at = function_at(guards_type())
    _admitted = njit(cache=True)(_admitted)
    _lowest = njit(cache=True, inline="always")(_lowest)
    _norm2 = njit(cache=True)(norm2)  # (the Python reference's own code)
    _f8, _i8, _v = _T.float64, _T.int64, _T.float64[::1]
    _iv, _b, _mc, _ma = _i8[::1], _T.boolean[::1], _f8[:, ::1], _f8[:, :]
    #: The numba function type of :func:`first_step_check`.
    FIRST_TYPE = _T.FunctionType(_f8(
        _i8, _i8, _v, _iv, _iv, _b, _iv, _iv, _mc, _f8, _v, _v, _v, _v, _i8, _i8, _f8, _f8,
        _f8, _f8[:], _f8[:], _v, _v))
else:  # pragma: no cover - without numba (the compiled loop is not used)
    FIRST_TYPE, _norm2 = None, norm2


def compiled_first_step(compile: bool = True) -> int | None:
    """The address of :func:`first_step_check` compiled (once per process; numba's disk
    cache after the first time on a machine), or ``None`` without numba; with
    ``compile=False`` only if numba's disk cache holds it (for
    :class:`~lumped.solvers.modes.on_demand.OnDemand`: until then the Python loop takes
    the first step after an event, the same numbers)."""
    if not numba_enabled():
        return None
    if not _FIRST:
        if compile:
            return compiled_address(_FIRST, first_step_check, FIRST_TYPE)
        from numba.experimental.function_type import _get_wrapper_address

        disp = from_disk(first_step_check, FIRST_TYPE.signature, no_cpython_wrapper=True)
        if disp is None:
            return None
        _FIRST.append((_get_wrapper_address(disp, FIRST_TYPE.signature), disp))
    return _FIRST[0][0]
