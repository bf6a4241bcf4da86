r"""Safe parsing of untrusted text (law residuals, forcing expressions) into sympy.

``sympy.sympify`` and ``sympy.parse_expr`` *evaluate* their input as Python, so a
scene file holding ``__import__('os').system(...)`` would run it.  This module never
evaluates the text: it parses it with :func:`ast.parse` (``mode="eval"``), walks the
syntax tree itself and builds the sympy expression node by node, accepting only

* numbers (``int`` and finite ``float`` literals),
* the given symbol names and the constants ``pi`` and ``E``,
* the arithmetic operators ``+ - * / **`` and unary ``+ -``,
* calls of the allowlisted functions below, with positional arguments only,
* inside a ``Piecewise`` condition: comparisons ``< <= > >= == !=`` (chains allowed),
  ``and``, ``or``, ``not``, ``True`` and ``False``.

Allowlisted functions (with their sympy meaning)::

    sin cos tan asin acos atan atan2 sinh cosh tanh asinh acosh atanh
    exp log sqrt Abs abs sign sgn Max max Min min Heaviside Piecewise
    clip(x, lo, hi) = Min(Max(x, lo), hi)

Everything else (attribute access, subscripts, lambdas, strings, keyword arguments,
``^``, calls of any other name, unknown names, text longer than
:data:`MAX_LENGTH` characters or nested deeper than :data:`MAX_DEPTH`) raises
``ValueError`` naming the offending token.
"""

from __future__ import annotations

import ast
import keyword
import warnings
from collections.abc import Callable, Iterable

import sympy as sp

__all__ = [
    "ALLOWED_FUNCTIONS",
    "CONSTANTS",
    "MAX_DEPTH",
    "MAX_LENGTH",
    "check_symbol_name",
    "parse_expression",
]

#: Longest text accepted, in characters.
MAX_LENGTH = 4000
#: Deepest nesting of the syntax tree accepted.
MAX_DEPTH = 60
#: Integer literals longer than this many digits are refused.
_MAX_INT_DIGITS = 100
#: A power of two numbers is evaluated only when its result stays below this many bits.
_MAX_POWER_BITS = 20000


def _clip(x: sp.Expr, lo: sp.Expr, hi: sp.Expr) -> sp.Expr:
    return sp.Min(sp.Max(x, lo), hi)


# name -> (sympy constructor, minimum number of arguments, maximum (None: unbounded))
_FUNCTIONS: dict[str, tuple[Callable[..., sp.Expr], int, int | None]] = {
    "sin": (sp.sin, 1, 1),
    "cos": (sp.cos, 1, 1),
    "tan": (sp.tan, 1, 1),
    "asin": (sp.asin, 1, 1),
    "acos": (sp.acos, 1, 1),
    "atan": (sp.atan, 1, 1),
    "atan2": (sp.atan2, 2, 2),
    "sinh": (sp.sinh, 1, 1),
    "cosh": (sp.cosh, 1, 1),
    "tanh": (sp.tanh, 1, 1),
    "asinh": (sp.asinh, 1, 1),
    "acosh": (sp.acosh, 1, 1),
    "atanh": (sp.atanh, 1, 1),
    "exp": (sp.exp, 1, 1),
    "log": (sp.log, 1, 2),
    "sqrt": (sp.sqrt, 1, 1),
    "Abs": (sp.Abs, 1, 1),
    "abs": (sp.Abs, 1, 1),
    "sign": (sp.sign, 1, 1),
    "sgn": (sp.sign, 1, 1),
    "Max": (sp.Max, 2, None),
    "max": (sp.Max, 2, None),
    "Min": (sp.Min, 2, None),
    "min": (sp.Min, 2, None),
    "Heaviside": (sp.Heaviside, 1, 2),
    "clip": (_clip, 3, 3),
    "Piecewise": (sp.Piecewise, 1, None),
}

#: Names of the functions :func:`parse_expression` accepts by default.
ALLOWED_FUNCTIONS: frozenset[str] = frozenset(_FUNCTIONS)

#: Named constants.
CONSTANTS: dict[str, sp.Expr] = {"pi": sp.pi, "E": sp.E}

_RESERVED = frozenset(_FUNCTIONS) | frozenset(CONSTANTS) | {"True", "False", "None"}

