"""Element laws: declaration, binding, display, and the maths of every built-in law."""

from __future__ import annotations

import doctest
import math
import pickle
import runpy
import sys
from pathlib import Path

import numpy as np
import pytest
import sympy as sp
from hypothesis import assume, given
from hypothesis import strategies as st

import lumped.codegen.emit
import lumped.laws
import lumped.laws.catalogue
import lumped.laws.element_law
import lumped.laws.parser
from lumped.laws import (
    BUILTIN_LAWS,
    BoundLaw,
    ElementLaw,
    get_law,
    s_shaped_point,
    s_shaped_turning_points,
)
from lumped.solvers.closed.closed_form import bdf1_step

q_, F_ = sp.symbols("q F")

# Parameter values are drawn from small sets so that compiled kernels are reused.
POS = st.sampled_from([0.25, 1.0, 2.0, 7.5, 100.0])
NONNEG = st.sampled_from([0.0, 0.5, 1.0, 3.0])
EXPONENT = st.sampled_from([0.3, 0.5, 1.0, 1.7, 3.0])
COORD = st.floats(-10.0, 10.0, allow_nan=False)

PARAMS = {
    "linear_spring": st.fixed_dictionaries({"k": POS}),
    "string_spring": st.fixed_dictionaries({"k": POS, "L": NONNEG}),
    "newtonian": st.fixed_dictionaries({"c": POS}),
    "bingham": st.fixed_dictionaries({"gamma": POS, "tau": NONNEG}),
    "coulomb": st.fixed_dictionaries({"tau": NONNEG, "r": POS}),
    "herschel_bulkley": st.fixed_dictionaries({"gamma": POS, "tau": NONNEG, "n": EXPONENT}),
    "implicit_spring": st.fixed_dictionaries(
        {"k": POS, "L0": NONNEG, "F0": st.sampled_from([2.0, 5.0, 10.0])}
    ),
    "s_shaped": st.fixed_dictionaries({"q0": POS, "F0": POS}),
}


def kink_distance(name: str, q: float, F: float, p: dict[str, float]) -> float:
    """Distance, in the units of the switching function, from the nearest kink."""
    if name == "string_spring":
        return abs(F / p["k"] - p["L"])
    if name in ("bingham", "herschel_bulkley"):
        return abs(abs(F) - p["tau"])
    if name == "coulomb":
        return abs(abs(F + p["r"] * q) - p["tau"])
    return math.inf


def test_the_catalogue_holds_the_promised_laws():
    assert set(BUILTIN_LAWS) == {
        "linear_spring", "string_spring", "newtonian", "bingham", "coulomb",
        "herschel_bulkley", "implicit_spring", "s_shaped",
    }
    kinds = {name: law.kind for name, law in BUILTIN_LAWS.items()}
    assert kinds["linear_spring"] == kinds["string_spring"] == "spring"
    assert kinds["implicit_spring"] == kinds["s_shaped"] == "spring"
    assert kinds["bingham"] == kinds["coulomb"] == kinds["newtonian"] == "dashpot"
    assert kinds["herschel_bulkley"] == "dashpot"


# ---------------------------------------------------------------------------------------
# Jacobians against central finite differences, away from kinks
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(PARAMS))
@given(data=st.data(), q=COORD, F=COORD)
def test_jacobian_matches_central_differences_away_from_kinks(name, data, q, F):
    p = data.draw(PARAMS[name], label="params")
    h_q, h_F = 1e-6 * (1.0 + abs(q)), 1e-6 * (1.0 + abs(F))
    slack = h_F + p.get("r", 0.0) * h_q
    assume(kink_distance(name, q, F, p) > max(1e-3, 1e3 * slack))
    kernel = get_law(name).bind(**p).kernel
    R, dq, dF = kernel(q, F)
    assert all(math.isfinite(v) for v in (R, dq, dF))
    fd_q = (kernel(q + h_q, F)[0] - kernel(q - h_q, F)[0]) / (2.0 * h_q)
    fd_F = (kernel(q, F + h_F)[0] - kernel(q, F - h_F)[0]) / (2.0 * h_F)
    noise = 1e-9 * (1.0 + abs(R)) / 1e-6
    assert abs(fd_q - dq) <= 1e-5 * abs(dq) + noise + 1e-8
    assert abs(fd_F - dF) <= 1e-5 * abs(dF) + noise + 1e-8


