"""The kernel generator: values, derivatives, kinks, safety, plainness of the source."""

from __future__ import annotations

import ast
import functools
import math

import mpmath
import pytest
import sympy as sp
from hypothesis import assume, given
from hypothesis import strategies as st

from lumped.codegen import check_supported, compile_function, compile_kernel, rewrite_kinks
from lumped.laws.parser import parse_expression
from lumped.scene import paper_F2

q, F, a, b = sp.symbols("q F a b")

finite = st.floats(min_value=-5.0, max_value=5.0, allow_nan=False, allow_infinity=False)


def kernel_of(text: str, **params: float):
    expr = parse_expression(text, ["q", "F", *params])
    return compile_kernel(expr, q, F, {sp.Symbol(p): v for p, v in params.items()})


SMOOTH = [
    "q**3 - 2*q*F + F**2",
    "sin(q)*exp(F/3) - cos(q*F)",
    "q - F/a - b*sinh(F/a)",
    "tanh(q + F) + atan(q) - q*F**2/(1 + F**2)",
    "sqrt(1 + q**2) + log(2 + F**2) + atan2(q, 3 + F**2)",
    "(q - F)**3 + 3*q - 5*F",
    "(1 + q**2)**0.75 - F**-2 * (1 + q**2)",
]


@functools.cache
def _reference(text: str):
    """The kernel, and sympy's own (R, dR/dq, dR/dF) evaluated in 30-digit arithmetic."""
    expr = parse_expression(text, ["q", "F", "a", "b"]).subs({a: 1.5, b: 0.25})
    exprs = (expr, sp.diff(expr, q), sp.diff(expr, F))
    reference = sp.lambdify((q, F), exprs, modules="mpmath")
    return kernel_of(text, a=1.5, b=0.25), reference


@pytest.mark.parametrize("text", SMOOTH)
@given(x=finite, y=finite)
def test_values_and_derivatives_equal_sympy_on_smooth_residuals(text, x, y):
    assume(abs(y) > 1e-3)
    kernel, reference = _reference(text)
    with mpmath.workdps(30):
        want = [float(v) for v in reference(mpmath.mpf(x), mpmath.mpf(y))]
    got = kernel(x, y)
    for g, w in zip(got, want, strict=True):
        assert g == pytest.approx(w, rel=1e-12, abs=1e-12)


def test_outputs_are_python_floats_and_constants_are_floats():
    kernel = kernel_of("q - 2*F")
    out = kernel(1.0, 3.0)
    assert out == (-5.0, 1.0, -2.0)
    assert all(type(v) is float for v in out)


def test_generated_source_is_plain_python_with_math_only():
    kernel = kernel_of("q - gamma*(F - clip(F, -tau, tau)) + sqrt(1 + q**2)", gamma=2.0, tau=1.0)
    source = kernel.__source__
    assert "numpy" not in source and "sympy" not in source and "np." not in source
    assert set(kernel.__globals__) <= {"math", "__builtins__", "kernel"}
    allowed = (
        ast.Module, ast.FunctionDef, ast.arguments, ast.arg, ast.Try, ast.ExceptHandler,
        ast.If, ast.Assign, ast.Return, ast.Tuple, ast.Name, ast.Load, ast.Store,
        ast.Constant, ast.BinOp, ast.UnaryOp, ast.Compare, ast.BoolOp, ast.Attribute,
        ast.Call, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.USub, ast.Not,
        ast.And, ast.Or, ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.Eq, ast.NotEq,
    )
    for node in ast.walk(ast.parse(source)):
        assert isinstance(node, allowed), ast.dump(node)
        if isinstance(node, ast.Attribute):
            assert isinstance(node.value, ast.Name) and node.value.id == "math"
        if isinstance(node, ast.Constant):
            assert type(node.value) in (float, int, bool)


def test_source_recompiles_to_the_same_function():
    kernel = kernel_of("q - gamma*(F - clip(F, -tau, tau))", gamma=3.0, tau=0.5)
    namespace = {"math": math}
    exec(kernel.__source__, namespace)  # noqa: S102 - our own generated source
    for point in ((0.0, 0.2), (1.0, 2.0), (-1.0, -0.5), (0.3, -4.0)):
        assert namespace["kernel"](*point) == kernel(*point)


