r"""The break-out root of a held interval (:meth:`lumped.solvers.modes.stuck.StaticHold._root`)
compiled with numba.

:func:`breakout_root` finds the time where one guard of a locked element turns negative
under the static balance, as the Python reference does and with the same numbers: the
guard ``g(t) = guard_j(q_e, F_e(t))`` with ``F_e(t)`` the balance's formula
(:meth:`~lumped.solvers.modes.stuck.StaticHold.forces`, the forcing by the scalar formulas of
its kinds), the ends checked, Brent's method as :func:`scipy.optimize.brentq` takes its
steps (a port of scipy's ``brentq.c``, step for step: the same iterates, hence the same
root, bit for bit), then the walk just past the crossing. The guards come in as the
address of the scene's generated ``branch_guards`` (:mod:`lumped.codegen.jit`), so the
code is compiled once for every scene and cached on disk. A guard that is not finite or
an iteration that does not converge returns ``nan``: the caller then runs the reference,
which says what went wrong.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.function_types import function_at, guards_type
from ...codegen.jit import njit, numba_enabled
from .on_demand import compiled_once

__all__ = ["breakout_root", "breakout_scan", "brent", "compiled_breakout_root",
           "compiled_breakout_scan"]

_MAX_ITER = 100  # scipy's default


@njit(cache=True)
def _guard(guards, lawc, e, mode, j, q, r, fkind, fpar, c, minv, t, gbuf) -> float:
    """``g_j(q_e, F_e(t))`` with ``F_e`` the static balance's row ``r``."""
    N = fkind.shape[0]
    s = 0.0
    for i in range(N):
        k = fkind[i]
        f = 0.0
        if k == 1:
            f = fpar[i, 0]
        elif k == 2:
            f = 0.0 if t > fpar[i, 2] else fpar[i, 0] * math.sin(fpar[i, 1] * t)
        s += minv[r, i] * (f + c[i])
    guards(e, mode, q, s, gbuf, lawc)
    return gbuf[j]


def breakout_root(guards_addr, lawc, e, mode, j, q, r, fkind, fpar, c, minv, a, b, gbuf) -> float:
    """The break-out time of guard ``j`` of element ``e`` (held on branch ``mode`` at
    ``q``; its force the static balance's row ``r``: ``minv[r] @ (f(t) + c)``) in
    ``[a, b]``, as :meth:`lumped.solvers.modes.stuck.StaticHold._root` finds it; ``nan`` when
    a guard is not finite or Brent's method does not converge."""
    guards = _guards_at(guards_addr)
    ga = _guard(guards, lawc, e, mode, j, q, r, fkind, fpar, c, minv, a, gbuf)
    if not ga > 0.0:
        return a if ga == ga else math.nan
    gb = _guard(guards, lawc, e, mode, j, q, r, fkind, fpar, c, minv, b, gbuf)
    if gb >= 0.0:
        return b
    if gb != gb:
        return math.nan
    xtol = 4e-16 * max(1.0, abs(b))
    rtol = 1e-15
    # scipy's brentq.c, step for step
    xpre, xcur = a, b
    fpre, fcur = ga, gb
    xblk = fblk = spre = scur = 0.0
    found = False
    for _ in range(_MAX_ITER):
        if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0.0 or abs(sbis) < delta:
            found = True
            break
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:  # interpolate
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:  # extrapolate
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry  # a good short step
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = _guard(guards, lawc, e, mode, j, q, r, fkind, fpar, c, minv, xcur, gbuf)
        if fcur != fcur:
            return math.nan
    if not found:
        return math.nan
    # just past the crossing (the guard negative), as in the reference
    root = xcur
    step = np.nextafter(abs(root), math.inf) - abs(root)  # math.ulp
    while (_guard(guards, lawc, e, mode, j, q, r, fkind, fpar, c, minv, root, gbuf) >= 0.0
           and root + step < b):
        root, step = root + step, 2.0 * step
    return root