@pytest.mark.parametrize("name", sorted(PARAMS))
@given(data=st.data(), q=COORD, F=COORD)
def test_kernels_return_python_floats(name, data, q, F):
    p = data.draw(PARAMS[name], label="params")
    out = get_law(name).bind(**p).kernel(q, F)
    assert isinstance(out, tuple) and len(out) == 3
    assert all(type(v) is float for v in out)


# ---------------------------------------------------------------------------------------
# Known points of every law: the residual vanishes there
# ---------------------------------------------------------------------------------------
def on_curve(name: str, F: float, p: dict[str, float], t: float) -> tuple[float, float]:
    """A point (q, F) on the law's graph, from the law's explicit side."""
    if name == "linear_spring":
        return F / p["k"], F
    if name == "string_spring":
        return min(F / p["k"], p["L"]), F
    if name == "newtonian":
        return F / p["c"], F
    if name == "bingham":
        tau = p["tau"]
        return p["gamma"] * (F - max(-tau, min(F, tau))), F
    if name == "coulomb":
        # t decides between slipping forward, backward and sticking
        tau = p["tau"]
        if t > 0.5:
            return 10.0 * t, tau
        if t < -0.5:
            return 10.0 * t, -tau
        return 0.0, max(-tau, min(F, tau))
    if name == "herschel_bulkley":
        excess = max(abs(F) - p["tau"], 0.0)
        return math.copysign(p["gamma"] * excess ** p["n"], F) if excess else 0.0, F
    if name == "implicit_spring":
        return F / p["k"] + p["L0"] * math.sinh(F / p["F0"]), F
    if name == "s_shaped":
        return s_shaped_point(3.0 * t, p["q0"], p["F0"])
    raise AssertionError(name)


@pytest.mark.parametrize("name", sorted(PARAMS))
@given(data=st.data(), F=COORD, t=st.floats(-1.0, 1.0))
def test_residual_vanishes_on_known_points(name, data, F, t):
    p = data.draw(PARAMS[name], label="params")
    q, F = on_curve(name, F, p, t)
    R, dq, dF = get_law(name).bind(**p).kernel(q, F)
    scale = abs(q) * abs(dq) + abs(F) * abs(dF) + 1.0
    assert abs(R) <= 1e-13 * scale


def test_bingham_on_curve_examples_from_the_brief():
    bound = get_law("bingham").bind(gamma=3.0, tau=0.5)
    for F in (0.75, 2.0, 9.5):
        assert bound.residual(3.0 * (F - 0.5), F) == 0.0
        assert bound.residual(-3.0 * (F - 0.5), -F) == 0.0
    for F in (-0.5, -0.2, 0.0, 0.4, 0.5):
        assert bound.residual(0.0, F) == 0.0
    assert bound.residual(1.0, 0.2) == 1.0  # moving while below the yield force: not a solution


# ---------------------------------------------------------------------------------------
# Kinks: consistent branch values
# ---------------------------------------------------------------------------------------
@given(gamma=POS, tau=st.sampled_from([0.5, 1.0, 3.0]))
def test_bingham_jacobian_at_the_yield_force_is_the_stuck_branch(gamma, tau):
    kernel = get_law("bingham").bind(gamma=gamma, tau=tau).kernel
    for F in (tau, -tau):
        assert kernel(0.0, F) == (0.0, 1.0, 0.0)
    # one-sided: inside the stuck interval the same; outside it is the slip branch
    assert kernel(0.0, 0.999 * tau)[1:] == (1.0, 0.0)
    assert kernel(0.0, tau + 1.0)[1:] == (1.0, -gamma)


@given(gamma=POS, F=COORD)
def test_bingham_without_yield_force_is_newtonian_and_smooth(gamma, F):
    kernel = get_law("bingham").bind(gamma=gamma, tau=0.0).kernel
    assert kernel(gamma * F, F) == (0.0, 1.0, -gamma)
    assert kernel(0.0, 0.0) == (0.0, 1.0, -gamma)