def test_kernels_are_compiled_once_per_expression_and_parameters():
    expr = parse_expression("F - k*q", ["q", "F", "k"])
    k = sp.Symbol("k")
    first = compile_kernel(expr, q, F, {k: 2.0})
    assert compile_kernel(expr, q, F, {k: 2.0}) is first
    assert compile_kernel(expr, q, F, {k: 3.0}) is not first


def test_only_the_active_branch_is_evaluated():
    kernel = kernel_of("Piecewise((sqrt(F), F >= 0), (-log(-F), F < 0), (1, True))")
    assert kernel(0.0, -1.0) == (0.0, 0.0, 1.0)
    assert kernel(0.0, 4.0) == (2.0, 0.0, 0.25)
    divide = kernel_of("Piecewise((1/F, F != 0), (0, True))")
    assert divide(0.0, 0.0) == (0.0, 0.0, 0.0)
    assert divide(0.0, 2.0) == (0.5, 0.0, -0.25)


@pytest.mark.parametrize(
    ("text", "point"),
    [("sqrt(F) - q", (0.0, -1.0)), ("exp(F) - q", (0.0, 1000.0)), ("1/F - q", (1.0, 0.0)),
     ("log(F) - q", (0.0, 0.0)), ("F**0.3 - q", (0.0, -2.0)), ("(q - F)**-2", (1.0, 1.0))],
)
def test_undefined_points_give_a_nan_triple_not_an_exception_or_complex(text, point):
    out = kernel_of(text)(*point)
    assert len(out) == 3 and all(type(v) is float and math.isnan(v) for v in out)


@pytest.mark.parametrize(
    ("expr", "message"),
    [
        (sp.Function("f")(q) - F, "unsupported"),
        (sp.I * q + F, "unsupported|finite"),
        (q + F + sp.oo, "finite|unsupported"),
        (sp.Derivative(q * F, q), "unsupported"),
        (sp.gamma(q) - F, "unsupported"),
    ],
)
def test_unsupported_terms_are_refused(expr, message):
    with pytest.raises(ValueError, match=message):
        check_supported(expr)
    with pytest.raises(ValueError):
        compile_kernel(expr, q, F, {})


def test_unbound_symbols_and_bad_parameters_are_named():
    k = sp.Symbol("k")
    with pytest.raises(ValueError, match="k"):
        compile_kernel(F - k * q, q, F, {})
    with pytest.raises(ValueError, match="k"):
        compile_kernel(F - k * q, q, F, {k: float("nan")})
    with pytest.raises(ValueError, match="undefined"):
        compile_kernel(F - q / k, q, F, {k: 0.0})
    with pytest.raises(TypeError):
        compile_kernel(F - q, q, q, {})


# ---------------------------------------------------------------------------------------
# Kinks: the derivative comes from the branch that supplies the value
# ---------------------------------------------------------------------------------------
def test_rewrite_kinks_leaves_no_kink_functions():
    expr = sp.Max(q, F, 1) + sp.Min(q, 2) * sp.Abs(F) + sp.sign(q) + sp.Heaviside(F)
    out = rewrite_kinks(expr)
    assert not out.has(sp.Max, sp.Min, sp.Abs, sp.sign, sp.Heaviside)
    for x, y in ((0.3, -1.2), (2.5, 0.1), (-1.0, 4.0)):
        assert float(out.subs({q: x, F: y})) == pytest.approx(float(expr.subs({q: x, F: y})))


@pytest.mark.parametrize(
    ("text", "point", "derivatives"),
    [
        # a variable argument wins a tie with a constant one
        ("Max(F, 1)", (0.0, 1.0), (0.0, 1.0)),
        ("Max(1, F)", (0.0, 1.0), (0.0, 1.0)),
        ("Min(F, 1)", (0.0, 1.0), (0.0, 1.0)),
        ("Min(2*q, 1)", (0.5, 0.0), (2.0, 0.0)),
        ("clip(F, -1, 1)", (0.0, 1.0), (0.0, 1.0)),
        ("clip(F, -1, 1)", (0.0, -1.0), (0.0, 1.0)),
        # Abs takes the right-hand slope at 0; sign and Heaviside are flat
        ("Abs(F)", (0.0, 0.0), (0.0, 1.0)),
        ("sign(F)*q", (2.0, 0.0), (0.0, 0.0)),
        ("Heaviside(F) + q", (0.0, 0.0), (1.0, 0.0)),
        # Piecewise: the first true condition supplies value *and* derivative
        ("Piecewise((2*F, F >= 1), (3*F - 1, True))", (0.0, 1.0), (0.0, 2.0)),
        ("Piecewise((2*F, F > 1), (3*F - 1, True))", (0.0, 1.0), (0.0, 3.0)),
    ],
)
def test_kink_derivative_is_the_chosen_branch(text, point, derivatives):
    _, dq, dF = kernel_of(text)(*point)
    assert (dq, dF) == derivatives


