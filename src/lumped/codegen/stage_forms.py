r"""Stage forms: a steep branch of a law solved for its force.

A branch whose ``dR/dF`` is unbounded somewhere (Herschel-Bulkley with ``n < 1`` at its
yield force, ``dq/dF -> infinity``) is badly conditioned for Newton in its own form.  When
it has the shape ``R = alpha(q) + beta (s F + d)^p`` it can be written as ``F = G(q)``,
which has the same zeros on the branch and a bounded slope there.  The adaptive method's
stage solve takes such a branch in this *inverse form*
(:meth:`lumped.codegen.branches.LawBranches.stage_kernel_for`); the shape is read from
the law's expression, never from its name.

A branch's fractional powers ``b^p`` of an expression in ``q`` or ``F`` are defined only
where ``b >= 0``, which holds on the branch; :func:`odd_continuation` continues them to
``b < 0`` as ``-(-b)^p``, so that a stage iterate a hair beyond the branch's end (inside
its guard's tolerance) gets a finite residual instead of ``nan``.
"""

from __future__ import annotations

import sympy as sp

__all__ = ["inverse_form", "odd_continuation"]

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


def odd_continuation(expr: sp.Expr) -> sp.Expr:
    r"""``expr`` with every power ``b^p`` (``p`` a non-integer number, ``b`` holding ``q``
    or ``F``) replaced by ``b^p`` where ``b >= 0`` and ``-(-b)^p`` where ``b < 0``.

    Equal to ``expr`` wherever ``expr`` is real, so on its branch. Herschel-Bulkley with
    ``n = 3/2`` on its forward slip branch, ``R = q - gamma (F - tau)^{3/2}``: a stage
    that starts at ``F = tau - 5e-6`` (a step accepted with its force within the guard's
    tolerance below the yield force) had ``R = nan``, so Newton failed on every step and
    the step size fell to its floor; now ``R = q + gamma (tau - F)^{3/2}`` there.
    Returns ``expr`` itself when it has no such power."""
    pows = [node for node in sp.preorder_traversal(expr)
            if isinstance(node, sp.Pow) and node.exp.is_number and not node.exp.is_integer
            and node.base.has(_Q, _F)]
    if not pows:
        return expr
    return expr.xreplace({P: sp.Piecewise((P, P.base >= 0), (-((-P.base) ** P.exp), True))
                          for P in pows})
