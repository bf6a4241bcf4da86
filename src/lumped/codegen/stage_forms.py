r"""Stage forms: a steep branch of a law solved for its force.

A branch whose ``dR/dF`` is unbounded somewhere (Herschel-Bulkley with ``n < 1`` at its
yield force, ``dq/dF -> infinity``) is badly conditioned for Newton in its own form.  When
it has the shape ``R = alpha(q) + beta (s F + d)^p`` it can be written as ``F = G(q)``,
which has the same zeros on the branch and a bounded slope there.  The adaptive method's
stage solve takes such a branch in this *inverse form*
(:meth:`lumped.codegen.branches.LawBranches.stage_kernel_for`); the shape is read from
the law's expression, never from its name.
"""

from __future__ import annotations

import sympy as sp

__all__ = ["inverse_form"]

_Q, _F = sp.Symbol("q"), sp.Symbol("F")


def inverse_form(expr: sp.Expr) -> tuple[sp.Expr, ...] | None:
    r"""A steep branch ``R = alpha(q) + beta (s F + d)^p`` (``p`` a non-integer number,
    ``beta, s, d`` numbers, ``F`` nowhere else) solved for ``F``:
    ``(F - G(q), -G'(q), 1, s F + d, w)`` with

    .. math:: G(q) = (w^{1/p} - d) / s,\qquad w = -\alpha(q) / \beta,

    and ``w^{1/p}`` continued oddly to ``w < 0`` (``-(-w)^{1/p}``), so that an iterate
    beyond the branch's end gives a force beyond its guard (an event) rather than ``nan``.
    ``G'(q) = r |w|^{r - 1} w'(q) / s`` (``r = 1/p``) is bounded where ``dR/dF`` is not
    (``p < 1``: ``r > 1``). ``None`` for any other shape."""
    pows = {node for node in sp.preorder_traversal(expr)
            if isinstance(node, sp.Pow) and node.base.has(_F)}
    if len(pows) != 1:
        return None
    (P,) = pows
    base, p = P.base, P.exp
    if not p.is_number or p.is_integer or not p.is_positive:
        return None
    slope = sp.diff(base, _F)
    shift = sp.expand(base - slope * _F)
    if not (slope.is_number and slope != 0 and shift.is_number):
        return None
    X = sp.Dummy("X")
    rest = expr.xreplace({P: X})
    if rest.has(_F):
        return None
    beta = sp.diff(rest, X)
    alpha = sp.expand(rest - beta * X)
    if not (beta.is_number and beta != 0) or alpha.has(X) or not alpha.has(_Q):
        return None
    w = -alpha / beta
    r = 1 / p
    root = sp.Piecewise((w ** r, w >= 0), (-((-w) ** r), True))
    slope_root = sp.Piecewise((r * w ** (r - 1), w >= 0), (r * (-w) ** (r - 1), True))
    G = (root - shift) / slope
    dG = slope_root * sp.diff(w, _Q) / slope
    return _F - G, -dG, sp.S.One, base, w