@given(st.sampled_from([0.1, 0.5, 1.0, 3.0, 7.25]), st.floats(-3.0, 3.0), st.floats(-3.0, 3.0))
def test_kink_value_and_derivative_are_one_sided_limits_of_the_chosen_branch(c, x, y):
    # Max(F, c) at the tie F = c takes value and derivative from the F side
    kernel = kernel_of("Max(F, c) * (1 + q**2)", c=c)
    on = kernel(x, c)
    near = kernel(x, c * (1.0 + 1e-12))
    for u, v in zip(on, near, strict=True):
        assert u == pytest.approx(v, rel=1e-9, abs=1e-9)
    assert on[2] == 1.0 + x * x
    assert kernel(x, y)[0] == pytest.approx(max(y, c) * (1 + x * x), rel=1e-12)


def test_integral_parameter_values_are_exact_integers_in_the_code():
    # n = 1 must give x**1 = x (no math.pow(x, 1.0)); n = 2 gives x*x and n = 0.5
    # math.sqrt(x), as numba compiles them (tests/codegen/test_jit.py); n = 3 x**3
    assert "pow" not in kernel_of("q - F**n", n=1.0).__source__
    assert "(F*F)" in kernel_of("q - F**n", n=2.0).__source__
    assert "math.sqrt(F)" in kernel_of("q - F**n", n=0.5).__source__
    assert "F**3" in kernel_of("q - F**n", n=3.0).__source__
    assert "pow" in kernel_of("q - F**n", n=0.3).__source__


# ---------------------------------------------------------------------------------------
# Structure of the generated code, and scalar functions (forcing terms)
# ---------------------------------------------------------------------------------------
def test_a_value_and_its_derivatives_share_one_if_chain():
    # Bingham: one three-way clip chain, not one per output
    kernel = kernel_of("q - gamma*(F - clip(F, -tau, tau))", gamma=2.0, tau=1.0)
    assert kernel.__source__.count("if ") == 2
    assert kernel(0.0, 0.5) == (0.0, 1.0, 0.0)
    assert kernel(1.0, 1.5) == (0.0, 1.0, -2.0)


def test_piecewise_without_fallback_is_nan_where_no_condition_holds():
    kernel = kernel_of("Piecewise((q - F, F > 0))")
    assert kernel(1.0, 1.0) == (0.0, 1.0, -1.0)
    assert all(math.isnan(v) for v in kernel(1.0, -1.0))


@given(st.floats(-1.0, 3.0))
def test_compiled_forcing_expression_matches_the_paper_forcing(time):
    t = sp.Symbol("t")
    A = sp.Symbol("A")
    expr = parse_expression("Piecewise((A*sin(5*pi*t), t <= 1), (0, True))", ["t", "A"])
    force = compile_function(expr, [t], {A: 10.0})
    expected = paper_F2(time) if time >= 0 else 10.0 * math.sin(5 * math.pi * time)
    assert force(time) == pytest.approx(expected, rel=1e-12, abs=1e-14)
    assert type(force(time)) is float


def test_compile_function_errors_and_nan():
    t = sp.Symbol("t")
    with pytest.raises(ValueError, match="w"):
        compile_function(t * sp.Symbol("w"), [t])
    with pytest.raises(TypeError):
        compile_function(t, [t, t])
    root = compile_function(sp.sqrt(t), [t])
    assert root(4.0) == 2.0 and math.isnan(root(-1.0))
    two = compile_function(sp.Max(q, F), [q, F])
    assert two(1.0, 2.0) == 2.0 and "def function(x0, x1)" in two.__source__


def test_unguarded_kernels_have_no_try_and_raise_python_errors():
    expr = parse_expression("sqrt(F) - q", ["q", "F"])
    bare = compile_kernel(expr, q, F, {}, guard=False)
    assert "try" not in bare.__source__ and "except" not in bare.__source__
    assert bare(1.0, 4.0) == (1.0, -1.0, 0.25) == compile_kernel(expr, q, F, {})(1.0, 4.0)
    with pytest.raises(ValueError):
        bare(0.0, -1.0)
