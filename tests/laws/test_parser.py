"""The safe parser: what it builds, what it refuses, and that it never runs the text."""

from __future__ import annotations

import math
import sys

import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

from lumped.laws.parser import (
    ALLOWED_FUNCTIONS,
    MAX_DEPTH,
    MAX_LENGTH,
    check_symbol_name,
    parse_expression,
)

SYMBOLS = ["q", "F", "gamma", "tau", "k", "t"]
q, F, gamma, tau, k, t = sp.symbols("q F gamma tau k t")


# --------------------------------------------------------------------------------------
# An audit hook that records what the interpreter does while a flag is set.  Imports of
# library modules (sympy loads some lazily) are allowed; code compiled from a string and
# executed, processes, sockets, and files opened for writing are not.
# --------------------------------------------------------------------------------------
_RECORD: list[tuple[str, tuple]] = []
_ACTIVE = [False]
_DANGEROUS_PREFIXES = (
    "os.system",
    "os.exec",
    "os.spawn",
    "os.posix_spawn",
    "os.fork",
    "os.remove",
    "os.rename",
    "os.kill",
    "subprocess.",
    "socket.",
    "shutil.",
    "ctypes.",
    "builtins.input",
)


def _hook(event: str, args: tuple) -> None:
    if _ACTIVE[0]:
        _RECORD.append((event, args))


sys.addaudithook(_hook)


def _dangerous(events: list[tuple[str, tuple]]) -> list[str]:
    bad = []
    for event, args in events:
        if event.startswith(_DANGEROUS_PREFIXES):
            bad.append(event)
        elif event == "exec":
            code = args[0] if args else None
            filename = getattr(code, "co_filename", "")
            if not str(filename).endswith(".py"):  # module imports execute .py files
                bad.append(f"exec of {filename!r}")
        elif event == "open" and len(args) > 1 and isinstance(args[1], str):
            if any(c in args[1] for c in "wax+"):
                bad.append(f"open for writing {args[0]!r}")
    return bad


def _parse_watched(text: str) -> tuple[object, list[str]]:
    _RECORD.clear()
    _ACTIVE[0] = True
    try:
        try:
            result: object = parse_expression(text, SYMBOLS)
        except ValueError as exc:
            result = exc
    finally:
        _ACTIVE[0] = False
    return result, _dangerous(list(_RECORD))


def test_the_audit_detector_has_teeth():
    # the same detector flags code that *is* evaluated from a string
    _RECORD.clear()
    _ACTIVE[0] = True
    try:
        eval("exec('1 + 1')")  # noqa: S307 - deliberately evaluated, harmless
    finally:
        _ACTIVE[0] = False
    assert _dangerous(list(_RECORD))


# --------------------------------------------------------------------------------------
# What it builds
# --------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("q - gamma*(F - clip(F, -tau, tau))", q - gamma * (F - sp.Min(sp.Max(F, -tau), tau))),
        ("F - k*q", F - k * q),
        ("q**2 / 3 + 0.5*F", q**2 / 3 + sp.Float(0.5) * F),
        ("-+-q", q),
        ("sqrt(q) + exp(F) - log(k) + sin(t)*cos(t)", sp.sqrt(q) + sp.exp(F) - sp.log(k)
         + sp.sin(t) * sp.cos(t)),
        ("abs(q) + Abs(F) + sgn(q) + sign(F)", sp.Abs(q) + sp.Abs(F) + 2 * 0 + sp.sign(q)
         + sp.sign(F)),
        ("max(q, F, 1) - min(q, F)", sp.Max(q, F, 1) - sp.Min(q, F)),
        ("Heaviside(q) + Heaviside(F, 1)", sp.Heaviside(q) + sp.Heaviside(F, 1)),
        ("atan2(q, F) + tanh(q) + asinh(F)", sp.atan2(q, F) + sp.tanh(q) + sp.asinh(F)),
        ("pi*E*q", sp.pi * sp.E * q),
        ("Piecewise((F, F > tau), (-F, F < -tau), (0, True))",
         sp.Piecewise((F, F > tau), (-F, F < -tau), (0, True))),
        ("Piecewise((q, 0 <= F < tau), (1, not q == 1 or F != 2), (2, True))",
         sp.Piecewise((q, sp.And(F >= 0, F < tau)), (1, sp.Or(sp.Not(sp.Eq(q, 1)),
                                                           sp.Ne(F, 2))), (2, True))),
        ("log(q, 10)", sp.log(q, 10)),
        ("  q\n + F ", q + F),
    ],
)
def test_builds_the_expected_sympy_expression(text, expected):
    assert parse_expression(text, SYMBOLS) == expected


