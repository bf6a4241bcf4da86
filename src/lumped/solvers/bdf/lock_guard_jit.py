r"""The guard of the compiled BDF on scenes with position locks: the first sample the
reference would not have computed as a plain step.

A step of the reference :func:`lumped.solvers.bdf.fixed_step.run_bdf` is the plain step
of the compiled loops (the same step system, the same Newton) unless

* it ends with a spring-like element on a locking branch that was not on one at the
  start of the step: a *new lock*, which the reference redoes as an impact (located in
  the step, an impulse, a BDF1 restart) -- a lock held through the step, or released,
  changes nothing in the step;
* it ends with two or more elements on cycles of the network (ground a vertex;
  :func:`lumped.solvers.nonsmooth.locks.cyclic_elements`) free of force (``dR/dF = 0``:
  a taut string, a stuck dashpot): the forces may be indeterminate, which the reference
  solves by minimum-norm Newton corrections and logs.

:func:`first_unkept_row` finds the first sample that is either (the compiled loop's
samples from it on are dropped and the reference takes over). *Locked* and *force-free*
are read off the scene's compiled kernels (:mod:`lumped.codegen.jit`'s ``element_law``,
whose value and generalised Jacobian at a point are those of the active branch): an
element is force-free where its ``dR/dF`` is 0 (or not finite), and a spring-like
element is locked where it is force-free and its ``dR/dq`` is not 0 -- the test of
:func:`lumped.solvers.nonsmooth.impacts.lock_state` read off the active branch's
derivatives (a locking branch has ``dR/dF`` identically 0 and depends on ``q``).
"""

from __future__ import annotations

from ...codegen.jit import njit, numba_enabled

__all__ = ["compiled_first_unkept_row", "first_unkept_row"]


@njit(cache=True, inline="always")
def _derivatives(element_law, lawc, ea, eb, spring, xs, vs, Fs, r, e):
    """``(dR/dq, dR/dF)`` of element ``e`` at sample ``r`` (``q = y_b - y_a``, ``y`` the
    displacements of a spring, the velocities of a dashpot; ground ``-1`` at 0)."""
    a, b = ea[e], eb[e]
    y = xs if spring[e] else vs
    q = (y[r, b] if b >= 0 else 0.0) - (y[r, a] if a >= 0 else 0.0)
    _, Rq, RF = element_law(e, q, Fs[r, e], lawc)
    return Rq, RF


@njit(cache=True, inline="always")
def _free(RF) -> bool:
    return not (RF != 0.0 and abs(RF) < 1e308)


def first_unkept_row(element_law, lawc, ea, eb, spring, lockable, cyclic, was_locked, xs,
                     vs, Fs, r0: int, r1: int) -> int:
    """The first row ``r0 <= r < r1`` of the samples ``xs, vs`` (node
    displacements and velocities) and ``Fs`` (element forces) at which an element of
    ``lockable`` is locked that was not at row ``r - 1``, or two elements of ``cyclic``
    are force-free (see the module notes); ``r1`` if none (``r0 >= 1``). ``was_locked``
    (one flag per element of ``lockable``) is a workspace."""
    for c in range(lockable.shape[0]):
        Rq, RF = _derivatives(element_law, lawc, ea, eb, spring, xs, vs, Fs, r0 - 1,
                              lockable[c])
        was_locked[c] = _free(RF) and Rq != 0.0
    for r in range(r0, r1):
        for c in range(lockable.shape[0]):
            Rq, RF = _derivatives(element_law, lawc, ea, eb, spring, xs, vs, Fs, r,
                                  lockable[c])
            now = _free(RF) and Rq != 0.0
            if now and not was_locked[c]:
                return r
            was_locked[c] = now
        free = 0
        for c in range(cyclic.shape[0]):
            _, RF = _derivatives(element_law, lawc, ea, eb, spring, xs, vs, Fs, r, cyclic[c])
            if _free(RF):
                free += 1
        if free >= 2:
            return r
    return r1


_COMPILED: list = []


def compiled_first_unkept_row():
    """:func:`first_unkept_row` compiled for the scene's ``element_law`` function pointer
    (once per process, from numba's disk cache after the first time on a machine); the
    plain function when numba is absent or disabled."""
    if not numba_enabled():
        return first_unkept_row
    if not _COMPILED:
        from numba import types as T

        from .core_jit import ELEMENT_LAW_TYPE

        f8, i8, b1 = T.float64, T.int64, T.boolean
        iv, m = i8[::1], f8[:, ::1]
        sig = T.int64(ELEMENT_LAW_TYPE, f8[::1], iv, iv, b1[::1], iv, iv, b1[::1], m, m, m,
                      i8, i8)
        _COMPILED.append(njit(sig, cache=True)(first_unkept_row))
    return _COMPILED[0]