_BINOPS: dict[type, Callable[[sp.Expr, sp.Expr], sp.Expr]] = {
    ast.Add: lambda a, b: a + b,
    ast.Sub: lambda a, b: a - b,
    ast.Mult: lambda a, b: a * b,
    ast.Div: lambda a, b: a / b,
}

_COMPARE: dict[type, Callable[[sp.Expr, sp.Expr], sp.Basic]] = {
    ast.Lt: sp.Lt,
    ast.LtE: sp.Le,
    ast.Gt: sp.Gt,
    ast.GtE: sp.Ge,
    ast.Eq: sp.Eq,
    ast.NotEq: sp.Ne,
}

_NODE_WORDS: dict[type, str] = {
    ast.Attribute: "attribute access",
    ast.Subscript: "subscript",
    ast.Lambda: "lambda",
    ast.IfExp: "conditional expression (use Piecewise)",
    ast.ListComp: "comprehension",
    ast.SetComp: "comprehension",
    ast.DictComp: "comprehension",
    ast.GeneratorExp: "comprehension",
    ast.List: "list",
    ast.Dict: "dict",
    ast.Set: "set",
    ast.Starred: "starred argument",
    ast.NamedExpr: "assignment expression",
    ast.JoinedStr: "string",
    ast.FormattedValue: "string",
    ast.Await: "await",
    ast.Yield: "yield",
    ast.YieldFrom: "yield",
    ast.Slice: "slice",
}


def check_symbol_name(name: object, what: str = "symbol") -> str:
    """Return ``name`` if it can be a symbol of a parsed expression, else raise.

    A symbol name is a Python identifier that is not a keyword, does not start with an
    underscore and is not the name of an allowlisted function or constant.
    """
    if not isinstance(name, str):
        raise TypeError(f"{what} name must be a string, got {name!r}")
    if not name.isidentifier() or keyword.iskeyword(name) or name.startswith("_"):
        raise ValueError(
            f"{what} name {name!r} is not allowed: use letters, digits and underscores, "
            "starting with a letter, and not a Python keyword"
        )
    if name in _RESERVED:
        raise ValueError(f"{what} name {name!r} clashes with a built-in function or constant")
    return name


def _bits(n: sp.Number) -> int:
    if isinstance(n, sp.Integer):
        return abs(int(n)).bit_length()
    if isinstance(n, sp.Rational):
        return max(abs(int(n.p)).bit_length(), abs(int(n.q)).bit_length())
    return 64