def test_symbols_are_plain_so_hand_built_expressions_compare_equal():
    expr = parse_expression("q*F", ["q", "F"])
    assert expr == sp.Symbol("q") * sp.Symbol("F")
    assert expr.subs({sp.Symbol("q"): 2, sp.Symbol("F"): 3}) == 6


def test_functions_can_be_restricted_to_a_subset():
    assert parse_expression("sin(q)", ["q"], functions=["sin"]) == sp.sin(q)
    with pytest.raises(ValueError, match="'cos' is not allowed"):
        parse_expression("cos(q)", ["q"], functions=["sin"])
    with pytest.raises(ValueError, match="open"):
        parse_expression("q", ["q"], functions=["sin", "open"])


def test_allowlist_is_what_the_brief_promises():
    for name in ("sin", "cos", "tan", "exp", "log", "sqrt", "Abs", "sign", "Max", "Min",
                 "Heaviside", "Piecewise", "tanh", "sinh", "cosh", "atan", "clip"):
        assert name in ALLOWED_FUNCTIONS
    for name in ("eval", "exec", "open", "getattr", "__import__", "sympify", "Symbol"):
        assert name not in ALLOWED_FUNCTIONS


# --------------------------------------------------------------------------------------
# What it refuses, naming the offending token
# --------------------------------------------------------------------------------------
HOSTILE = [
    ("__import__('os').system('echo pwned')", "__import__"),
    ("q.__class__", "q.__class__"),
    ("().__class__.__bases__[0].__subclasses__()", "__subclasses__"),
    ("q.__class__.__mro__", "__mro__"),
    ("__builtins__", "__builtins__"),
    ("__class__", "__class__"),
    ("lambda: 0", "lambda"),
    ("(lambda x: x)(q)", "lambda"),
    ("eval('1')", "eval"),
    ("exec('import os')", "exec"),
    ("open('/etc/passwd')", "open"),
    ("getattr(q, 'x')", "getattr"),
    ("globals()", "globals"),
    ("sympify('q')", "sympify"),
    ("Symbol('x')", "Symbol"),
    ("q[0]", "q[0]"),
    ("'abc'", "'abc'"),
    ("b'x'", "b'x'"),
    ("f'{q}'", "f'{q}'"),
    ("[x for x in q]", "comprehension"),
    ("[q, F]", "list"),
    ("{q: 1}", "dict"),
    ("(q := 1)", "q := 1"),
    ("q if F else 1", "q if F else 1"),
    ("sin(q=1)", "keyword"),
    ("sin(*q)", "*q"),
    ("q ^ 2", "**"),
    ("q % 2", "q % 2"),
    ("q // 2", "q // 2"),
    ("q @ F", "q @ F"),
    ("q << 1", "q << 1"),
    ("~q", "~q"),
    ("q > 1", "q > 1"),
    ("not q", "not q"),
    ("q and F", "q and F"),
    ("1j", "1j"),
    ("None", "None"),
    ("True", "True"),
    ("...", "..."),
    ("x + 1", "'x'"),
    ("sin", "sin"),
    ("foo(q)", "foo"),
    ("import os", "cannot parse"),
    ("q; import os", "cannot parse"),
    ("q\x00", "cannot parse"),
    ("", "empty"),
    ("9**9**9", "9**9**9"),
    ("(10**99)**1000", "power too large"),
    ("1" * 200, "digits"),
    ("1e999", "1e999"),
    ("1/0", "infinite"),
    ("sqrt(-1)", "complex"),
    ("Max(q)", "Max"),
    ("sqrt(q, F)", "sqrt"),
    ("Piecewise(q)", "'q'"),
    ("Piecewise((q, q))", "'q'"),
    ("Piecewise((q, F > 1, 3))", "F > 1"),
    ("await q", "await"),
    ("(yield q)", "yield"),
]


@pytest.mark.parametrize(("text", "token"), HOSTILE)
def test_hostile_text_is_refused_with_the_token_named(text, token):
    result, bad = _parse_watched(text)
    assert not bad
    assert isinstance(result, ValueError), result
    assert token in str(result)


