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

from .rewrite import (
    check_supported,
    constants_of,
    magnitude_expression,
    outer_piecewise,
    prepare,
    rewrite_kinks,
)

__all__ = ["Kernel", "compile_function", "compile_kernel"]

#: ``kernel(q, F) -> (R, dR/dq, dR/dF)``.
Kernel = Callable[[float, float], tuple[float, float, float]]


class KernelPrinter(PythonCodePrinter):
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
        # squares and square roots as a product and math.sqrt, whatever the exponent's
        # type (2, 2.0, 1/2 or 0.5: a law bound with n = 0.5): numba's LLVM turns
        # pow(x, 2.0) into x*x and pow(x, 0.5) into sqrt(x), correctly rounded, where
        # CPython calls the C library's pow, which is off by an ulp for about 1 argument
        # in 1000; written out, the compiled kernels give the Python kernels' numbers
        if exponent.is_Number and float(exponent) in (2.0, -2.0):
            op = self._operand(base)
            return f"({op}*{op})" if float(exponent) > 0.0 else f"1.0/({op}*{op})"
        if exponent.is_Number and float(exponent) == 0.5:
            return f"math.sqrt({self._print(base)})"
        if isinstance(exponent, sp.Integer):
            n = int(exponent)
            if n == 0:
                return "1.0"
            if n > 0:
                return f"{self._operand(base)}**{n}"
            if n == -1:
                return f"1.0/{self._operand(base)}"
            return f"1.0/{self._operand(base)}**{-n}"
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
        self.printer = KernelPrinter()
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
        found = outer_piecewise(exprs)
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
    twin = _CACHE.get((*key[:4], not key[4]))
    with distribute(False):  # keep gamma*(F - p) as written: no gamma*F - gamma*p
        # the other variant's prepared expressions when it is built (the same parameters)
        exprs = twin.expressions if twin is not None else prepare(residual, q, F, params)
        kernel = build_kernel("kernel", ["q", "F"], list(exprs), guard=guard)
        magnitude = build_kernel("magnitude", ["q", "F"], [magnitude_expression(exprs[0])],
                           guard=guard)
    kernel.expressions = exprs  # type: ignore[attr-defined]
    kernel.magnitude = magnitude  # type: ignore[attr-defined]
    _CACHE[key] = kernel
    return kernel


#: :func:`build_kernel`'s emitted bodies: ``(name, args, exprs) -> (lines, result, nans)``,
#: the body at indent 0, shared by the guarded and the bare variant.
_BODIES: dict[tuple, tuple[list[str], str, str]] = {}


def build_kernel(name: str, args: list[str], exprs: list[sp.Expr], *,
                 guard: bool = True) -> Callable:
    """Generate, compile and return ``def name(*args): return exprs`` (see module doc).

    The body is emitted once per ``(name, args, exprs)`` and shared by the guarded and
    the bare variant (the same text, indented)."""
    key = (name, tuple(args), tuple(exprs))
    hit = _BODIES.get(key)
    if hit is None:
        emitter = _Emitter()
        codes = emitter.region(exprs, 0, _Scope({}, {}))
        result = codes[0] if len(codes) == 1 else f"({', '.join(codes)})"
        nans = "math.nan" if len(codes) == 1 else f"({', '.join(['math.nan'] * len(codes))})"
        hit = _BODIES[key] = (emitter.lines, result, nans)
    body, result, nans = hit
    depth = 2 if guard else 1
    pad = "    " * depth
    lines = [f"def {name}({', '.join(args)}):"]
    if guard:
        lines.append("    try:")
    lines += [pad + line for line in body]
    lines.append(f"{pad}return {result}")
    if guard:
        lines += ["    except (ArithmeticError, ValueError):", f"        return {nans}"]
    source = "\n".join(lines) + "\n"
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
    >>> from lumped.laws.parser import parse_expression
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
    values = constants_of(expr, params)
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
        function = build_kernel("function", names, [rewrite_kinks(expr)])
    _FUNCTION_CACHE[key] = function
    return function
