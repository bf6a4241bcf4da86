r"""The step loop of the generic fixed-step BDF1/BDF2, written for numba.

The same loop as :func:`lumped.solvers.bdf.fixed_step.run_bdf` (read it for the maths),
operation for operation, on preallocated arrays:

* BDF1: ``h = dt``, ``x_hat = x_n``, ``v_hat = v_n``; BDF2 (from the second step on):
  ``h = 2 dt / 3``, ``x_hat = x_n + (x_n - x_{n-1}) / 3``, ``v_hat = v_n + (v_n - v_{n-1}) / 3``
  (exact for a stuck state);
* the unknowns ``u = (v_1 .. v_N, F_1 .. F_E)``, from the previous step's solution; the
  fast path (the same Jacobian as the cached factors: accept ``u`` or take one full
  step, checked with the linearised row scales) and otherwise the full Newton of
  :func:`lumped.solvers.newton.semismooth_jit.newton` with the round-off row scales;
* ``x_{n+1} = x_hat + h v_{n+1}``;
* the fold check of :mod:`lumped.solvers.implicit.branch_check` on the elements whose law is not a
  known monotone built-in.

The scene enters through two compiled callbacks, ``evaluate(u, p, G, J, S, roundoff)``
(the step system, with ``p = [h, m_i / h (N), v_hat (N), x_hat (N), f(t) (N), c]``,
``c`` the scene's law constants) and ``element_law(e, q, F, c)`` (element ``e``'s
kernel), passed as *function pointers* (numba's first-class function types,
:data:`EVALUATE_TYPE`, :data:`ELEMENT_LAW_TYPE`): the loop is compiled once for every
scene (:func:`compiled_run_bdf_core`, cached on disk). The runs take the structure-generic
pair of :mod:`lumped.codegen.step_dispatch` (compiled once for every scene too, so a new
structure of compiled laws compiles nothing; a scene module of :mod:`lumped.codegen.jit`
gives the same pair per structure, the same numbers); the laws' numbers are data
(``lawc``), so new numbers compile nothing. Nothing else comes from the scene: the forcing is read
from ``fkind, fpar, ftab`` by :func:`forcing_into` (kinds: 0 none, 1 constant
``fpar[i, 0]``, 2 sine burst ``fpar[i] = (A, omega, t_off)``, 3 a table
``ftab[step, i]`` computed before the loop).

``info`` receives the outcome: ``info[0]`` 0 success, 1 Newton failed, 2 a fold
(branch lost), 3 a non-finite force; ``info[1]`` the step; ``info[2]`` the Newton code;
``info[3]`` the worst row, element or node; ``info[4..7]`` the counters (Newton
iterations, residual and Jacobian evaluations, factorisations), ``info[8]`` the largest
iteration count of one step. ``finfo`` receives floats for the message: the residual
(or force value), then for a fold ``q0, F0, q1, F1``; ``finfo[5]`` the last Newton
iteration count on failure.
"""

from __future__ import annotations

import numpy as np

from ...codegen.jit import njit, numba_enabled, numba_module
from ...scene.forcing_jit import forcing_into
from ..implicit.branch_check_jit import left_branch
from ..newton.criteria_jit import finite_sum, residual_ok, same, update_ok, worst_row
from ..newton.linalg_jit import lu_solve_into
from ..newton.semismooth_jit import (
    WS_D2,
    WS_DU,
    WS_G,
    WS_GN,
    WS_J,
    WS_JN,
    WS_S,
    WS_SN,
    WS_UN,
    newton,
)

__all__ = ["EVALUATE_TYPE", "ELEMENT_LAW_TYPE", "compiled_run_bdf_core",
           "fast_step", "loop_workspace", "run_bdf_core"]

OK, NEWTON_FAILED, BRANCH_LOST, BAD_FORCE = 0, 1, 2, 3


@njit(cache=True, inline="always")
def fast_step(evaluate, p, u0, u, cJ, cLU, cperm, cvalid, wv, wm, rtol, atol) -> int:
    """The common step (the reference's :func:`lumped.solvers.bdf.step_loop.fast_step`):
    returns the Newton iterations it took (0 or 1) with the solution in ``u``, or -1 when
    full Newton must run."""
    n = u.shape[0]
    G, S, J, du = wv[WS_G], wv[WS_S], wm[WS_J], wv[WS_DU]
    evaluate(u0, p, G, J, S, False)
    if cvalid[0] == 0 or not same(J, cJ) or not finite_sum(G):
        return -1
    lu_solve_into(cLU, cperm, G, du)
    if not finite_sum(du):
        return -1
    if residual_ok(G, S, rtol, atol):
        if update_ok(du, u0, rtol, atol):
            for i in range(n):
                u[i] = u0[i] - du[i]
            return 0
        return -1
    u1, G1, S1, J1, d = wv[WS_UN], wv[WS_GN], wv[WS_SN], wm[WS_JN], wv[WS_D2]
    for i in range(n):
        u1[i] = u0[i] - du[i]
    evaluate(u1, p, G1, J1, S1, False)
    if not same(J1, J) or not finite_sum(G1) or not residual_ok(G1, S1, rtol, atol):
        return -1
    lu_solve_into(cLU, cperm, G1, d)
    if not (finite_sum(d) and update_ok(d, u1, rtol, atol)):
        return -1
    for i in range(n):
        u[i] = u1[i] - d[i]
    return 1


