r"""The root in ``F`` of one law at a fixed elongation or rate: ``R(q, F) = 0``.

A safeguarded Newton iteration inside a bracket found by doubling steps from a start;
it reports whether the law pins ``F`` (a set-valued law, such as a stuck Bingham
dashpot, leaves ``F`` free where ``R = 0`` with ``dR/dF = 0``).
"""

from __future__ import annotations

import math

__all__ = ["scalar_root"]


def scalar_root(kernel, q: float, F0: float) -> tuple[float, bool]:
    """Solve ``R(q, F) = 0`` for ``F`` (``q`` fixed) by safeguarded Newton in a bracket.

    Returns ``(F, pinned)``: ``pinned`` is False when the law is flat in ``F`` at an
    exact root (``R = 0`` with ``dR/dF = 0``: a set-valued law, e.g. a stuck Bingham
    dashpot), so that ``F`` is not fixed by the law alone; a root found only as a sign
    change between neighbouring floats is isolated, hence pinned. Raises ValueError if
    no sign change is found.
    """
    R, _, RF = kernel(q, F0)
    if R == 0.0:
        return F0, RF != 0.0
    # bracket: expand both ways from F0
    lo = hi = None
    step = 1.0 + abs(F0)
    for _ in range(2000):
        for cand in (F0 + step, F0 - step):
            Rc = kernel(q, cand)[0]
            if Rc == 0.0:
                _, _, RFc = kernel(q, cand)
                return cand, RFc != 0.0
            if (Rc > 0.0) != (R > 0.0):
                lo, hi = (F0, cand) if cand > F0 else (cand, F0)
                break
        if lo is not None or step > 1e300:
            break
        step *= 2.0
    if lo is None:
        raise ValueError(f"no root of the law in F at q = {q!r}")
    R_lo = kernel(q, lo)[0]
    F = F0 if lo <= F0 <= hi else 0.5 * (lo + hi)
    for _ in range(400):
        R, _, RF = kernel(q, F)
        if R == 0.0:
            return F, RF != 0.0
        if (R > 0.0) == (R_lo > 0.0):
            lo, R_lo = F, R
        else:
            hi = F
        F_new = F - R / RF if RF != 0.0 else math.nan
        if not (lo < F_new < hi):
            F_new = 0.5 * (lo + hi)
        if F_new == F or not (lo < F_new < hi):
            break
        F = F_new
    # No exact zero: the root lies between floating-point neighbours (e.g. a Bingham
    # force tau + q / gamma with q / gamma below an ulp of tau, at the kink). The sign
    # change isolates it, so the law fixes F there even if the nearest float sits on a
    # flat piece: take the candidate with the smallest |R| (the correctly rounded root).
    best = min((F, lo, hi), key=lambda c: abs(kernel(q, c)[0]))
    return best, True
