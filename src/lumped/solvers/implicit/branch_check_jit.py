r"""The branch check of :mod:`lumped.solvers.implicit.branch_check`, compiled with numba:
the sign with a dead band and the fold test of one element over a step.

The fold test reads ``dR/dq`` and ``dR/dF`` at both ends of the step (and at three
interior points when the step leaves the law's tangent); strictly opposite signs of
either mean the step crossed a fold of a non-monotone law.
"""

from __future__ import annotations

from ...codegen.jit import njit
from .branch_check import dead_band_sign as _dead_band_sign

__all__ = ["dead_band_sign", "sign_bit", "left_branch"]


#: The reference's sign with a dead band
#: (:func:`lumped.solvers.implicit.branch_check.dead_band_sign`), compiled.
dead_band_sign = njit(cache=True, inline="always")(_dead_band_sign)


@njit(cache=True, inline="always")
def left_branch(element_law, c, e, q0, F0, Rq0, RF0, q1, F1, Rq1, RF1) -> bool:
    """The fold test of :func:`lumped.solvers.implicit.branch_check.left_branch` for element ``e``:
    ``dR/dq`` or ``dR/dF`` of strictly opposite signs at the two ends, or at three
    interior points when the step leaves the law's tangent. ``c``: the scene's law
    constants (``element_law(e, q, F, c)``)."""
    s0 = abs(Rq0) + abs(RF0)
    s1 = abs(Rq1) + abs(RF1)
    # sign sets as bit masks: 1 for +1, 2 for -1 (0 adds nothing)
    mq = sign_bit(dead_band_sign(Rq0, s0)) | sign_bit(dead_band_sign(Rq1, s1))
    mf = sign_bit(dead_band_sign(RF0, s0)) | sign_bit(dead_band_sign(RF1, s1))
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
        _, Rq, RF = element_law(e, q0 + s * dq, F0 + s * dF, c)
        sc = abs(Rq) + abs(RF)
        mq |= sign_bit(dead_band_sign(Rq, sc))
        mf |= sign_bit(dead_band_sign(RF, sc))
        if mq == 3 or mf == 3:
            return True
    return False


@njit(cache=True, inline="always")
def sign_bit(s: int) -> int:
    return 1 if s > 0 else (2 if s < 0 else 0)