@given(tau=st.sampled_from([0.5, 1.0, 3.0]), r=POS, q=COORD)
def test_coulomb_jacobian_at_the_switch_is_the_stuck_branch(tau, r, q):
    kernel = get_law("coulomb").bind(tau=tau, r=r).kernel
    for s in (tau, -tau):
        F = s - r * q
        if F + r * q != s:  # the switching value is not representable here
            continue
        R, dq, dF = kernel(q, F)
        assert (dq, dF) == (-r, 0.0)
        assert R == pytest.approx(-r * q)


@given(k=POS, L=NONNEG)
def test_string_spring_jacobian_at_the_taut_point_is_the_spring_branch(k, L):
    kernel = get_law("string_spring").bind(k=k, L=L).kernel
    F = k * L
    if F / k != L:
        F = L * k  # same value; the tie below needs F/k == L exactly
    assume(F / k == L)
    R, dq, dF = kernel(L, F)
    assert R == 0.0 and dq == 1.0 and dF == pytest.approx(-1.0 / k)


@pytest.mark.parametrize("n", [0.2, 0.5, 1.0, 2.0])
def test_herschel_bulkley_derivative_is_finite_at_the_yield_force(n):
    bound = get_law("herschel_bulkley").bind(gamma=2.0, tau=1.0, n=n)
    for F in (1.0, -1.0):
        assert bound.kernel(0.0, F) == (0.0, 1.0, 0.0)
    # the same law written with sign/Max/Abs (the textbook form) has no finite
    # slip-branch slope at |F| = tau when n < 1: that is why the built-in is a Piecewise
    textbook = ElementLaw(
        "hb_textbook", "dashpot", "q - gamma*sign(F)*Max(Abs(F) - tau, 0)**n",
        ["gamma", "tau", "n"],
    ).bind(gamma=2.0, tau=1.0, n=n)
    value = textbook.kernel(0.0, 1.0)
    if n < 1:
        assert all(math.isnan(v) for v in value)
    else:
        assert value[0] == 0.0 and math.isfinite(value[2])


# ---------------------------------------------------------------------------------------
# Relations between laws
# ---------------------------------------------------------------------------------------
@given(gamma=POS, tau=NONNEG, q=COORD, F=COORD)
def test_herschel_bulkley_with_n_1_equals_bingham(gamma, tau, q, F):
    # values to rounding, Jacobians exactly, also at the kinks and with tau = 0
    hb = get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=1.0).kernel
    bingham = get_law("bingham").bind(gamma=gamma, tau=tau).kernel
    for point in ((q, F), (q, tau), (q, -tau)):  # also exactly at the kinks
        a, b = hb(*point), bingham(*point)
        assert a[0] == pytest.approx(b[0], rel=1e-12, abs=1e-12 * (1 + abs(gamma * F)))
        assert a[1:] == b[1:]


@given(gamma=POS, tau=NONNEG, n=EXPONENT, q=COORD, F=COORD)
def test_herschel_bulkley_equals_the_textbook_formula_away_from_the_kink(gamma, tau, n, q, F):
    assume(abs(abs(F) - tau) > 1e-9)
    hb = get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=n)
    expected = q - gamma * math.copysign(max(abs(F) - tau, 0.0) ** n, F)
    assert hb.residual(q, F) == pytest.approx(expected, rel=1e-12, abs=1e-12)


@given(tau=NONNEG, r=POS, q=st.floats(1e-3, 10.0), sign=st.sampled_from([1.0, -1.0]))
def test_coulomb_is_the_limit_of_bingham_with_gamma_1e12(tau, r, q, sign):
    gamma = 1e12
    q = sign * q
    F = sign * tau + q / gamma  # Bingham's force for this slip rate
    # Bingham's residual there is zero up to gamma times the rounding of F: the reason
    # the Coulomb limit has its own, well-conditioned law
    bingham = get_law("bingham").bind(gamma=gamma, tau=tau).residual(q, F)
    assert abs(bingham) <= gamma * 4 * 2.0**-52 * (abs(F) + tau) + 1e-12 * abs(q)
    assert abs(get_law("coulomb").bind(tau=tau, r=r).residual(q, F)) <= 2 * abs(q) / gamma + (
        1e-15 * tau
    )


