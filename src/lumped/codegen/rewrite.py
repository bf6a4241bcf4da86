r"""Prepare a law residual for code generation: kinks -> ``Piecewise``, branch-wise
derivatives, and the magnitude of the terms.

* :func:`check_supported` refuses anything the emitter cannot turn into plain code.
* :func:`rewrite_kinks` turns every kink into an explicit ``Piecewise``::

      Max(a, b)      -> Piecewise((a, a >= b), (b, True))
      Min(a, b)      -> Piecewise((a, a <= b), (b, True))
      Abs(a)         -> Piecewise((a, a >= 0), (-a, True))
      sign(a)        -> Piecewise((1, a > 0), (-1, a < 0), (0, True))
      Heaviside(a,h) -> Piecewise((1, a > 0), (0, a < 0), (h, True))

  so that the value and the derivative always come from the same smooth piece (the
  generalised Jacobian is discussed in :mod:`lumped.codegen.emit`).
* :func:`diff_branchwise` differentiates every ``Piecewise`` branch by branch, keeping
  its conditions.
* :func:`magnitude_expression` replaces every sum by the sum of its terms' magnitudes:
  ``eps * magnitude`` is the scale of the residual's round-off.
* :func:`prepare` substitutes the parameters (with sympy's distribution of numbers over
  sums switched off) and returns ``(R, dR/dq, dR/dF)`` ready for the emitter.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping

import sympy as sp
from sympy.core.parameters import distribute

__all__ = [
    "check_supported",
    "constant_of",
    "constants_of",
    "diff_branchwise",
    "exponent_symbols",
    "magnitude_expression",
    "prepare",
    "rewrite_kinks",
]


_FUNCTION_CLASSES: tuple[type, ...] = (
    sp.sin,
    sp.cos,
    sp.tan,
    sp.asin,
    sp.acos,
    sp.atan,
    sp.atan2,
    sp.sinh,
    sp.cosh,
    sp.tanh,
    sp.asinh,
    sp.acosh,
    sp.atanh,
    sp.exp,
    sp.log,
    sp.Abs,
    sp.sign,
    sp.Max,
    sp.Min,
    sp.Heaviside,
)
_STRUCTURAL: tuple[type, ...] = (
    sp.Symbol,
    sp.Add,
    sp.Mul,
    sp.Pow,
    sp.Piecewise,
    sp.core.relational.Relational,
    sp.And,
    sp.Or,
    sp.Not,
    sp.ITE,
    sp.logic.boolalg.BooleanTrue,
    sp.logic.boolalg.BooleanFalse,
    sp.functions.elementary.piecewise.ExprCondPair,
)


def check_supported(expr: sp.Basic) -> None:
    """Raise ``ValueError`` if ``expr`` holds anything the code generator cannot emit.

    Accepted: symbols, finite real numbers, ``pi``, ``E``, ``+ - * / **``, the
    functions of :data:`lumped.laws.parser.ALLOWED_FUNCTIONS`, ``Piecewise`` with
    comparisons, ``And``, ``Or``, ``Not``.  Refused, e.g.: undefined functions
    ``f(q)``, ``I``, ``oo``, ``nan``, derivatives, integrals.
    """
    for node in sp.preorder_traversal(expr):
        if isinstance(node, sp.Number):
            if not (node.is_finite and node.is_real) or node is sp.nan:
                raise ValueError(f"number {node} is not a finite real number")
        elif node in (sp.pi, sp.E):
            continue
        elif isinstance(node, sp.Eq | sp.Ne) or isinstance(node, _STRUCTURAL):
            continue
        elif isinstance(node, _FUNCTION_CLASSES):
            continue
        else:
            raise ValueError(
                f"unsupported term {node} ({type(node).__name__}) in a law residual"
            )


def _depends(expr: sp.Basic) -> bool:
    return bool(expr.free_symbols)


def _ordered(args: tuple[sp.Expr, ...]) -> list[sp.Expr]:
    # arguments that depend on (q, F) first, each group in sympy's canonical order
    return [a for a in args if _depends(a)] + [a for a in args if not _depends(a)]


def _max(args: list[sp.Expr], ge: Callable[[sp.Expr, sp.Expr], sp.Basic]) -> sp.Expr:
    if len(args) == 1:
        return args[0]
    head, rest = args[0], _max(args[1:], ge)
    return sp.Piecewise((head, ge(head, rest)), (rest, True), evaluate=False)


def _as_clip(e: sp.Basic) -> tuple[sp.Expr, sp.Expr, sp.Expr] | None:
    """``(x, lo, hi)`` if ``e`` is ``Min(Max(x, lo), hi)`` or ``Max(Min(x, hi), lo)``
    with numbers ``lo <= hi`` and ``x`` depending on ``(q, F)``, else ``None``."""
    if not isinstance(e, sp.Min | sp.Max) or len(e.args) != 2:
        return None
    inner_type = sp.Max if isinstance(e, sp.Min) else sp.Min
    inner = [a for a in e.args if isinstance(a, inner_type) and len(a.args) == 2]
    outer = [a for a in e.args if isinstance(a, sp.Number)]
    if len(inner) != 1 or len(outer) != 1:
        return None
    xs = [a for a in inner[0].args if _depends(a)]
    bounds = [a for a in inner[0].args if isinstance(a, sp.Number)]
    if len(xs) != 1 or len(bounds) != 1:
        return None
    lo, hi = (bounds[0], outer[0]) if isinstance(e, sp.Min) else (outer[0], bounds[0])
    if not bool(lo <= hi):
        return None
    return xs[0], lo, hi


def outer_piecewise(exprs: list[sp.Expr]) -> list[sp.Piecewise]:
    """The outermost ``Piecewise`` nodes of ``exprs`` (not those nested inside another),
    each once, in order of first appearance."""
    found: list[sp.Piecewise] = []

    def visit(e: sp.Basic) -> None:
        if isinstance(e, sp.Piecewise):
            if e not in found:
                found.append(e)
            return
        for a in e.args:
            visit(a)

    for e in exprs:
        visit(e)
    return found


def diff_branchwise(expr: sp.Expr, x: sp.Symbol) -> sp.Expr:
    """``d expr / dx``, differentiating every ``Piecewise`` branch by branch.

    Unlike :func:`sympy.diff`, the derivative of a ``Piecewise`` keeps exactly the
    conditions of the original (sympy merges neighbouring branches whose derivatives
    coincide), so a value and its derivatives can share one ``if`` chain.
    """
    pieces = outer_piecewise([expr])
    if not pieces:
        return sp.diff(expr, x)
    dummies = [sp.Dummy(f"pw{i}") for i in range(len(pieces))]
    opaque = expr.xreplace(dict(zip(pieces, dummies, strict=True)))
    back = dict(zip(dummies, pieces, strict=True))
    total = sp.diff(opaque, x).xreplace(back)
    for pw, d in zip(pieces, dummies, strict=True):
        outer = sp.diff(opaque, d)
        if outer == 0:
            continue
        branches = [diff_branchwise(e, x) for e, _ in pw.args]
        if pw.args[-1].cond is sp.true and all(b == branches[0] for b in branches):
            inner = branches[0]  # the same on every branch (e.g. 0): no chain needed
        else:
            inner = sp.Piecewise(
                *[(b, c) for b, (_, c) in zip(branches, pw.args, strict=True)], evaluate=False
            )
        total += outer.xreplace(back) * inner
    return total


def rewrite_kinks(expr: sp.Basic) -> sp.Basic:
    """Rewrite ``Max, Min, Abs, sign, Heaviside`` as explicit ``Piecewise`` (bottom-up).

    See the module docstring for the rules and for which branch wins a tie.
    """
    cache: dict[sp.Basic, sp.Basic] = {}

    def walk(e: sp.Basic) -> sp.Basic:
        hit = cache.get(e)
        if hit is not None:
            return hit
        clip = _as_clip(e)
        if clip is not None:
            x, lo, hi = clip
            x = walk(x)
            out = sp.Piecewise((lo, sp.Lt(x, lo)), (hi, sp.Gt(x, hi)), (x, True), evaluate=False)
        elif not e.args:
            out = e
        else:
            args = tuple(walk(a) for a in e.args)
            if isinstance(e, sp.Max):
                out = _max(_ordered(args), sp.Ge)
            elif isinstance(e, sp.Min):
                out = _max(_ordered(args), sp.Le)
            elif isinstance(e, sp.Abs):
                (a,) = args
                out = sp.Piecewise((a, sp.Ge(a, 0)), (-a, True), evaluate=False)
            elif isinstance(e, sp.sign):
                (a,) = args
                out = sp.Piecewise(
                    (sp.S.One, sp.Gt(a, 0)), (-sp.S.One, sp.Lt(a, 0)), (sp.S.Zero, True),
                    evaluate=False,
                )
            elif isinstance(e, sp.Heaviside):
                a = args[0]
                half = args[1] if len(args) > 1 else sp.S.Half
                out = sp.Piecewise(
                    (sp.S.One, sp.Gt(a, 0)), (sp.S.Zero, sp.Lt(a, 0)), (half, True),
                    evaluate=False,
                )
            elif args == e.args:
                out = e
            else:
                out = e.func(*args)
        cache[e] = out
        return out

    return walk(expr)


def constant_of(sym: sp.Symbol, value: float, exponent: bool = True) -> sp.Number:
    """The sympy number a parameter's ``value`` is substituted as.

    Integral values become sympy Integers where the parameter is an ``exponent`` (of a
    power in the expression), so that ``n = 1`` gives ``x**1 = x`` and ``n = 2`` a
    product: the branch's shape, as for the other integral values. Zero becomes the
    Integer 0 everywhere: sympy drops a term with a factor 0, the form of the law
    without it. Every other value stays a float: sympy drops a factor ``Integer(1)``
    from the code and prints ``Integer(100)`` as ``100``, so ``gamma = 1`` or ``k = 100``
    gave another text of the compiled module than every other value, and another law
    class (:mod:`lumped.codegen.parametric`): a user who edited such a number derived
    the law again in sympy or compiled a law module for one number. ``1.0*y`` is ``y``
    to the bit, and ``100.0*y`` is ``100*y``: the numbers are the same.
    """
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"parameter `{sym}` must be finite, got {x!r}")
    if not x.is_integer() or abs(x) >= 2**53 or (not exponent and x != 0.0):
        return sp.Float(x)
    return sp.Integer(int(x))


def exponent_symbols(expr: sp.Expr) -> set:
    """The symbols that appear in the exponent of a power of ``expr``."""
    exponents: set = set()
    for node in sp.preorder_traversal(expr):
        if isinstance(node, sp.Pow):
            exponents |= node.exp.free_symbols
    return exponents


def constants_of(expr: sp.Expr, params: Mapping[sp.Symbol, float]) -> dict:
    """``{symbol: constant_of(symbol, value, exponent)}`` for ``params`` in ``expr``,
    ``exponent`` whether the symbol appears in the exponent of one of its powers."""
    exponents = exponent_symbols(expr)
    return {sym: constant_of(sym, value, sym in exponents) for sym, value in params.items()}


def prepare(
    residual: sp.Expr, q: sp.Symbol, F: sp.Symbol, params: Mapping[sp.Symbol, float]
) -> tuple[sp.Expr, sp.Expr, sp.Expr]:
    """Return ``(R, dR/dq, dR/dF)`` with parameters substituted and kinks rewritten.

    The symbols ``q`` and ``F`` are renamed to plain ``Symbol("q")`` and ``Symbol("F")``.
    """
    residual = sp.sympify(residual) if not isinstance(residual, sp.Basic) else residual
    if not isinstance(residual, sp.Expr):
        raise TypeError(f"`residual` must be a sympy expression, got {type(residual).__name__}")
    if not isinstance(q, sp.Symbol) or not isinstance(F, sp.Symbol) or q == F:
        raise TypeError("`q` and `F` must be two distinct sympy symbols")
    check_supported(residual)
    values = constants_of(residual, params)
    qq, FF = sp.Symbol("q"), sp.Symbol("F")
    with distribute(False):
        expr = residual.xreplace(values).xreplace({q: qq, F: FF})
    unbound = sorted(str(s) for s in expr.free_symbols - {qq, FF})
    if unbound:
        raise ValueError(f"residual has symbols without a value: {', '.join(unbound)}")
    if expr.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
        raise ValueError(f"residual is undefined with these parameters: {expr}")
    with distribute(False):
        expr = rewrite_kinks(expr)
        return expr, diff_branchwise(expr, qq), diff_branchwise(expr, FF)


def magnitude_expression(expr: sp.Expr) -> sp.Expr:
    r"""The magnitude of the terms of ``expr``: the scale of its round-off.

    Built bottom-up on the prepared expression (kinks already ``Piecewise``)::

        M(a + b + ...)  = M(a) + M(b) + ...
        M(a * b * ...)  = M(a) * M(b) * ...
        M(a ** p)       = M(a) ** p               (p a positive number)
        M(Piecewise((e_i, c_i), ...)) = Piecewise((M(e_i), c_i), ...)   (same conditions)
        M(number)       = |number|,   M(anything else) = |anything else|

    ``M >= |expr|`` everywhere, with equality when no terms cancel; evaluating ``expr``
    in floating point errs by a few ``eps * M`` (each operation errs by ``eps`` of its
    result, and every intermediate result is bounded by the ``M`` of its subtree, up to
    the rounding of non-polynomial functions).  Where terms cancel, ``M`` keeps their
    size: for Bingham, ``q - gamma (F - clip(F))`` has ``M = |q| + gamma (|F| + |clip F|)``,
    also on the stuck piece where the residual is exactly ``q``.
    """
    cache: dict[sp.Basic, sp.Expr] = {}

    def mag(e: sp.Basic) -> sp.Expr:
        hit = cache.get(e)
        if hit is not None:
            return hit
        if isinstance(e, sp.Number):
            out = abs(e)
        elif isinstance(e, sp.Add):
            out = sp.Add(*[mag(a) for a in e.args], evaluate=False)
        elif isinstance(e, sp.Mul):
            out = sp.Mul(*[mag(a) for a in e.args], evaluate=False)
        elif (isinstance(e, sp.Pow) and isinstance(e.exp, sp.Number)
              and bool(e.exp > 0)):
            out = sp.Pow(mag(e.base), e.exp, evaluate=False)
        elif isinstance(e, sp.Piecewise):
            out = sp.Piecewise(*[(mag(v), c) for v, c in e.args], evaluate=False)
        elif isinstance(e, sp.Symbol):
            out = sp.Piecewise((e, sp.Ge(e, 0)), (-e, True), evaluate=False)
        else:
            out = sp.Piecewise((e, sp.Ge(e, 0)), (-e, True), evaluate=False)
        cache[e] = out
        return out

    return mag(expr)
