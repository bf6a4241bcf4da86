r"""Branch check for non-monotone laws (fold detection).

After each step, every element whose law is not a known monotone built-in is checked for
a jump between branches: if ``dR/dq`` or ``dR/dF`` takes strictly opposite signs at the
old and new point (or, when the step leaves the tangent of the law, at points sampled on
the segment between them), the step has crossed or skipped a fold; the run then stops
with :class:`~lumped.solvers.status.BranchError`.
"""

from __future__ import annotations

__all__ = ["MONOTONE_BUILTINS"]


#: Built-in laws whose graph is monotone (no folds); their branch check is skipped.
MONOTONE_BUILTINS = frozenset(
    {"linear_spring", "string_spring", "newtonian", "bingham", "coulomb", "herschel_bulkley",
     "implicit_spring"}
)


def known_monotone(bound) -> bool:
    """True for the built-in monotone laws (their graphs have no folds)."""
    law = getattr(bound, "law", None)
    name = getattr(law, "name", None)
    if name not in MONOTONE_BUILTINS:
        return False
    try:
        from ...laws import BUILTIN_LAWS
    except ImportError:  # the law library is not there: check everything
        return False
    builtin = BUILTIN_LAWS.get(name) if isinstance(BUILTIN_LAWS, dict) else None
    return builtin is not None and (law is builtin or law == builtin)


def dead_band_sign(x: float, scale: float) -> int:
    """The sign of ``x``, 0 within ``1e-12 scale`` of zero."""
    if x > 1e-12 * scale:
        return 1
    if x < -1e-12 * scale:
        return -1
    return 0


def left_branch(kernel, q0: float, F0: float, Rq0: float, RF0: float,
                 q1: float, F1: float, Rq1: float, RF1: float) -> bool:
    """Did the step from ``(q0, F0)`` to ``(q1, F1)`` cross or skip a fold of ``R = 0``?

    A fold is where ``dR/dF`` (or ``dR/dq``) changes sign strictly. The partial
    derivatives at both ends are compared; when the step is not close to the tangent of
    the law at either end (``|R_q dq + R_F dF|`` above half of ``|R_q dq| + |R_F dF|``),
    three interior points of the segment are sampled too.
    """
    s0 = abs(Rq0) + abs(RF0)
    s1 = abs(Rq1) + abs(RF1)
    signs_q = {dead_band_sign(Rq0, s0), dead_band_sign(Rq1, s1)}
    signs_F = {dead_band_sign(RF0, s0), dead_band_sign(RF1, s1)}
    if {1, -1} <= signs_q or {1, -1} <= signs_F:
        return True
    dq, dF = q1 - q0, F1 - F0
    off = 0.0
    for Rq, RF in ((Rq0, RF0), (Rq1, RF1)):
        total = abs(Rq * dq) + abs(RF * dF)
        if total > 0.0:
            off = max(off, abs(Rq * dq + RF * dF) / total)
    if off <= 0.5:
        return False
    for s in (0.25, 0.5, 0.75):
        _, Rq, RF = kernel(q0 + s * dq, F0 + s * dF)
        sc = abs(Rq) + abs(RF)
        signs_q.add(dead_band_sign(Rq, sc))
        signs_F.add(dead_band_sign(RF, sc))
        if {1, -1} <= signs_q or {1, -1} <= signs_F:
            return True
    return False
