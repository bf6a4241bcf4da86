"""The branches of a law (lumped.codegen.branches): the selector agrees with the kernel,
guards are positive inside their branch only, and locking branches are found from the
expression, not the law's name."""

from __future__ import annotations

import math

import pytest
import sympy as sp
from hypothesis import given
from hypothesis import strategies as st

from lumped.codegen.branches import law_branches
from lumped.codegen.rebinding import codes_of
from lumped.laws import ElementLaw, get_law

#: (label, bound law, expected count, expected lock values by branch (None: no lock))
CASES = [
    ("linear_spring", get_law("linear_spring").bind(k=3.0), [None]),
    ("newtonian", get_law("newtonian").bind(c=2.0), [None]),
    ("bingham", get_law("bingham").bind(gamma=2.0, tau=1.0), [None, None, 0.0]),
    ("coulomb", get_law("coulomb").bind(tau=1.0, r=10.0), [None, None, 0.0]),
    ("string_spring", get_law("string_spring").bind(k=100.0, L=0.1), [None, 0.1]),
    ("hb", get_law("herschel_bulkley").bind(gamma=2.0, tau=1.0, n=0.5), [None, None, 0.0]),
    ("hb_tau0_n1", get_law("herschel_bulkley").bind(gamma=2.0, tau=0.0, n=1.0), [None]),
    ("implicit_spring", get_law("implicit_spring").bind(k=1.0, L0=0.1, F0=1.0), [None]),
    ("s_shaped", get_law("s_shaped").bind(q0=1.0, F0=1.0), [None]),
    # user laws: a hard stop written another way, a Bingham law through sign/Max/Abs,
    # and a smooth-by-pieces spring
    ("user_stop", ElementLaw("stop", "spring", "q - Piecewise((F/k, F < k*L), (L, True))",
                             ["k", "L"]).bind(k=10.0, L=0.2), [None, 0.2]),
    ("user_bingham", ElementLaw("b2", "dashpot", "q - gamma*sign(F)*Max(Abs(F) - tau, 0)",
                                ["gamma", "tau"]).bind(gamma=2.0, tau=1.0),
     [None, 0.0, None, 0.0]),
    ("user_pieces", ElementLaw("p", "spring", "F - k*q*Abs(q) - Max(q, 0)*c",
                               ["k", "c"]).bind(k=2.0, c=1.0), [None, None]),
]
IDS = [c[0] for c in CASES]

points = st.tuples(
    st.one_of(st.floats(-3, 3), st.sampled_from([0.0, 0.1, 0.2, -0.1])),
    st.one_of(st.floats(-30, 30), st.sampled_from([-1.0, 1.0, 0.0, 2.0, 10.0, -10.0])),
)


@pytest.mark.parametrize(("label", "bound", "locks"), CASES, ids=IDS)
def test_branch_structure(label, bound, locks):
    lb = law_branches(bound)
    assert lb.count == len(locks)
    assert [b.lock_value for b in lb.info] == locks
    assert [b.locks for b in lb.info] == [v is not None for v in locks]
    assert law_branches(bound) is lb  # cached


@pytest.mark.parametrize(("label", "bound", "locks"), CASES, ids=IDS)
@given(point=points)
def test_selector_kernel_and_guards_agree(label, bound, locks, point):
    q, F = point
    lb = law_branches(bound)
    i = lb.branch(q, F)
    assert 0 <= i < lb.count
    whole, alone = bound.kernel(q, F), lb.kernel_for(i)(q, F)
    for a, b in zip(whole, alone, strict=True):
        assert (math.isnan(a) and math.isnan(b)) or abs(a - b) <= 1e-14 * (1 + abs(a))
    assert all(g >= 0 for g in lb.guards_for(i)(q, F))
    for j in range(lb.count):
        if j != i:  # another branch is not strictly admissible here
            assert min(lb.guards_for(j)(q, F)) <= 0


def test_guard_changes_sign_where_the_branch_is_left():
    lb = law_branches(get_law("string_spring").bind(k=100.0, L=0.1))
    slack, taut = 0, 1
    assert lb.branch(0.05, 5.0) == slack and lb.branch(0.1, 11.0) == taut
    g = lb.guards_for(slack)
    assert g(0.0, 9.0)[0] > 0 and g(0.0, 10.0)[0] == 0 and g(0.0, 11.0)[0] < 0
    assert lb.info[taut].residual.free_symbols == {sp.Symbol("q")}  # F free: a lock


