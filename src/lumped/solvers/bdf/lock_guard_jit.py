r"""The guard of the compiled BDF on scenes with position locks: the first sample at which
a spring-like element's law is on a locking branch.

:func:`lumped.solvers.nonsmooth.impacts.lock_state` reads the active branch of a law at
``(q, F)`` from its generated branches; a locking branch fixes ``q`` and leaves ``F``
free, so its ``dR/dF`` is identically 0. :func:`first_locked_row` reads the same off
the scene's compiled kernel (:mod:`lumped.codegen.jit`'s ``element_law``, whose value and
generalised Jacobian at a point are those of the active branch): a sample where
``dR/dF == 0`` (or is not finite) for a lockable element is *locked*. The test can only
err on the safe side -- a branch with ``dR/dF`` vanishing at one point is taken as a lock,
and such a sample is then recomputed by the reference, which gives the same numbers --
never miss a lock.
"""

from __future__ import annotations

from ...codegen.jit import njit, numba_enabled

__all__ = ["compiled_first_locked_row", "first_locked_row"]


def first_locked_row(element_law, lawc, ea, eb, lockable, xs, Fs, r0: int, r1: int) -> int:
    """The first row ``r`` in ``r0 .. r1 - 1`` of the samples ``xs`` (node displacements)
    and ``Fs`` (element forces) at which an element of ``lockable`` (spring-like: ``q =
    x_b - x_a``, ground ``-1`` at 0) has ``dR/dF == 0`` or not finite; ``r1`` if none."""
    for r in range(r0, r1):
        for c in range(lockable.shape[0]):
            e = lockable[c]
            a, b = ea[e], eb[e]
            q = (xs[r, b] if b >= 0 else 0.0) - (xs[r, a] if a >= 0 else 0.0)
            _, _, RF = element_law(e, q, Fs[r, e], lawc)
            if not (RF != 0.0 and abs(RF) < 1e308):
                return r
    return r1


_COMPILED: list = []


def compiled_first_locked_row():
    """:func:`first_locked_row` compiled for the scene's ``element_law`` function pointer
    (once per process, from numba's disk cache after the first time on a machine); the
    plain function when numba is absent or disabled."""
    if not numba_enabled():
        return first_locked_row
    if not _COMPILED:
        from numba import types as T

        from .core_jit import ELEMENT_LAW_TYPE

        f8, i8 = T.float64, T.int64
        sig = T.int64(ELEMENT_LAW_TYPE, f8[::1], i8[::1], i8[::1], i8[::1], f8[:, ::1],
                      f8[:, ::1], i8, i8)
        _COMPILED.append(njit(sig, cache=True)(first_locked_row))
    return _COMPILED[0]