class _Builder:
    def __init__(self, text: str, symbols: dict[str, sp.Symbol], functions: frozenset[str]):
        self.text = text
        self.symbols = symbols
        self.functions = functions

    # -- helpers ---------------------------------------------------------------------------
    def _token(self, node: ast.AST) -> str:
        segment = ast.get_source_segment(self.text, node)
        if segment is None:
            segment = type(node).__name__
        if len(segment) > 60:
            segment = segment[:57] + "..."
        return segment

    def _refuse(self, node: ast.AST, why: str) -> ValueError:
        return ValueError(f"{why}: {self._token(node)!r} is not allowed")

    def _depth(self, node: ast.AST, depth: int) -> None:
        if depth > MAX_DEPTH:
            raise ValueError(
                f"expression nested deeper than {MAX_DEPTH} levels near {self._token(node)!r}"
            )

    # -- expressions -----------------------------------------------------------------------
    def expr(self, node: ast.AST, depth: int = 0) -> sp.Expr:
        self._depth(node, depth)
        d = depth + 1
        if isinstance(node, ast.Constant):
            return self._constant(node)
        if isinstance(node, ast.Name):
            return self._name(node)
        if isinstance(node, ast.UnaryOp):
            if isinstance(node.op, ast.USub):
                return -self.expr(node.operand, d)
            if isinstance(node.op, ast.UAdd):
                return self.expr(node.operand, d)
            raise self._refuse(node, "operator")
        if isinstance(node, ast.BinOp):
            return self._binop(node, d)
        if isinstance(node, ast.Call):
            return self._call(node, d)
        if isinstance(node, (ast.Compare, ast.BoolOp)):
            raise self._refuse(node, "comparison or logical operator outside a Piecewise condition")
        if isinstance(node, ast.Tuple):
            raise self._refuse(node, "a tuple outside Piecewise")
        word = _NODE_WORDS.get(type(node), f"syntax {type(node).__name__}")
        raise self._refuse(node, word)

    def _constant(self, node: ast.Constant) -> sp.Expr:
        value = node.value
        if isinstance(value, bool) or value is None:
            raise self._refuse(node, "constant outside a Piecewise condition")
        if isinstance(value, int):
            if len(str(abs(value))) > _MAX_INT_DIGITS:
                raise self._refuse(node, f"integer literal longer than {_MAX_INT_DIGITS} digits")
            return sp.Integer(value)
        if isinstance(value, float):
            if value != value or value in (float("inf"), float("-inf")):
                raise self._refuse(node, "non-finite number")
            return sp.Float(value)
        if isinstance(value, (str, bytes)):
            raise self._refuse(node, "string")
        raise self._refuse(node, f"{type(value).__name__} literal")

    def _name(self, node: ast.Name) -> sp.Expr:
        name = node.id
        if name in self.symbols:
            return self.symbols[name]
        if name in CONSTANTS:
            return CONSTANTS[name]
        if name in self.functions:
            raise ValueError(f"function {name!r} used without calling it")
        known = ", ".join(sorted(self.symbols)) or "none"
        raise ValueError(f"unknown symbol {name!r} (known symbols: {known})")

    def _binop(self, node: ast.BinOp, depth: int) -> sp.Expr:
        if isinstance(node.op, ast.BitXor):
            raise self._refuse(node, "operator '^' (write powers with '**')")
        if isinstance(node.op, ast.Pow):
            base = self.expr(node.left, depth)
            exponent = self.expr(node.right, depth)
            return self._power(node, base, exponent)
        op = _BINOPS.get(type(node.op))
        if op is None:
            raise self._refuse(node, f"operator {type(node.op).__name__}")
        return op(self.expr(node.left, depth), self.expr(node.right, depth))

    def _power(self, node: ast.AST, base: sp.Expr, exponent: sp.Expr) -> sp.Expr:
        # Guard against 9**9**9-style blow-ups: sympy evaluates powers of numbers exactly.
        if isinstance(base, sp.Number) and isinstance(exponent, sp.Number):
            if isinstance(exponent, sp.Integer):
                if _bits(base) * max(abs(int(exponent)), 1) > _MAX_POWER_BITS:
                    raise self._refuse(node, "numeric power too large")
            elif isinstance(exponent, sp.Rational):
                if _bits(base) > 1000 or abs(int(exponent.p)) > 1000:
                    raise self._refuse(node, "numeric power too large")
        return sp.Pow(base, exponent)

    def _call(self, node: ast.Call, depth: int) -> sp.Expr:
        if not isinstance(node.func, ast.Name):
            raise self._refuse(node.func, "call of anything but an allowlisted function name")
        name = node.func.id
        if name not in self.functions:
            if name in _FUNCTIONS:
                raise ValueError(f"function {name!r} is not allowed here")
            raise ValueError(
                f"call of {name!r} is not allowed (allowed functions: "
                f"{', '.join(sorted(self.functions))})"
            )
        if node.keywords:
            raise self._refuse(node, "keyword argument")
        for arg in node.args:
            if isinstance(arg, ast.Starred):
                raise self._refuse(arg, "starred argument")
        func, lo, hi = _FUNCTIONS[name]
        n = len(node.args)
        if n < lo or (hi is not None and n > hi):
            want = str(lo) if lo == hi else (f"at least {lo}" if hi is None else f"{lo} to {hi}")
            raise ValueError(f"{name}() takes {want} argument(s), got {n} in {self._token(node)!r}")
        if name == "Piecewise":
            return self._piecewise(node, depth)
        args = [self.expr(a, depth) for a in node.args]
        return func(*args)

    def _piecewise(self, node: ast.Call, depth: int) -> sp.Expr:
        pairs = []
        for arg in node.args:
            if not (isinstance(arg, ast.Tuple) and len(arg.elts) == 2):
                raise self._refuse(arg, "Piecewise argument that is not a pair (value, condition)")
            value = self.expr(arg.elts[0], depth + 1)
            condition = self.cond(arg.elts[1], depth + 1)
            pairs.append((value, condition))
        try:
            return sp.Piecewise(*pairs)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"invalid Piecewise {self._token(node)!r}: {exc}") from None

    # -- conditions ------------------------------------------------------------------------
    def cond(self, node: ast.AST, depth: int) -> sp.Basic:
        self._depth(node, depth)
        d = depth + 1
        if isinstance(node, ast.Constant) and isinstance(node.value, bool):
            return sp.true if node.value else sp.false
        if isinstance(node, ast.Compare):
            terms = [self.expr(node.left, d)] + [self.expr(c, d) for c in node.comparators]
            parts = []
            for op, a, b in zip(node.ops, terms[:-1], terms[1:], strict=True):
                make = _COMPARE.get(type(op))
                if make is None:
                    raise self._refuse(node, f"comparison {type(op).__name__}")
                try:
                    parts.append(make(a, b))
                except TypeError as exc:
                    raise ValueError(f"invalid comparison {self._token(node)!r}: {exc}") from None
            return sp.And(*parts)
        if isinstance(node, ast.BoolOp):
            parts = [self.cond(v, d) for v in node.values]
            return sp.And(*parts) if isinstance(node.op, ast.And) else sp.Or(*parts)
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.Not):
            return sp.Not(self.cond(node.operand, d))
        raise self._refuse(node, "Piecewise condition that is not a comparison")


