r"""Compile a law residual ``R(q, F)`` into a plain scalar Python kernel.

:func:`compile_kernel` turns a sympy residual into a function
``kernel(q, F) -> (R, dR/dq, dR/dF)`` that uses only float arithmetic, comparisons,
``if``/``else`` and the :mod:`math` module: no numpy, no sympy at run time, so a JIT
(numba) could take the generated source unchanged.  The source is kept on the
function as ``kernel.__source__``.

Steps
-----
1. The parameters are substituted as float constants, with sympy's automatic
   distribution of numbers over sums switched off, so ``gamma*(F - p)`` is evaluated
   as written and not as ``gamma*F - gamma*p`` (which loses ``gamma * eps * |F|`` to
   cancellation when ``gamma`` is large).
2. Every kink is rewritten as an explicit ``Piecewise`` (see *Generalised Jacobian*).
3. ``dR/dq`` and ``dR/dF`` are taken symbolically, every ``Piecewise`` branch by
   branch with its conditions kept (:func:`diff_branchwise`).
4. Code is emitted for ``(R, dR/dq, dR/dF)`` together.  Each ``Piecewise`` becomes an
   ``if``/``else`` block that evaluates *only* the active branch (so ``sqrt`` of a
   negative number, ``log(0)`` or a division by zero in an inactive branch is never
   computed), and each straight-line stretch goes through :func:`sympy.cse`, so common
   subexpressions (also those shared between ``R`` and its derivatives) are computed
   once.  A ``Piecewise`` or condition already computed in an enclosing block is
   reused, never recomputed.
5. The source is compiled once and cached by ``(residual, q, F, parameter values)``.

Magnitude of the terms
----------------------
Each kernel also carries ``kernel.magnitude(q, F) -> float``, generated from the same
prepared expression by :func:`magnitude_expression`: the residual with every sum
replaced by the sum of its terms' magnitudes (``|a + b| -> |a| + |b|``, products and
positive powers of magnitudes, ``|f(...)|`` for any other function, the same
``Piecewise`` conditions).  ``eps * magnitude`` is the size of the residual's
round-off, also where its terms cancel exactly (Bingham, stuck:
``q - gamma (F - F) = q``, magnitude ``|q| + 2 gamma |F|``).  The Newton solver uses it
as the scale of a law row's residual.

Generalised Jacobian at kinks
-----------------------------
The kernel returns the derivative *of the branch that supplies the value*: the value
and the derivative always come from the same smooth piece.  The rewrites are::

    Max(a, b)      -> Piecewise((a, a >= b), (b, True))
    Min(a, b)      -> Piecewise((a, a <= b), (b, True))
    Abs(a)         -> Piecewise((a, a >= 0), (-a, True))
    sign(a)        -> Piecewise((1, a > 0), (-1, a < 0), (0, True))
    Heaviside(a,h) -> Piecewise((1, a > 0), (0, a < 0), (h, True))    (h = 1/2 by default)

For ``Max``/``Min`` the argument that depends on ``(q, F)`` is put first, so at a tie
with a constant it wins: the kink of ``clip(F, -tau, tau) = Min(Max(F, -tau), tau)``
belongs to its sloped (identity) piece (a clip with constant bounds is emitted as one
three-way chain ``lo if x < lo else hi if x > hi else x``, same rule).  For the
friction laws this means that *at* the threshold the Jacobian is the one of the stuck
branch (Bingham: ``dR/dq = 1, dR/dF = 0``).  Between two arguments that both depend
on ``(q, F)`` sympy's canonical argument order decides; ``Abs`` takes the right-hand
slope at 0.  The derivative so chosen is the gradient of an active smooth piece: an
element of the B-subdifferential (hence of Clarke's generalised Jacobian) whenever that
piece is active on a set with non-empty interior next to the kink, which is the case
for every built-in law, and in all cases a valid Newton derivative for semismooth
Newton.

Failure values
--------------
Where the residual is undefined or overflows (``math`` domain error, overflow,
division by zero) the kernel returns ``(nan, nan, nan)`` instead of raising; the
caller (the Newton solver) must treat a non-finite triple as a failed evaluation.
A ``Piecewise`` without a ``True`` fallback is ``nan`` where no condition holds.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping, Sequence

import sympy as sp
from sympy.core.parameters import distribute
from sympy.printing.pycode import PythonCodePrinter

__all__ = [
    "Kernel",
    "check_supported",
    "compile_function",
    "compile_kernel",
    "diff_branchwise",
    "magnitude_expression",
    "prepare",
    "rewrite_kinks",
]

#: ``kernel(q, F) -> (R, dR/dq, dR/dF)``.
Kernel = Callable[[float, float], tuple[float, float, float]]

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
    functions of :data:`lumped.expressions.ALLOWED_FUNCTIONS`, ``Piecewise`` with
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


def _outer_piecewise(exprs: list[sp.Expr]) -> list[sp.Piecewise]:
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
    pieces = _outer_piecewise([expr])
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


class _Printer(PythonCodePrinter):
    """Python printer whose numbers are exact float literals and powers stay real."""

    def __init__(self) -> None:
        super().__init__({"fully_qualified_modules": True, "standard": "python3"})

    def _float_literal(self, value: float) -> str:
        if not math.isfinite(value):
            raise ValueError(f"constant {value!r} is not finite")
        return repr(value)

    def _print_Integer(self, expr: sp.Integer) -> str:  # noqa: N802 (sympy API)
        try:
            return self._float_literal(float(int(expr)))
        except OverflowError:
            raise ValueError(f"integer constant {expr} is too large for a float") from None

    def _print_Rational(self, expr: sp.Rational) -> str:  # noqa: N802
        return self._float_literal(float(expr))

    def _print_Float(self, expr: sp.Float) -> str:  # noqa: N802
        return self._float_literal(float(expr))

    def _print_Half(self, expr: sp.Rational) -> str:  # noqa: N802
        return "0.5"

    def _operand(self, expr: sp.Expr) -> str:
        text = self._print(expr)
        if isinstance(expr, sp.Symbol) or (isinstance(expr, sp.Number) and expr >= 0):
            return text
        if isinstance(expr, sp.Function) or expr in (sp.pi, sp.E):
            return text
        return f"({text})"

    def _print_Pow(self, expr: sp.Pow, rational: bool = False) -> str:  # noqa: N802
        base, exponent = expr.as_base_exp()
        if isinstance(exponent, sp.Integer):
            n = int(exponent)
            if n == 0:
                return "1.0"
            if n > 0:
                return f"{self._operand(base)}**{n}"
            if n == -1:
                return f"1.0/{self._operand(base)}"
            return f"1.0/{self._operand(base)}**{-n}"
        if exponent == sp.S.Half:
            return f"math.sqrt({self._print(base)})"
        if exponent == -sp.S.Half:
            return f"1.0/math.sqrt({self._print(base)})"
        # math.pow raises ValueError on a negative base (x**y would give a complex number)
        return f"math.pow({self._print(base)}, {self._print(exponent)})"


_RELATIONS = {"<": "<", "<=": "<=", ">": ">", ">=": ">=", "==": "==", "!=": "!="}


class _Scope:
    """Piecewise values and conditions already computed in the current block."""

    def __init__(self, values: dict[sp.Basic, sp.Symbol], conds: dict[sp.Basic, str]):
        self.values = values
        self.conds = conds

    def child(self) -> _Scope:
        return _Scope(dict(self.values), dict(self.conds))


class _Emitter:
    def __init__(self) -> None:
        self.lines: list[str] = []
        self.printer = _Printer()
        self._temps: Iterator[sp.Symbol] = sp.numbered_symbols("_t")
        self._count = 0

    def fresh(self, prefix: str) -> str:
        self._count += 1
        return f"{prefix}{self._count}"

    def emit(self, indent: int, line: str) -> None:
        self.lines.append("    " * indent + line)

    def region(self, exprs: list[sp.Expr], indent: int, scope: _Scope) -> list[str]:
        """Emit straight-line code for ``exprs``; return one code string per expression."""
        exprs = [e.xreplace(scope.values) if scope.values else e for e in exprs]
        found = _outer_piecewise(exprs)
        # Piecewise with the same conditions (a value and its derivatives) share one chain
        groups: dict[tuple, list[sp.Piecewise]] = {}
        for pw in found:
            if pw not in scope.values:
                groups.setdefault(tuple(c for _, c in pw.args), []).append(pw)
        for conds, members in groups.items():
            names = [self.fresh("_p") for _ in members]
            values = [[pw.args[i].expr for pw in members] for i in range(len(conds))]
            self._chain(list(conds), values, names, indent, scope)
            for pw, name in zip(members, names, strict=True):
                scope.values[pw] = sp.Symbol(name)
        if found:
            exprs = [e.xreplace(scope.values) for e in exprs]
        replacements, reduced = sp.cse(exprs, symbols=self._temps, order="none")
        for sym, value in replacements:
            self.emit(indent, f"{sym} = {self.printer.doprint(value)}")
        return [self.printer.doprint(r) for r in reduced]

    def _chain(
        self, conds: list, values: list[list[sp.Expr]], names: list[str], indent: int,
        scope: _Scope,
    ) -> None:
        """Emit ``if c0: names = values[0] else: if c1: ...`` (first true condition wins)."""
        if not conds:
            for name in names:
                self.emit(indent, f"{name} = math.nan")
            return
        cond = conds[0]
        if cond is sp.false:
            self._chain(conds[1:], values[1:], names, indent, scope)
            return
        if cond is sp.true:
            for name, code in zip(names, self.region(values[0], indent, scope), strict=True):
                self.emit(indent, f"{name} = {code}")
            return
        test = self.condition(cond, indent, scope)
        self.emit(indent, f"if {test}:")
        codes = self.region(values[0], indent + 1, scope.child())
        for name, code in zip(names, codes, strict=True):
            self.emit(indent + 1, f"{name} = {code}")
        self.emit(indent, "else:")
        self._chain(conds[1:], values[1:], names, indent + 1, scope.child())

    def condition(self, cond: sp.Basic, indent: int, scope: _Scope) -> str:
        if cond is sp.true:
            return "True"
        if cond is sp.false:
            return "False"
        reduced = cond.xreplace(scope.values) if scope.values else cond
        known = scope.conds.get(cond) or scope.conds.get(reduced)
        if known is not None:
            return known
        if isinstance(cond, sp.core.relational.Relational):
            op = _RELATIONS.get(cond.rel_op)
            if op is None:
                raise ValueError(f"unsupported relation {cond}")
            sides = []
            for side, text in zip(
                (cond.lhs, cond.rhs), self.region([cond.lhs, cond.rhs], indent, scope),
                strict=True,
            ):
                if side.free_symbols and not side.xreplace(scope.values).is_Atom:
                    # a switching function is usually needed again in the branch values
                    name = self.fresh("_s")
                    self.emit(indent, f"{name} = {text}")
                    scope.values[side] = sp.Symbol(name)
                    text = name
                sides.append(text)
            code = f"{sides[0]} {op} {sides[1]}"
        elif isinstance(cond, sp.And | sp.Or):
            parts = [self.condition(a, indent, scope) for a in cond.args]
            code = (" and " if isinstance(cond, sp.And) else " or ").join(parts)
        elif isinstance(cond, sp.Not):
            code = f"not {self.condition(cond.args[0], indent, scope)}"
        elif isinstance(cond, sp.ITE):
            # sympy folds a Piecewise inside a relation into ITE(c, a, b)
            test = self.condition(cond.args[0], indent, scope)
            name = self.fresh("_b")
            self.emit(indent, f"if {test}:")
            inner = self.condition(cond.args[1], indent + 1, scope.child())
            self.emit(indent + 1, f"{name} = {inner}")
            self.emit(indent, "else:")
            inner = self.condition(cond.args[2], indent + 1, scope.child())
            self.emit(indent + 1, f"{name} = {inner}")
            scope.conds[cond] = scope.conds[reduced] = name
            return name
        else:
            raise ValueError(f"unsupported condition {cond} ({type(cond).__name__})")
        name = self.fresh("_b")
        self.emit(indent, f"{name} = {code}")
        scope.conds[cond] = scope.conds[reduced] = name
        scope.conds[cond.xreplace(scope.values)] = name
        return name


_CACHE: dict[tuple, Kernel] = {}

_NAMESPACE_BUILTINS = {"ArithmeticError": ArithmeticError, "ValueError": ValueError}


def _constant(sym: sp.Symbol, value: float) -> sp.Number:
    x = float(value)
    if not math.isfinite(x):
        raise ValueError(f"parameter `{sym}` must be finite, got {x!r}")
    # integral values become sympy Integers, so that e.g. n = 1 gives x**1 = x exactly
    return sp.Integer(int(x)) if x.is_integer() and abs(x) < 2**53 else sp.Float(x)


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
    values = {sym: _constant(sym, value) for sym, value in params.items()}
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


def compile_kernel(
    residual: sp.Expr,
    q: sp.Symbol,
    F: sp.Symbol,
    params: Mapping[sp.Symbol, float],
    *,
    guard: bool = True,
) -> Kernel:
    """Compile ``residual`` into ``kernel(q, F) -> (R, dR/dq, dR/dF)`` on Python floats.

    Parameters
    ----------
    residual
        The residual ``R(q, F; params)``, a sympy expression.
    q, F
        The symbols for the kinematic variable and the force.
    params
        A value for every other free symbol of ``residual``; substituted as float
        constants into the generated source.
    guard
        Wrap the body in ``try: ... except (ArithmeticError, ValueError): return nans``
        (the default).  ``guard=False`` emits the bare body, which raises Python's
        exceptions instead; that is the form to hand to a JIT such as numba, whose
        ``error_model="numpy"`` turns domain errors into ``inf``/``nan`` by itself.

    Returns
    -------
    Callable
        ``kernel(q: float, F: float) -> (R, dR/dq, dR/dF)``, three Python floats
        (``nan`` where the residual is undefined, see the module docstring).  Its
        source is ``kernel.__source__``; ``kernel.expressions`` holds the three sympy
        expressions it evaluates.  Compiled once per ``(residual, q, F, params)``.

    Examples
    --------
    >>> import sympy as sp
    >>> q, F, k = sp.symbols("q F k")
    >>> kernel = compile_kernel(F - k * q, q, F, {k: 100.0})
    >>> kernel(0.01, 2.0)
    (1.0, -100.0, 1.0)
    """
    key = (
        residual,
        q,
        F,
        tuple(sorted(((str(s), s, repr(float(v))) for s, v in params.items()), key=str)),
        bool(guard),
    )
    hit = _CACHE.get(key)
    if hit is not None:
        return hit
    with distribute(False):  # keep gamma*(F - p) as written: no gamma*F - gamma*p
        exprs = prepare(residual, q, F, params)
        kernel = _build("kernel", ["q", "F"], list(exprs), guard=guard)
        magnitude = _build("magnitude", ["q", "F"], [magnitude_expression(exprs[0])],
                           guard=guard)
    kernel.expressions = exprs  # type: ignore[attr-defined]
    kernel.magnitude = magnitude  # type: ignore[attr-defined]
    _CACHE[key] = kernel
    return kernel


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


def _build(name: str, args: list[str], exprs: list[sp.Expr], *, guard: bool = True) -> Callable:
    """Generate, compile and return ``def name(*args): return exprs`` (see module doc)."""
    emitter = _Emitter()
    emitter.emit(0, f"def {name}({', '.join(args)}):")
    depth = 1
    if guard:
        emitter.emit(1, "try:")
        depth = 2
    codes = emitter.region(exprs, depth, _Scope({}, {}))
    result = codes[0] if len(codes) == 1 else f"({', '.join(codes)})"
    nans = "math.nan" if len(codes) == 1 else f"({', '.join(['math.nan'] * len(codes))})"
    emitter.emit(depth, f"return {result}")
    if guard:
        emitter.emit(1, "except (ArithmeticError, ValueError):")
        emitter.emit(2, f"return {nans}")
    source = "\n".join(emitter.lines) + "\n"
    namespace: dict[str, object] = {"math": math, "__builtins__": dict(_NAMESPACE_BUILTINS)}
    exec(compile(source, f"<lumped {name}>", "exec"), namespace)  # noqa: S102 (our own source)
    function = namespace[name]
    function.__source__ = source  # type: ignore[attr-defined]
    return function  # type: ignore[return-value]


_FUNCTION_CACHE: dict[tuple, Callable] = {}


def compile_function(
    expr: sp.Expr,
    args: Sequence[sp.Symbol],
    params: Mapping[sp.Symbol, float] | None = None,
) -> Callable[..., float]:
    """Compile a scalar sympy expression into a plain Python function of ``args``.

    For forcing terms and other scalar functions (e.g. ``F(t)`` parsed from a scene
    file).  Same rules as :func:`compile_kernel`: parameters substituted as floats,
    kinks as ``if`` chains evaluating only the active branch, ``math`` only, ``nan``
    where undefined, source in ``function.__source__``, compiled once per input.

    Examples
    --------
    >>> import sympy as sp
    >>> from lumped.expressions import parse_expression
    >>> t, A = sp.symbols("t A")
    >>> expr = parse_expression("Piecewise((A*sin(5*pi*t), t <= 1), (0, True))", ["t", "A"])
    >>> force = compile_function(expr, [t], {A: 0.5})
    >>> force(0.1), force(2.0)
    (0.5, 0.0)
    """
    params = dict(params or {})
    args = list(args)
    if not all(isinstance(a, sp.Symbol) for a in args) or len(set(args)) != len(args):
        raise TypeError("`args` must be distinct sympy symbols")
    key = (
        expr,
        tuple(args),
        tuple(sorted(((str(s), s, repr(float(v))) for s, v in params.items()), key=str)),
    )
    hit = _FUNCTION_CACHE.get(key)
    if hit is not None:
        return hit
    expr = sp.sympify(expr) if not isinstance(expr, sp.Basic) else expr
    if not isinstance(expr, sp.Expr):
        raise TypeError(f"`expr` must be a sympy expression, got {type(expr).__name__}")
    check_supported(expr)
    values = {sym: _constant(sym, v) for sym, v in params.items()}
    names = [f"x{i}" for i in range(len(args))]
    plain = {a: sp.Symbol(n) for a, n in zip(args, names, strict=True)}
    with distribute(False):
        expr = expr.xreplace(values).xreplace(plain)
    unbound = sorted(str(s) for s in expr.free_symbols - set(plain.values()))
    if unbound:
        raise ValueError(f"expression has symbols without a value: {', '.join(unbound)}")
    if expr.has(sp.nan, sp.zoo, sp.oo, -sp.oo):
        raise ValueError(f"expression is undefined with these parameters: {expr}")
    with distribute(False):
        function = _build("function", names, [rewrite_kinks(expr)])
    _FUNCTION_CACHE[key] = function
    return function