def loop_workspace(N: int, E: int, K: int) -> tuple:
    """The arrays :func:`run_bdf_core` works in (``P, cJ, cLU, cperm, cvalid, counts,
    vec``), for ``N`` nodes, ``E`` elements and ``K`` law constants."""
    n = N + E
    return (np.zeros((2, 1 + 4 * N + K)), np.zeros((2, n, n)), np.zeros((2, n, n)),
            np.zeros((2, n), dtype=np.int64), np.zeros((2, 1), dtype=np.int64),
            np.zeros(4, dtype=np.int64), np.zeros((10, n)))


@njit(cache=True, inline="always")
def _elongation(y, a, b) -> float:
    return (y[b] if b >= 0 else 0.0) - (y[a] if a >= 0 else 0.0)


def run_bdf_core(evaluate, element_law, masses, ea, eb, spring, checked, x0, v0, F0,
                 dt, n_steps, bdf2, rtol, atol, max_iters, max_backtracks, free_steps,
                 fkind, fpar, ftab, xs, vs, Fs, info, finfo, wv, wm, wperm, P, cJ, cLU,
                 cperm, cvalid, counts, vec, lawc, step0=0, step_stop=-1) -> int:
    """Advance the fixed steps from ``step0 + 1`` to ``step_stop`` (to ``n_steps`` when
    ``step_stop < 0``) from ``(x0, v0, F0)`` at step ``step0``; fill rows ``step0`` to
    the last step taken of ``xs, vs, Fs`` and ``info, finfo`` (see the module notes);
    return the rows filled (the last step taken + 1).

    For ``step0 >= 1`` the previous state (BDF2) is read from row ``step0 - 1`` of ``xs,
    vs``: a run can be continued from any stored step (the fast path of
    :mod:`lumped.solvers.bdf.fast_codegen` hands single steps over this way).

    ``wv, wm, wperm`` is Newton's workspace
    (:func:`lumped.solvers.newton.semismooth_jit.workspace`),
    ``P .. vec`` the loop's (:func:`loop_workspace`), both allocated by the caller;
    ``lawc`` the scene's law constants (:attr:`lumped.codegen.jit.JitScene.consts`),
    copied into the tail of ``P`` for ``evaluate``.
    Compiled by :func:`compiled_run_bdf_core`."""
    N = x0.shape[0]
    E = F0.shape[0]
    n = N + E
    h1 = dt
    h2 = 2.0 * dt / 3.0
    # step parameters for each step size: [h, m/h, v_hat, x_hat, f]
    for k in range(2):
        h = h1 if k == 0 else h2
        P[k, 0] = h
        for i in range(N):
            P[k, 1 + i] = masses[i] / h if masses[i] != 0.0 else 0.0
        cvalid[k, 0] = 0
        for j in range(lawc.shape[0]):
            P[k, 1 + 4 * N + j] = lawc[j]
    u0, u, x, v, xp, vp = vec[0], vec[1], vec[2][:N], vec[3][:N], vec[4][:N], vec[5][:N]
    F, prev_q, prev_Rq, prev_RF = vec[6][:E], vec[7][:E], vec[8][:E], vec[9][:E]
    for i in range(N):
        x[i] = x0[i]
        v[i] = v0[i]
        xs[step0, i] = x0[i]
        vs[step0, i] = v0[i]
        if step0 >= 1:
            xp[i] = xs[step0 - 1, i]
            vp[i] = vs[step0 - 1, i]
    for e in range(E):
        F[e] = F0[e]
        Fs[step0, e] = F0[e]
    for c in range(checked.shape[0]):
        e = checked[c]
        q = _elongation(x if spring[e] else v, ea[e], eb[e])
        _, Rq, RF = element_law(e, q, F[e], lawc)
        prev_q[e] = q
        prev_Rq[e] = Rq
        prev_RF[e] = RF
    fast = free_steps >= 1
    total_it = res_ev = jac_ev = facts = max_it = 0
    for i in range(9):
        info[i] = 0
    rows = step0 + 1
    last = n_steps if step_stop < 0 else step_stop
    for step in range(step0 + 1, last + 1):
        t = step * dt
        k = 0 if (not bdf2 or step == 1) else 1
        p = P[k]
        h = p[0]
        off = 1 + 3 * N
        bad = forcing_into(step, t, fkind, fpar, ftab, p[off:off + N])
        if bad >= 0:
            info[0] = BAD_FORCE
            info[1] = step
            info[3] = bad
            finfo[0] = p[off + bad]
            finfo[1] = t
            break
        for i in range(N):
            if k == 0:
                p[1 + 2 * N + i] = x[i]
                p[1 + N + i] = v[i]
            else:
                xi = x[i]
                vi = v[i]
                p[1 + 2 * N + i] = xi + (xi - xp[i]) / 3.0
                p[1 + N + i] = vi + (vi - vp[i]) / 3.0
        for i in range(N):
            u0[i] = v[i]
        for e in range(E):
            u0[N + e] = F[e]
        it = fast_step(evaluate, p, u0, u, cJ[k], cLU[k], cperm[k], cvalid[k], wv, wm,
                       rtol, atol) if fast else -1
        if it >= 0:
            total_it += it
            res_ev += 1 + it
            jac_ev += 1
            if it > max_it:
                max_it = it
        else:
            for j in range(n):
                u[j] = u0[j]
            code = newton(evaluate, p, u, True, rtol, atol, max_iters, max_backtracks,
                          free_steps, cJ[k], cLU[k], cperm[k], cvalid[k], wv, wm, wperm,
                          counts)
            total_it += counts[0]
            res_ev += counts[1]
            jac_ev += counts[2]
            facts += counts[3]
            if counts[0] > max_it:
                max_it = counts[0]
            if code != 0:
                w = worst_row(wv[WS_G], wv[WS_S], rtol, atol)
                info[0] = NEWTON_FAILED
                info[1] = step
                info[2] = code
                info[3] = w
                finfo[0] = wv[WS_G][w]
                finfo[1] = t
                finfo[5] = counts[0]
                break
        for i in range(N):
            xp[i] = x[i]
            vp[i] = v[i]
            v[i] = u[i]
            x[i] = p[1 + 2 * N + i] + h * u[i]
        lost = -1
        for c in range(checked.shape[0]):
            e = checked[c]
            q1 = _elongation(x if spring[e] else v, ea[e], eb[e])
            R1, Rq1, RF1 = element_law(e, q1, u[N + e], lawc)
            if left_branch(element_law, lawc, e, prev_q[e], F[e], prev_Rq[e], prev_RF[e],
                           q1, u[N + e], Rq1, RF1):
                lost = e
                finfo[0] = R1
                finfo[1] = t
                finfo[2] = prev_q[e]
                finfo[3] = F[e]
                finfo[4] = q1
                finfo[5] = u[N + e]
                break
            prev_q[e] = q1
            prev_Rq[e] = Rq1
            prev_RF[e] = RF1
        if lost >= 0:
            info[0] = BRANCH_LOST
            info[1] = step
            info[3] = lost
            break
        for e in range(E):
            F[e] = u[N + e]
            Fs[rows, e] = F[e]
        for i in range(N):
            xs[rows, i] = x[i]
            vs[rows, i] = v[i]
        rows += 1
    info[4] = total_it
    info[5] = res_ev
    info[6] = jac_ev
    info[7] = facts
    info[8] = max_it
    return rows