@given(tau=NONNEG, r=POS, q=st.sampled_from([0.0, 0.0, 1.5, -2.0, 1e-9]), F=COORD,
       snap=st.sampled_from([None, "tau", "-tau"]))
def test_coulomb_solution_set_is_the_coulomb_graph_for_every_r(tau, r, q, F, snap):
    if snap == "tau":
        F = tau
    elif snap == "-tau":
        F = -tau
    on_graph = (q == 0.0 and abs(F) <= tau) or (q > 0 and F == tau) or (q < 0 and F == -tau)
    R = get_law("coulomb").bind(tau=tau, r=r).residual(q, F)
    assert (R == 0.0) == on_graph


@given(k=POS, L=NONNEG, F=st.floats(-1e3, 1e3), q0=COORD)
def test_string_spring_never_exceeds_L(k, L, F, q0):
    bound = get_law("string_spring").bind(k=k, L=L)
    # the residual is affine in q with slope 1: one Newton step from anywhere solves it
    R, dq, _ = bound.kernel(q0, F)
    q = q0 - R / dq
    # (to the rounding of the two operations: q0 = -0.6, R = -1.1 gives L + 1 ulp)
    assert q <= L + 4 * sys.float_info.epsilon * (abs(q0) + L)
    assert abs(bound.residual(q, F)) <= 1e-12 * (1 + abs(q))
    # and no elongation beyond L satisfies the law, whatever the force
    assert bound.residual(L + 1e-6 * (1 + L), F) > 0


def test_s_shaped_turning_points_are_folds_on_the_curve():
    for q0, F0 in ((1.0, 1.0), (0.02, 50.0)):
        bound = get_law("s_shaped").bind(q0=q0, F0=F0)
        folds = s_shaped_turning_points(q0, F0)
        assert folds["F_max"] == pytest.approx((2 * q0, F0))
        assert folds["F_min"] == pytest.approx((-2 * q0, -F0))
        for key, (q, F) in folds.items():
            R, dq, dF = bound.kernel(q, F)
            assert R == pytest.approx(0.0, abs=1e-12)
            if key.startswith("F_"):
                assert dq * q0 == pytest.approx(0.0, abs=1e-12)  # horizontal tangent
                assert abs(dF * F0) > 0.1
            else:
                assert dF * F0 == pytest.approx(0.0, abs=1e-12)  # vertical tangent
                assert abs(dq * q0) > 0.1


def test_s_shaped_is_neither_q_of_F_nor_F_of_q():
    bound = get_law("s_shaped").bind(q0=1.0, F0=1.0)
    s5, s3 = math.sqrt(5.0), math.sqrt(3.0)
    for F in (-s5, 0.0, s5):  # three forces at q = 0
        assert bound.residual(0.0, F) == pytest.approx(0.0, abs=1e-12)
    for q in (-s3, 0.0, s3):  # three elongations at F = 0
        assert bound.residual(q, 0.0) == pytest.approx(0.0, abs=1e-12)


@given(t=st.floats(-4.0, 4.0), q0=POS, F0=POS)
def test_s_shaped_parametrisation_lies_on_the_curve(t, q0, F0):
    q, F = s_shaped_point(t, q0, F0)
    R, dq, dF = get_law("s_shaped").bind(q0=q0, F0=F0).kernel(q, F)
    assert abs(R) <= 1e-12 * (1 + t**4) * 10


@given(k=POS, L0=NONNEG, F0=st.sampled_from([2.0, 5.0]), q=COORD, F=COORD)
def test_implicit_spring_is_strictly_monotone(k, L0, F0, q, F):
    _, dq, dF = get_law("implicit_spring").bind(k=k, L0=L0, F0=F0).kernel(q, F)
    assert dq == 1.0 and dF < 0.0  # so F is a function of q, by the implicit function theorem