def test_numba_source_has_no_try():
    lb = law_branches(get_law("bingham").bind(gamma=2.0, tau=1.0))
    src = lb.source_for(1)
    assert "try" not in src and src.startswith("def kernel(q, F):")
    assert "try" in lb.source_for(1, guard=True)


@pytest.mark.parametrize("bad", [-1, 3, 1.0, True, "0"])
def test_bad_branch_index(bad):
    lb = law_branches(get_law("bingham").bind(gamma=2.0, tau=1.0))
    with pytest.raises(ValueError, match="branch index"):
        lb.kernel_for(bad)


def test_bad_law():
    with pytest.raises(TypeError, match="bound"):
        law_branches(object())


def test_doctests_pass():
    import doctest

    import lumped.codegen.branches as module

    result = doctest.testmod(module)
    assert result.attempted > 0 and result.failed == 0


@pytest.mark.parametrize(("n", "steep"), [(0.3, True), (0.5, True), (1.0, False), (2.0, False)])
def test_steep_branches_are_the_unbounded_slopes(n, steep):
    lb = law_branches(get_law("herschel_bulkley").bind(gamma=2.0, tau=1.0, n=n))
    assert [b.steep for b in lb.info] == [steep, steep, False]  # slip+, slip-, stuck
    for name, p in [("bingham", {"gamma": 1.0, "tau": 1.0}), ("s_shaped", {"q0": 1.0, "F0": 1.0}),
                    ("implicit_spring", {"k": 1.0, "L0": 0.1, "F0": 1.0})]:
        assert not any(b.steep for b in law_branches(get_law(name).bind(**p)).info)


def test_fractional_powers_are_continued_oddly_beyond_the_branch() -> None:
    # Herschel-Bulkley n = 3/2, forward slip branch R = q - (F - 1)^1.5: on the branch
    # the kernel is the law's; a hair below the yield force it is finite (was nan), with
    # R = q + (1 - F)^1.5 and dR/dF = -1.5 |F - 1|^0.5
    lb = law_branches(get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=1.5))
    slip = lb.branch(0.5, 2.0)
    k = lb.kernel_for(slip)
    b = 1.21 - 1.0
    assert k(0.0, 1.21) == (-math.pow(b, 1.5) + 0.0, 1.0, -(1.5 * math.pow(b, 0.5)))
    R, Rq, RF = k(0.0, 0.99)
    assert R == pytest.approx(0.01 ** 1.5, rel=1e-12) and Rq == 1.0
    assert RF == pytest.approx(-1.5 * 0.01 ** 0.5, rel=1e-12)


def test_an_even_power_is_continued_with_its_sign_beyond_the_branch() -> None:
    # Herschel-Bulkley n = 2, backward slip branch q = -gamma (-F - tau)^2 (F < -tau):
    # its mirror root F = -tau + sqrt(-q / gamma) beyond the yield force, where a stage
    # solve landed (issue 29, random-network seed 274), is gone; on the branch the kernel
    # is the law's
    gamma, tau, q = 0.27, 0.108, -7.8e-9
    lb = law_branches(get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=2.0))
    back = lb.branch(-1.0, -2.0 * tau)
    k = lb.kernel_for(back)
    d = math.sqrt(-q / gamma)
    assert k(q, -tau - d)[0] == pytest.approx(0.0, abs=1e-20)  # the root on the branch
    R, _, RF = k(q, -tau + d)  # its mirror: R = q - gamma d^2, not 0
    assert R == pytest.approx(2.0 * q, rel=1e-12)
    assert RF == pytest.approx(-2.0 * gamma * d, rel=1e-12)  # monotone: the slope's sign
    assert k(q, -tau - d)[2] == pytest.approx(-2.0 * gamma * d, rel=1e-12)
    # a law even in F everywhere (no branch condition fixes the base's sign) is kept
    even = law_branches(ElementLaw("even", "spring", "q - F**2/k", ["k"]).bind(k=2.0))
    assert even.kernel_for(0)(0.5, -1.0) == (0.0, 1.0, 1.0)