def _signature():
    from numba import types as T

    f8, i8, b1 = T.float64, T.int64, T.boolean
    v, m, c = f8[::1], f8[:, ::1], f8[:, :, ::1]
    iv, im = i8[::1], i8[:, ::1]
    return T.int64(EVALUATE_TYPE, ELEMENT_LAW_TYPE, v, iv, iv, b1[::1], iv, v, v, v, f8, i8,
                   b1, f8, f8, i8, i8, i8, iv, m, m, m, m, m, iv, v, m, c, iv, m, c, c, im,
                   im, iv, m, v, i8, i8)


if numba_module is not None:
    from numba import types as _T

    _f8 = _T.float64
    #: ``evaluate(u, p, G, J, S, roundoff) -> None`` as a numba function type.
    EVALUATE_TYPE = _T.FunctionType(_T.none(_f8[::1], _f8[::1], _f8[::1], _f8[:, ::1],
                                            _f8[::1], _T.boolean))
    #: ``element_law(e, q, F, c) -> (R, dR/dq, dR/dF)`` as a numba function type.
    ELEMENT_LAW_TYPE = _T.FunctionType(_T.UniTuple(_f8, 3)(_T.int64, _f8, _f8, _f8[::1]))
else:  # pragma: no cover - without numba
    EVALUATE_TYPE = ELEMENT_LAW_TYPE = None

_COMPILED: list = []


def compiled_run_bdf_core():
    """:func:`run_bdf_core` compiled for the function-pointer callbacks (once per process,
    from numba's disk cache after the first time on a machine); the plain function when
    numba is absent or disabled."""
    if not numba_enabled():
        return run_bdf_core
    if not _COMPILED:
        _COMPILED.append(njit(_signature(), cache=True)(run_bdf_core))
    return _COMPILED[0]


def port_cached() -> bool:
    """The faithful port is compiled in this process, or numba's disk cache holds an
    index for it (an earlier process on this machine compiled it: loading it takes about
    0.4 s, compiling it about 30 s of CPU). Read from numba's cache locator without
    compiling; ``True`` when numba is absent or the locator cannot be read (nothing to
    gain by avoiding the port then)."""
    if _COMPILED or not numba_enabled():
        return True
    try:
        from numba.core.caching import FunctionCache

        index = FunctionCache(run_bdf_core)._cache_file._index_path
    except Exception:  # pragma: no cover - numba's private layout changed
        return True
    import os

    return os.path.exists(index)