def parse_expression(
    text: str,
    symbols: Iterable[str],
    *,
    functions: Iterable[str] | None = None,
) -> sp.Expr:
    """Parse untrusted ``text`` into a sympy expression without evaluating it as Python.

    Parameters
    ----------
    text
        The expression, e.g. ``"q - gamma*(F - clip(F, -tau, tau))"``.
    symbols
        The names that may appear as free symbols.  Each becomes ``sympy.Symbol(name)``
        (no assumptions), so the result compares equal to expressions built by hand.
    functions
        The subset of :data:`ALLOWED_FUNCTIONS` to accept (default: all of them).  The
        allowlist cannot be extended: only these functions have a safe meaning.

    Returns
    -------
    sympy.Expr

    Raises
    ------
    ValueError
        On anything outside the grammar described in the module docstring; the message
        quotes the offending token.
    TypeError
        If ``text`` is not a string.

    Examples
    --------
    >>> parse_expression("q - gamma*(F - clip(F, -tau, tau))", ["q", "F", "gamma", "tau"])
    -gamma*(F - Min(tau, Max(F, -tau))) + q
    >>> parse_expression("q.__class__", ["q"])
    Traceback (most recent call last):
    ...
    ValueError: attribute access: 'q.__class__' is not allowed
    """
    if not isinstance(text, str):
        raise TypeError(f"expression must be a string, got {type(text).__name__}")
    if len(text) > MAX_LENGTH:
        raise ValueError(f"expression longer than {MAX_LENGTH} characters ({len(text)})")
    if isinstance(symbols, str):
        raise TypeError("`symbols` must be an iterable of names, not a single string")
    table: dict[str, sp.Symbol] = {}
    for name in symbols:
        table[check_symbol_name(name)] = sp.Symbol(name)
    if functions is None:
        allowed = ALLOWED_FUNCTIONS
    else:
        if isinstance(functions, str):
            raise TypeError("`functions` must be an iterable of names, not a single string")
        allowed = frozenset(functions)
        unknown = sorted(allowed - ALLOWED_FUNCTIONS)
        if unknown:
            raise ValueError(f"`functions` may only name allowlisted functions, got {unknown}")
    if not text.strip():
        raise ValueError("expression is empty")
    # parenthesised so that an expression may span several lines (e.g. in a TOML file)
    source = "(" + text.strip() + "\n)"
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", SyntaxWarning)
            tree = ast.parse(source, mode="eval")
    except SyntaxError as exc:
        raise ValueError(f"cannot parse expression {text[:60]!r}: {exc.msg}") from None
    except (ValueError, RecursionError, MemoryError, OverflowError) as exc:
        raise ValueError(
            f"cannot parse expression: nested too deeply or too complex ({type(exc).__name__})"
        ) from None
    builder = _Builder(source, table, allowed)
    try:
        result = builder.expr(tree.body)
    except RecursionError:
        raise ValueError("expression nested too deeply") from None
    if not isinstance(result, sp.Expr):
        raise ValueError(f"expression {text[:60]!r} is not a scalar expression")
    if result.has(sp.zoo, sp.oo, -sp.oo, sp.nan):
        raise ValueError(f"expression {text[:60]!r} evaluates to an infinite or undefined value")
    if result.has(sp.I):
        raise ValueError(f"expression {text[:60]!r} holds a complex number")
    return result