def test_very_long_input_is_refused_before_parsing():
    text = "q+" * (MAX_LENGTH // 2) + "q"
    with pytest.raises(ValueError, match="longer than"):
        parse_expression(text, SYMBOLS)


@pytest.mark.parametrize(
    "text",
    [
        "sin(" * (MAX_DEPTH + 1) + "q" + ")" * (MAX_DEPTH + 1),
        "-" * (MAX_LENGTH - 1) + "q",
        "(" * 1000 + "q" + ")" * 1000,
        "Max(q, " * 300 + "F" + ")" * 300,
        "q" + "**q" * 1000,
    ],
)
def test_deeply_nested_input_is_refused(text):
    with pytest.raises(ValueError, match="nest|complex|parse"):
        parse_expression(text, SYMBOLS)


def test_moderate_nesting_is_fine():
    text = "sin(" * 20 + "q" + ")" * 20
    assert parse_expression(text, SYMBOLS).has(q)


@pytest.mark.parametrize(
    "name", ["__class__", "_x", "lambda", "sin", "pi", "E", "True", "1q", "q-1", "", "a b"]
)
def test_bad_symbol_names_are_refused(name):
    with pytest.raises(ValueError, match="name"):
        check_symbol_name(name)
    with pytest.raises(ValueError):
        parse_expression("1", [name])


def test_bad_argument_types():
    with pytest.raises(TypeError):
        parse_expression(b"q", SYMBOLS)  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        parse_expression("q", "q")
    with pytest.raises(TypeError):
        parse_expression("q", [1])  # type: ignore[list-item]


# --------------------------------------------------------------------------------------
# Random text: never executes anything; either parses to a sympy expression or raises
# ValueError (never another exception).
# --------------------------------------------------------------------------------------
_VOCAB = [
    "q", "F", "tau", "k", "x", "1", "2.5", "0", "1e308", "(", ")", "(", ")", ",", "+", "-", "*",
    "**", "/", "//", "%", "^", ".", "__class__", "__import__", "__builtins__", "lambda", ":",
    "[", "]", "'os'", "\"", "sin", "sqrt", "log", "Piecewise", "clip", "Max", "Heaviside",
    ">", "<=", "==", "and", "or", "not", "True", "False", "None", "os", "system", "eval",
    "open", "=", " ", "if", "else", "for", "in", "{", "}", "@", "~", "\n", "\\", "#",
]


@given(st.lists(st.sampled_from(_VOCAB), max_size=30).map("".join))
def test_random_token_soup_never_executes_and_only_raises_value_error(text):
    result, bad = _parse_watched(text)
    assert not bad, (text, bad)
    assert isinstance(result, (sp.Expr, ValueError)), (text, result)


@given(st.text(max_size=80))
def test_random_text_never_executes_and_only_raises_value_error(text):
    result, bad = _parse_watched(text)
    assert not bad, (text, bad)
    assert isinstance(result, (sp.Expr, ValueError)), (text, result)


@given(
    st.recursive(
        st.sampled_from(["q", "F", "tau", "1", "2", "0.5"]),
        lambda inner: st.one_of(
            st.tuples(inner, st.sampled_from(["+", "-", "*", "/", "**"]), inner).map(
                lambda p: f"({p[0]} {p[1]} {p[2]})"
            ),
            st.tuples(st.sampled_from(["sin", "exp", "sqrt", "Abs", "tanh"]), inner).map(
                lambda p: f"{p[0]}({p[1]})"
            ),
            st.tuples(inner, inner).map(lambda p: f"clip({p[0]}, -tau, {p[1]})"),
        ),
        max_leaves=12,
    )
)
def test_well_formed_expressions_parse_to_what_python_arithmetic_says(text):
    # the parser and Python agree on the value at a point where everything is defined
    # (here the evaluation is of *our own* generated text, inside the test only)
    try:
        expr = parse_expression(text, SYMBOLS)
    except ValueError:
        return  # e.g. 1/0 or a complex value
    env = {"q": 0.7, "F": 1.3, "tau": 0.4}
    value = complex(expr.subs({q: env["q"], F: env["F"], tau: env["tau"]}).evalf())
    py_env = {
        "sin": math.sin, "exp": math.exp, "sqrt": math.sqrt, "Abs": abs, "tanh": math.tanh,
        "clip": lambda x, lo, hi: min(max(x, lo), hi),
        **env,
    }
    try:
        expected = eval(text, {"__builtins__": {}}, py_env)  # noqa: S307 - generated text
    except (ZeroDivisionError, OverflowError, TypeError, ValueError):
        return
    if isinstance(expected, complex) or abs(expected) > 1e12 or abs(value) > 1e12:
        return
    assert value.imag == pytest.approx(0.0, abs=1e-9)
    assert value.real == pytest.approx(expected, rel=1e-9, abs=1e-12)