def breakout_scan(guards_addr, lawc, free, modes, q, fkind, fpar, c, minv, F0, ts, out, gbuf
                  ) -> int:
    """The scan of :meth:`lumped.solvers.modes.stuck.StaticHold.breakout` over the sample times
    ``ts``, with the same numbers: at each sample the forces of the static balance (``F0``
    but the ``free`` elements', row ``r`` of those ``minv[r] @ (f(t) + c)``, the forcing
    by the scalar formulas of its kinds) written to ``out[r]``, then every guard of every
    free element (held on branch ``modes[e]`` at ``q[e]``) against its round-off
    tolerance (:func:`lumped.solvers.modes.guards.guard_tolerance`). Returns the index of the
    first sample where a guard is below its tolerance (the rows up to it written), or
    ``-1`` when none is (all rows written)."""
    guards = _guards_at(guards_addr)
    N = fkind.shape[0]
    E = F0.shape[0]
    g = np.empty(N)
    for r in range(ts.shape[0]):
        t = ts[r]
        for i in range(N):
            k = fkind[i]
            f = 0.0
            if k == 1:
                f = fpar[i, 0]
            elif k == 2:
                f = 0.0 if t > fpar[i, 2] else fpar[i, 0] * math.sin(fpar[i, 1] * t)
            g[i] = f + c[i]
        for e in range(E):
            out[r, e] = F0[e]
        for k in range(free.shape[0]):
            s_ = 0.0
            for i in range(N):
                s_ += minv[k, i] * g[i]
            out[r, free[k]] = s_
        failed = False
        for k in range(free.shape[0]):
            e = free[k]
            Fe = out[r, e]
            n = guards(e, modes[e], q[e], Fe, gbuf, lawc)
            tol = 64.0 * 2.220446049250313e-16 * (1.0 + abs(q[e]) + abs(Fe))
            for j in range(n):
                if gbuf[j] + tol < 0.0:
                    failed = True
        if failed:
            return r
    return -1


def brent(f, xa: float, xb: float, xtol: float, rtol: float, maxiter: int = _MAX_ITER
          ) -> float:
    """The iteration of :func:`breakout_root` in Python on any ``f`` with ``f(xa)``,
    ``f(xb)`` of opposite signs (for the test against :func:`scipy.optimize.brentq`);
    raises ``RuntimeError`` when it does not converge."""
    xpre, xcur = xa, xb
    fpre, fcur = f(xpre), f(xcur)
    if fpre == 0.0:
        return xpre
    if fcur == 0.0:
        return xcur
    xblk = fblk = spre = scur = 0.0
    for _ in range(maxiter):
        if fpre != 0.0 and fcur != 0.0 and (fpre < 0.0) != (fcur < 0.0):
            xblk, fblk = xpre, fpre
            spre = scur = xcur - xpre
        if abs(fblk) < abs(fcur):
            xpre, xcur, xblk = xcur, xblk, xcur
            fpre, fcur, fblk = fcur, fblk, fcur
        delta = (xtol + rtol * abs(xcur)) / 2
        sbis = (xblk - xcur) / 2
        if fcur == 0.0 or abs(sbis) < delta:
            return xcur
        if abs(spre) > delta and abs(fcur) < abs(fpre):
            if xpre == xblk:
                stry = -fcur * (xcur - xpre) / (fcur - fpre)
            else:
                dpre = (fpre - fcur) / (xpre - xcur)
                dblk = (fblk - fcur) / (xblk - xcur)
                stry = -fcur * (fblk * dblk - fpre * dpre) / (dblk * dpre * (fblk - fpre))
            if 2 * abs(stry) < min(abs(spre), 3 * abs(sbis) - delta):
                spre, scur = scur, stry
            else:
                spre = scur = sbis
        else:
            spre = scur = sbis
        xpre, fpre = xcur, fcur
        if abs(scur) > delta:
            xcur += scur
        else:
            xcur += delta if sbis > 0 else -delta
        fcur = f(xcur)
    raise RuntimeError("brent: no convergence")


if numba_enabled():
    _guards_at = function_at(guards_type())

_COMPILED: list = []
_SCAN: list = []


def compiled_breakout_root(compile: bool = True):
    """:func:`breakout_root` compiled once for every scene (numba's disk cache after the
    first time on a machine), or ``None`` without numba; ``compile=False``: only if
    numba's disk cache holds it (:func:`lumped.solvers.modes.on_demand.compiled_once`)."""
    return compiled_once(_COMPILED, breakout_root, _root_signature, compile)


def compiled_breakout_scan(compile: bool = True):
    """:func:`breakout_scan` compiled once for every scene (numba's disk cache after the
    first time on a machine), or ``None`` without numba; ``compile=False`` as
    :func:`compiled_breakout_root`."""
    return compiled_once(_SCAN, breakout_scan, _scan_signature, compile)


def _root_signature():
    from numba import types as T_

    f8, i8 = T_.float64, T_.int64
    return f8(i8, f8[::1], i8, i8, i8, f8, i8, i8[::1], f8[:, ::1], f8[::1], f8[:, ::1], f8, f8,
              f8[::1])


def _scan_signature():
    from numba import types as T_

    f8, i8 = T_.float64, T_.int64
    return i8(i8, f8[::1], i8[::1], i8[::1], f8[::1], i8[::1], f8[:, ::1], f8[::1], f8[:, ::1],
              f8[::1], f8[::1], f8[:, ::1], f8[::1])