# ---------------------------------------------------------------------------------------
# Declaring laws
# ---------------------------------------------------------------------------------------
def test_declare_from_string_and_from_sympy_gives_the_same_law():
    gamma, tau = sp.symbols("gamma tau", positive=True)  # assumptions are matched by name
    q, F = sp.symbols("q F", real=True)
    from_sympy = ElementLaw(
        "bingham", "dashpot", q - gamma * (F - sp.Min(sp.Max(F, -tau), tau)), ["gamma", "tau"],
        domains={"gamma": "positive", "tau": "nonnegative"},
    )
    assert from_sympy == get_law("bingham")
    assert hash(from_sympy) == hash(get_law("bingham"))
    assert from_sympy.q == sp.Symbol("q") and from_sympy.F == sp.Symbol("F")


def test_equations_are_accepted_as_strings_and_as_sympy_eq():
    law = ElementLaw("drag", "dashpot", "F = c*q*Abs(q)", ["c"])
    assert law.residual == F_ - sp.Symbol("c") * q_ * sp.Abs(q_)
    eq = ElementLaw("drag", "dashpot", sp.Eq(F_, sp.Symbol("c") * q_ * sp.Abs(q_)), ["c"])
    assert eq == law
    cmp = ElementLaw("cmp", "spring", "Piecewise((q, F >= 0), (2*q, True)) - F", [])
    assert cmp.residual.has(sp.Piecewise)


@pytest.mark.parametrize(
    ("args", "kwargs", "fragment"),
    [
        (("x", "spring", "F - k*q - x0", ["k"]), {}, "x0"),
        (("x", "spring", "F - k*q", []), {}, "'k'"),
        (("x", "spring", F_ - sp.Symbol("kk") * q_, ["k"]), {}, "kk"),
        (("x", "spring", "2*k", ["k"]), {}, "neither q nor F"),
        (("x", "spring", "k - 1", ["k"]), {}, "neither q nor F"),
        (("x", "spring", sp.Integer(3), []), {}, "neither q nor F"),
        (("x", "spring", "q.__class__", []), {}, "__class__"),
        (("x", "spring", "q = F = 1", []), {}, "'='"),
        (("x", "spring", "F - k*q > 0", ["k"]), {}, "comparison"),
        (("x", "spring", sp.Function("f")(q_) - F_, []), {}, "unsupported"),
        (("x", "spring", sp.Gt(q_, F_), []), {}, "scalar expression"),
        (("x", "spring_", "F - q", []), {}, "kind"),
        (("x", "Spring", "F - q", []), {}, "kind"),
        (("", "spring", "F - q", []), {}, "name"),
        (("1x", "spring", "F - q", []), {}, "name"),
        (("a b", "spring", "F - q", []), {}, "name"),
        (("x", "spring", "F - q", ["k", "k"]), {}, "twice"),
        (("x", "spring", "F - q", ["q"]), {}, "reserved"),
        (("x", "spring", "F - q", ["sin"]), {}, "sin"),
        (("x", "spring", "F - q", ["__k"]), {}, "__k"),
        (("x", "spring", "F - k*q", ["k"]), {"domains": {"c": "positive"}}, "'c'"),
        (("x", "spring", "F - k*q", ["k"]), {"domains": {"k": "big"}}, "big"),
    ],
)
def test_declaration_errors_name_the_problem(args, kwargs, fragment):
    with pytest.raises(ValueError) as info:
        ElementLaw(*args, **kwargs)
    assert fragment in str(info.value)


def test_declaration_type_errors():
    with pytest.raises(TypeError):
        ElementLaw("x", "spring", 3.0, [])  # type: ignore[arg-type]
    with pytest.raises(TypeError):
        ElementLaw("x", "spring", "F - k*q", "k")


def test_a_listed_but_unused_parameter_is_fine():
    law = ElementLaw("x", "spring", "F - k*q", ["k", "unused"])
    assert law.bind(k=2.0, unused=5.0).kernel(1.0, 2.0) == (0.0, -2.0, 1.0)


