r"""Stage forms: a steep branch of a law solved for its force.

A branch whose ``dR/dF`` is unbounded somewhere (Herschel-Bulkley with ``n < 1`` at its
yield force, ``dq/dF -> infinity``) is badly conditioned for Newton in its own form.  When
it has the shape ``R = alpha(q) + beta (s F + d)^p`` it can be written as ``F = G(q)``,
which has the same zeros on the branch and a bounded slope there.  The adaptive method's
stage solve takes such a branch in this *inverse form*
(:meth:`lumped.codegen.branches.LawBranches.stage_kernel_for`); the shape is read from
the law's expression, never from its name.

A branch *affine* in ``F``, ``R = A(q) + beta F`` (Bingham slipping, ``q - gamma (F -
tau)``), has a bounded ``dR/dF = beta`` but can still be steep against ``dR/dq``: its
forward form fixes ``q`` only to ``|beta| ulp(F) / |A'(q)|``, ``gamma ulp(tau)`` (2e-4 for
``gamma = 1e12``, ``tau = 1``), while its inverse ``F = tau + q / gamma`` fixes ``F`` to
its rounding. :func:`affine_inverse_form` gives that form when the branch is steep by
the numerical test :func:`affine_steepness` ``>=`` :data:`STEEP_SPAN` (``16``), decided
from the bound law's numbers.

A branch's fractional powers ``b^p`` of an expression in ``q`` or ``F`` are defined only
where ``b >= 0``, which holds on the branch; :func:`odd_continuation` continues them to
``b < 0`` as ``-(-b)^p``, so that a stage iterate a hair beyond the branch's end (inside
its guard's tolerance) gets a finite residual instead of ``nan``.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import sympy as sp

__all__ = ["STEEP_SPAN", "affine_inverse_form", "affine_steepness",
           "affine_steepness_function", "flat_inverse", "flat_root", "inverse_form",
           "odd_continuation"]

_Q, _F = sp.Symbol("q"), sp.Symbol("F")

#: A branch affine in ``F`` whose :func:`affine_steepness` is at least this is steep: its
#: forward form resolves rates of order one no finer than ``STEEP_SPAN`` ulps of its force
#: (``3.6e-15``), above the velocity tolerance of tight runs (``atol = 1e-3 rtol`` at
#: ``rtol = 1e-12``). Measured: a mass of 100 on Bingham with ``gamma tau`` = 100 to 1e3
#: in its forward form stopped at its step floor at ``rtol = 1e-12`` (the rates just
#: after a break-out were quantized at ``gamma ulp(tau)``); ``gamma tau = 10`` ran.
#: The paper's scenes (``gamma tau = 1``) stay forward, and so do any scenes with
#: ``gamma tau < 16``.
STEEP_SPAN = 16.0


def _power_shape(expr: sp.Expr):
    """``(base, p, slope, shift, alpha, beta)`` of a branch ``R = alpha(q) + beta (slope F
    + shift)^p`` (``p``, ``beta``, ``slope``, ``shift`` numbers, ``beta`` and ``slope``
    nonzero, ``F`` nowhere else, ``alpha`` holding ``q``), else ``None``."""
    pows = {node for node in sp.preorder_traversal(expr)
            if isinstance(node, sp.Pow) and node.base.has(_F)}
    if len(pows) != 1:
        return None
    (P,) = pows
    base, p = P.base, P.exp
    if not p.is_number or not p.is_positive:
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
    return base, p, slope, shift, alpha, beta


def inverse_form(expr: sp.Expr) -> tuple[sp.Expr, ...] | None:
    r"""A steep branch ``R = alpha(q) + beta (s F + d)^p`` (``p`` a non-integer number,
    ``beta, s, d`` numbers, ``F`` nowhere else) solved for ``F``:
    ``(F - G(q), -G'(q), 1, s F + d, w)`` with

    .. math:: G(q) = (w^{1/p} - d) / s,\qquad w = -\alpha(q) / \beta,

    and ``w^{1/p}`` continued oddly to ``w < 0`` (``-(-w)^{1/p}``), so that an iterate
    beyond the branch's end gives a force beyond its guard (an event) rather than ``nan``.
    ``G'(q) = r |w|^{r - 1} w'(q) / s`` (``r = 1/p``) is bounded where ``dR/dF`` is not
    (``p < 1``: ``r > 1``). ``None`` for any other shape."""
    shape = _power_shape(expr)
    if shape is None or shape[1].is_integer:
        return None
    base, p, slope, shift, alpha, beta = shape
    w = -alpha / beta
    r = 1 / p
    root = sp.Piecewise((w ** r, w >= 0), (-((-w) ** r), True))
    slope_root = sp.Piecewise((r * w ** (r - 1), w >= 0), (r * (-w) ** (r - 1), True))
    G = (root - shift) / slope
    dG = slope_root * sp.diff(w, _Q) / slope
    return _F - G, -dG, sp.S.One, base, w


def flat_root(expr: sp.Expr) -> tuple[sp.Expr, sp.Expr] | None:
    r"""``(s F + d, w)`` of a branch ``R = alpha(q) + beta (s F + d)^p`` flat at its end,
    ``p > 1`` (Herschel-Bulkley ``n > 1``: ``q = gamma (F - tau)^n``, ``dR/dF = 0`` at the
    yield force), with ``w = -alpha(q) / beta``: the power's base and the value of the
    power on the branch, which have one sign there (the power continued oddly,
    :func:`odd_continuation`). A guard that is a positive multiple of the base reads as
    ``w`` (:meth:`lumped.codegen.branches.LawBranches.stage_guards_for`): the force is
    flat there, so a stage solve fixes it only to its Newton tolerance (``1e-5`` of a
    yield force ``0.44`` at a rate of ``2.6e-11``, a step of ``3.5e-12`` s just after a
    velocity reversal at ``rtol = 1e-10``) and its guard read a false end of the slip,
    while the rate ``w`` is held to the velocities' tolerance (issue 29). ``None`` for
    any other shape."""
    shape = _power_shape(expr)
    if shape is None or not shape[1] > 1:
        return None
    return shape[0], -shape[4] / shape[5]


def flat_inverse(expr: sp.Expr) -> tuple[sp.Expr, sp.Expr] | None:
    r"""``(s F + d, G(q))`` of a branch ``R = alpha(q) + beta (s F + d)^p`` flat at its
    end (``p > 1``, :func:`flat_root`): the power's base and the branch solved for its
    force, ``G(q) = (w^{1/p} - d) / s``, ``w = -alpha(q) / beta``, ``w^{1/p}`` continued
    oddly to ``w < 0``. A stage that starts at the end (``s F + d = 0``, where ``dR/dF =
    0``) takes its forces from ``G`` at predicted rates
    (:mod:`lumped.solvers.radau.flat_start`): Newton from the end itself loads the whole
    excess force onto the branch at its first iteration (Herschel-Bulkley ``n = 1.5``,
    issue 29). ``None`` for any other shape."""
    shape = _power_shape(expr)
    if shape is None or not shape[1] > 1:
        return None
    base, p, slope, shift, alpha, beta = shape
    w = -alpha / beta
    r = 1 / p
    root = sp.Piecewise((w ** r, w >= 0), (-((-w) ** r), True))
    return base, (root - shift) / slope


def odd_continuation(expr: sp.Expr, path: tuple = ()) -> sp.Expr:
    r"""``expr`` with every power ``b^p`` (``p`` a non-integer number, ``b`` holding ``q``
    or ``F``) replaced by ``b^p`` where ``b >= 0`` and ``-(-b)^p`` where ``b < 0``; and
    every even power ``b^p`` (``p = 2, 4, ...``) whose base has one sign wherever the
    branch's ``path`` holds (a condition of the path is ``b > 0``, ``b >= 0``, or the
    opposite, up to a positive factor) continued past ``b = 0`` with the opposite sign.

    Equal to ``expr`` wherever ``expr`` is real, so on its branch. Herschel-Bulkley with
    ``n = 3/2`` on its forward slip branch, ``R = q - gamma (F - tau)^{3/2}``: a stage
    that starts at ``F = tau - 5e-6`` (a step accepted with its force within the guard's
    tolerance below the yield force) had ``R = nan``, so Newton failed on every step and
    the step size fell to its floor; now ``R = q + gamma (tau - F)^{3/2}`` there. With
    ``n = 2`` the branch ``q = -gamma (-F - tau)^2`` (``F < -tau``) has a mirror root
    ``F = -tau + sqrt(-q / gamma)`` beyond its yield force: a stage solve of a dashpot
    slipping at ``q = -7.8e-9`` from its yield force met it, ``F`` ``1.8e-4`` past the
    guard, and the run read a false event every ``1e-12`` s until it was bridged (issue
    29); continued, the branch is monotone in ``F`` and has the one root. A law even in
    its base everywhere (no condition of the path fixes the base's sign) is left alone.
    Returns ``expr`` itself when it has no such power."""
    swap = {}
    for node in sp.preorder_traversal(expr):
        if not (isinstance(node, sp.Pow) and node.exp.is_number and node.base.has(_Q, _F)):
            continue
        if not node.exp.is_integer:
            swap[node] = sp.Piecewise((node, node.base >= 0), (-((-node.base) ** node.exp),
                                                               True))
        elif node.exp.is_even and node.exp.is_positive:
            sign = _sign_on_path(node.base, path)
            if sign:
                swap[node] = sp.Piecewise((node, sign * node.base >= 0), (-node, True))
    return expr.xreplace(swap) if swap else expr


def _sign_on_path(base: sp.Expr, path: tuple) -> int:
    """``1`` (``-1``) when a condition of ``path`` says ``base > 0`` or ``base >= 0``
    (``<= 0``) up to a positive number as a factor, else ``0``."""
    for cond, want in path:
        if not isinstance(cond, sp.core.relational.Relational) or \
                isinstance(cond, (sp.Eq, sp.Ne)):
            continue
        up = cond.lhs - cond.rhs  # cond: up > 0 (>=) or up < 0 (<=)
        if isinstance(cond, (sp.StrictLessThan, sp.LessThan)):
            up = -up
        if not want:
            up = -up
        ratio = sp.simplify(base / up)
        if ratio.is_number and ratio.is_nonzero:
            return 1 if ratio.is_positive else -1
    return 0


def affine_steepness(expr: sp.Expr) -> float:
    r"""How steep a branch ``R = A(q) + beta F`` (``beta`` a nonzero number, ``F`` nowhere
    else) is in ``F`` against ``q``: the rate at which its force doubles,

    .. math:: S = \frac{|\partial R/\partial F|\,|F_0|}{|\partial R/\partial q|}
              \Big|_{q = 0,\ F = F_0},\qquad F_0 = G(0) = -A(0)/\beta,

    in the law's own units. Its forward form resolves ``q`` near ``q = 0`` only to ``S``
    ulps of a unit rate (one ulp of ``F_0`` times ``|beta| / |A'(0)|``); the inverse ``F =
    G(q)`` takes ``q`` as it is and rounds only ``F``. Bingham slipping, ``q -
    gamma (F - tau)``: ``S = gamma tau``. ``inf`` where ``A'(0) = 0`` and ``F_0 != 0``
    (``q^3 = F - tau`` resolves ``q`` to ``ulp(tau)^(1/3)``); ``0`` where ``F_0 = 0`` (a
    Newtonian ``q = gamma F`` loses nothing: ``q`` and ``gamma F`` round alike) and for any
    other shape. A number, computed once per bound law (the parameters are numbers in it).
    """
    parts = _affine_parts(expr)
    if parts is None:
        return 0.0
    A, beta = parts
    try:
        F0 = float(-A.xreplace({_Q: sp.S.Zero}) / beta)
        slope = abs(float(sp.diff(A, _Q).xreplace({_Q: sp.S.Zero})))
    except (TypeError, ValueError):
        return 0.0
    if not math.isfinite(F0) or F0 == 0.0:
        return 0.0
    if not math.isfinite(slope):
        return 0.0
    return math.inf if slope == 0.0 else abs(float(beta)) * abs(F0) / slope


def affine_steepness_function(leaf: sp.Expr, symbols: list) -> Callable[..., float]:
    """:func:`affine_steepness` of the branch ``leaf`` (in ``q``, ``F`` and the
    parameters' ``symbols``) as a float function of their values: the same formula,
    ``|beta| |F_0| / |A'(0)|``, in other roundings (a few ulps apart)."""
    from .emit import compile_function

    beta = sp.diff(leaf, _F)
    A = sp.expand(leaf - beta * _F)
    parts = [compile_function(e, symbols) for e in
             (beta, A.xreplace({_Q: sp.S.Zero}), sp.diff(A, _Q).xreplace({_Q: sp.S.Zero}))]

    def steepness(*values: float) -> float:
        b, a0, slope = (f(*values) for f in parts)
        F0, slope = (-a0 / b if b != 0.0 else math.nan), abs(slope)
        if not math.isfinite(F0) or F0 == 0.0 or not math.isfinite(slope):
            return 0.0
        return math.inf if slope == 0.0 else abs(b) * abs(F0) / slope

    return steepness


def affine_inverse_form(expr: sp.Expr) -> tuple[sp.Expr, ...] | None:
    r"""A steep branch ``R = A(q) + beta F`` (:func:`affine_steepness` ``>=``
    :data:`STEEP_SPAN`) solved for ``F``: ``(F - G(q), -G'(q), 1, base, w)`` with

    .. math:: G(q) = -A(q)/\beta,\qquad \text{base} = c\,(F - F_0),\qquad
              w(q) = c\,(G(q) - F_0),\qquad c = |\beta| / |A'(0)|,

    ``F_0 = G(0)``: the shape of :func:`inverse_form` with ``p = 1``, and ``base = w`` on
    the branch. A guard that is a positive multiple of ``base`` (``F - tau`` of a Bingham
    dashpot slipping forward) is taken as ``w`` (``q``): the branch ends at ``q = 0``,
    where ``F - tau = q / gamma`` is ``1e-12 q`` flat, so a guard in ``F`` located to
    round-off would leave a rate of ``gamma ulp(tau)``. ``c`` puts ``w`` on the scale of
    ``q`` (``dw/dq = 1`` at ``q = 0``), the scale of the guards' round-off tolerance,
    whatever the residual's own scale (``q - gamma (F - tau)`` and ``q / gamma - (F -
    tau)`` give ``w = q`` alike; ``c = |beta|`` where ``A'(0) = 0``). ``None`` when the
    branch has another shape or is not steep."""
    parts = _affine_parts(expr)
    if parts is None or not affine_steepness(expr) >= STEEP_SPAN:
        return None
    A, beta = parts
    G = sp.expand(-A / beta)
    F0 = G.xreplace({_Q: sp.S.Zero})
    slope = abs(sp.diff(A, _Q).xreplace({_Q: sp.S.Zero}))
    scale = abs(beta) / slope if slope.is_number and slope.is_finite and slope != 0 \
        else abs(beta)
    w = sp.expand(scale * (G - F0))
    return _F - G, -sp.diff(G, _Q), sp.S.One, scale * (_F - F0), w


def _affine_parts(expr: sp.Expr) -> tuple[sp.Expr, sp.Expr] | None:
    """``(A(q), beta)`` when ``expr = A(q) + beta F`` with ``beta`` a nonzero number and
    ``A`` holding ``q`` (not a lock, not a law of ``F`` alone); else ``None``."""
    if not expr.has(_F) or not expr.has(_Q):
        return None
    beta = sp.diff(expr, _F)
    if not (beta.is_number and beta.is_finite and beta != 0):
        return None
    A = sp.expand(expr - beta * _F)
    if A.has(_F) or not A.has(_Q) or A.has(sp.Piecewise):
        return None
    return A, beta