@pytest.mark.parametrize("n", [1.5, 2.0, 3.0])
def test_the_guard_of_a_branch_flat_at_its_end_reads_its_rate(n) -> None:
    # Herschel-Bulkley n > 1 slipping forwards, q = gamma (F - tau)^n: the stage guard of
    # the slip's end is q / gamma, not F - tau (a stage force 1e-7 below the yield force
    # at a rate of 2.6e-11, inside Newton's force tolerance, read a false end: issue 29)
    gamma, tau = 0.28, 0.44
    lb = law_branches(get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=n))
    fwd, back = lb.branch(1.0, 2.0 * tau), lb.branch(-1.0, -2.0 * tau)
    assert min(lb.stage_guards_for(fwd)(2.6e-11, tau - 1e-7)) > 0.0
    assert min(lb.stage_guards_for(back)(-2.6e-11, -tau + 1e-7)) > 0.0
    assert min(lb.stage_guards_for(fwd)(-1e-15, tau + 1e-7)) < 0.0  # the rate's sign
    assert min(lb.guards_for(fwd)(2.6e-11, tau - 1e-7)) < 0.0  # the law's own guards


@pytest.mark.parametrize(("gamma", "tau", "steep"), [
    (1.0, 1.0, False), (10.0, 1.0, False), (20.0, 1.0, True), (1.0, 20.0, True),
    (1e3, 1.0, True), (1e12, 1.0, True), (1e12, 0.0, False)])
def test_an_affine_branch_is_steep_when_its_force_doubles_at_a_large_rate(gamma, tau, steep):
    # Bingham slipping, q - gamma (F - tau): steepness S = gamma tau against 16; a
    # Newtonian (tau = 0) loses nothing in its forward form
    lb = law_branches(get_law("bingham").bind(gamma=gamma, tau=tau))
    slips = [b for b in lb.info if not b.locks]  # slip-, slip+ (tau = 0: one, Newtonian)
    assert slips and all(b.steep is steep and (b.stage is not None) is steep for b in slips)
    assert not any(b.steep for b in lb.info if b.locks)


def test_the_coulomb_limit_is_solved_for_its_force():
    # gamma = 1e12: F = tau + q / gamma on the forward slip branch, its guard at the end
    # of the slip is the rate itself (F - tau is 1e-12 q there), the other stays in F
    lb = law_branches(get_law("bingham").bind(gamma=1e12, tau=1.0))
    fwd, back = lb.branch(3.0, 1.0 + 3e-12), lb.branch(-3.0, -1.0 - 3e-12)
    R, Rq, RF = lb.stage_kernel_for(fwd)(3.0, 1.5)
    assert (R, Rq, RF) == (pytest.approx(0.5 - 3e-12, rel=1e-15), -1e-12, 1.0)
    # (the rate with its factor 1.0, the text of every other gamma: 1e12 is no integer
    # to sympy, rewrite.constant_of)
    assert codes_of(lb.stage_guards_for(fwd))[1] == "1.0*q"
    assert lb.stage_guards_for(fwd)(2.0, 1.0)[0] == 2.0  # F + tau
    assert codes_of(lb.stage_guards_for(back)) == ("-1.0*q",)
    other = law_branches(get_law("bingham").bind(gamma=1.3e12, tau=1.0))
    assert codes_of(other.stage_guards_for(other.branch(3.0, 1.0 + 3e-12)))[1] == "1.0*q"
    # the whole law in the form of the mode choice: the same zeros as the law
    law = lb.stage_law_for(get_law("bingham").bind(gamma=1e12, tau=1.0).kernel)
    assert law(0.0, 0.5) == (0.0, 1.0, 0.0) and law(2.0, 1.0 + 2e-12)[0] == 0.0


def test_steepness_is_read_from_the_expression_not_the_name():
    # the same law written as a user might: scaled by 1/gamma, the slip terms swapped;
    # Herschel-Bulkley n = 1 is Bingham; the coulomb law's slip branch has no q
    user = ElementLaw("my_fluid", "dashpot", "q/gamma - F + clip(F, -tau, tau)",
                      ["gamma", "tau"])
    for bound in (user.bind(gamma=1e9, tau=0.5),
                  get_law("herschel_bulkley").bind(gamma=1e9, tau=0.5, n=1.0)):
        lb = law_branches(bound)
        assert [b.steep for b in lb.info].count(True) == 2
        slip = lb.branch(1.0, 0.5 + 1e-9)
        assert lb.stage_kernel_for(slip)(1.0, 0.5 + 1e-9)[0] == pytest.approx(0.0, abs=1e-16)
        assert lb.stage_kernel_for(slip)(1.0, 0.5)[2] == 1.0
    coulomb = law_branches(get_law("coulomb").bind(tau=1.0, r=1e12))
    assert not any(b.steep for b in coulomb.info)