# ---------------------------------------------------------------------------------------
# Binding
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize(
    ("name", "params", "fragment"),
    [
        ("bingham", {"gamma": 1.0}, "missing parameter(s) tau"),
        ("bingham", {"gamma": 1.0, "tau": 1.0, "mu": 2.0}, "unknown parameter(s) mu"),
        ("bingham", {"gamma": float("nan"), "tau": 1.0}, "`gamma` must be finite"),
        ("bingham", {"gamma": 1.0, "tau": float("inf")}, "`tau` must be finite"),
        ("bingham", {"gamma": 0.0, "tau": 1.0}, "`gamma` must be positive"),
        ("bingham", {"gamma": 1.0, "tau": -1.0}, "`tau` must be non-negative"),
        ("linear_spring", {"k": -3.0}, "`k` must be positive"),
        ("string_spring", {"k": 1.0, "L": -0.1}, "`L` must be non-negative"),
        ("coulomb", {"tau": 1.0, "r": 0.0}, "`r` must be positive"),
        ("herschel_bulkley", {"gamma": 1.0, "tau": 1.0, "n": 0.0}, "`n` must be positive"),
        ("implicit_spring", {"k": 1.0, "L0": 1.0, "F0": -1.0}, "`F0` must be positive"),
        ("s_shaped", {"q0": 0.0, "F0": 1.0}, "`q0` must be positive"),
        ("newtonian", {"c": -1.0}, "`c` must be non-negative"),
    ],
)
def test_bind_errors_name_the_law_and_the_parameter(name, params, fragment):
    with pytest.raises(ValueError) as info:
        get_law(name).bind(**params)
    assert fragment in str(info.value)
    assert name in str(info.value)


def test_bind_refuses_non_numbers():
    with pytest.raises(TypeError, match="k"):
        get_law("linear_spring").bind(k="100")


def test_bound_law_is_immutable_and_copies_its_parameters():
    bound = get_law("linear_spring").bind(k=100.0)
    params = bound.params
    params["k"] = 1.0
    assert bound.params == {"k": 100.0}
    with pytest.raises(AttributeError):
        bound.law = get_law("bingham")  # type: ignore[misc]
    assert bound.kernel is bound.kernel
    assert bound == get_law("linear_spring").bind(k=100)
    assert "k=100.0" in repr(bound) and "linear_spring" in str(bound)
    assert bound.expression() == F_ - sp.Float(100.0) * q_
    bound.kernel(1.0, 1.0)
    copy = pickle.loads(pickle.dumps(bound))
    assert copy == bound and copy.kernel(0.5, 1.0) == bound.kernel(0.5, 1.0)
    assert isinstance(bound, BoundLaw)


def test_get_law_lists_known_names():
    with pytest.raises(ValueError, match="bingham.*coulomb"):
        get_law("bingam")


# ---------------------------------------------------------------------------------------
# Display, identity
# ---------------------------------------------------------------------------------------
def test_str_and_latex():
    law = get_law("bingham")
    assert str(law) == "bingham (dashpot): q - gamma*(F - Min(tau, Max(F, -tau))) = 0"
    latex = law.latex()
    assert latex.endswith("= 0") and r"\gamma" in latex and r"\tau" in latex
    assert law._repr_latex_().startswith("$") and law._repr_latex_().endswith("$")
    assert "ElementLaw('bingham', 'dashpot'" in repr(law)
    assert str(get_law("linear_spring")) == "linear_spring (spring): F - k*q = 0"
    assert "Piecewise" in str(get_law("herschel_bulkley"))
    assert r"\begin{cases}" in get_law("herschel_bulkley").latex()


def test_laws_are_immutable_hashable_and_picklable():
    law = get_law("coulomb")
    with pytest.raises(AttributeError):
        law.name = "other"  # type: ignore[misc]
    with pytest.raises(AttributeError):
        del law.kind
    assert pickle.loads(pickle.dumps(law)) == law
    assert len({law, get_law("coulomb"), get_law("bingham")}) == 2
    assert law.parameters == ("tau", "r")
    assert law.q == sp.Symbol("q") and law.F == sp.Symbol("F")
    assert law.symbols["tau"] == sp.Symbol("tau")
    dq, dF = law.derivatives()
    assert dq.has(sp.Symbol("r"))


# ---------------------------------------------------------------------------------------
# Documentation: every built-in has maths and a doctest, and the doctests pass
# ---------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", sorted(BUILTIN_LAWS))
def test_every_builtin_has_a_docstring_with_an_example(name):
    doc = getattr(lumped.laws.catalogue, name).__doc__
    assert doc and ">>>" in doc and "Examples" in doc
    assert getattr(lumped.laws.catalogue, name)() == BUILTIN_LAWS[name]
    assert BUILTIN_LAWS[name].description


@pytest.mark.parametrize("module", [
    lumped.laws.element_law, lumped.laws.catalogue, lumped.codegen.emit, lumped.laws.parser,
])
def test_doctests_pass(module):
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS)
    assert result.attempted > 0 and result.failed == 0


def test_the_custom_law_example_runs(capsys):
    path = Path(__file__).resolve().parents[2] / "examples" / "custom_law.py"
    runpy.run_path(str(path), run_name="__main__")
    out = capsys.readouterr().out
    assert "quadratic_drag (dashpot): F - c*q*Abs(q) = 0" in out
    assert "0.0 -2.0 1.0" in out
    assert "def kernel(q, F):" in out


@given(
    m=st.sampled_from([1.0, 2.5]), k=st.sampled_from([10.0, 100.0]),
    h=st.sampled_from([1e-3, 1e-2]), tau=st.sampled_from([0.5, 1.0]),
    x_n=st.floats(-0.1, 0.1), v_n=st.floats(-2.0, 2.0), force=st.floats(-20.0, 20.0),
    start=st.lists(st.floats(-5.0, 5.0), min_size=4, max_size=4),
)
def test_coulomb_with_r_from_the_predictor_solves_a_bdf1_step_in_two_newton_iterations(
    m, k, h, tau, x_n, v_n, force, start
):
    # The docstring's claim: with r = m/h + h k, semismooth Newton on one BDF1 step of
    # mass + linear spring + Coulomb pad converges in at most two iterations, from any
    # start, to the closed-form step with 1/gamma = 0.
    kernel = get_law("coulomb").bind(tau=tau, r=m / h + h * k).kernel
    z = np.array(start)  # x, v, F_s, F_d
    for _ in range(2):
        x, v, F_s, F_d = z
        R, dq, dF = kernel(v, F_d)
        G = np.array([m * (v - v_n) / h - force + F_s + F_d, x - x_n - h * v, F_s - k * x, R])
        J = np.array([[0, m / h, 1, 1], [1, -h, 0, 0], [-k, 0, 1, 0], [0, dq, 0, dF]])
        z = z - np.linalg.solve(J, G)
    x_c, v_c, F_c, _ = bdf1_step(m, k, 0.0, tau, h, x_n, v_n, force)
    assert z[1] == pytest.approx(v_c, abs=1e-9 * (1 + abs(force)))
    assert z[3] == pytest.approx(F_c, abs=1e-9 * (1 + abs(force)))
    assert z[0] == pytest.approx(x_c, abs=1e-9)


@given(
    d=st.floats(1e-9, 1e-3), gamma=st.sampled_from([3.3e11, 1e12]), sign=st.sampled_from([1, -1])
)
def test_bingham_residual_keeps_gamma_times_the_excess_force_accurate(d, gamma, sign):
    # R = q - gamma*(F - clip(F)) is evaluated as written: distributing gamma over the
    # difference (gamma*F - gamma*clip) would lose gamma * eps * |F| to cancellation
    tau = 1.5
    F = sign * (tau + d)
    excess = F - sign * tau  # exact (Sterbenz)
    q = gamma * excess
    R = get_law("bingham").bind(gamma=gamma, tau=tau).residual(q, F)
    assert abs(R) <= 2 * 2.0**-52 * abs(q)


def test_a_laws_hash_is_computed_once(monkeypatch):
    """A bound law is hashed by every cache a run with new numbers looks it up in (and its
    law with it): the content key of each is made once (counted), and equal laws still
    hash alike (a pickled copy included)."""
    from lumped.laws.element_law import BoundLaw, ElementLaw

    keys = []
    for cls in (BoundLaw, ElementLaw):
        real = cls._key
        monkeypatch.setattr(cls, "_key", lambda self, real=real: keys.append(1) or real(self))
    law = ElementLaw("hash_once", "spring", "F - k*q", ["k"])
    bound = law.bind(k=2.5)
    first = hash(bound)
    assert len(keys) == 2  # the bound law's key and its law's
    assert hash(bound) == first and hash(law) == hash(bound.law) and len(keys) == 2
    again = pickle.loads(pickle.dumps(bound))
    assert again == bound and hash(again) == first
