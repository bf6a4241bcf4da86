"""The generic BDF solver against the closed form, exact solutions and the laws' limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
import scipy.linalg
from _fake_laws import bound, law
from _helpers import assert_columns_close
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped.scene import Element, Junction, Mass, Scene, SineBurst, paper_F2
from lumped.simulate import simulate
from lumped.solvers.closed.closed_form import BinghamOscillator, initial_dashpot_force
from lumped.solvers.closed.integrate import integrate
from lumped.solvers.implicit.branch_check import left_branch
from lumped.solvers.registry import METHODS
from lumped.solvers.status import BranchError, InconsistentInitialForce, SolverError, Status


def paper_scene(m=1.0, k=100.0, gamma=1.0, tau=1.0, x0=0.0, v0=0.0, forcing=None,
                flip_spring=False, F0=None):
    a, b = ("mass", "ground") if flip_spring else ("ground", "mass")
    return Scene(
        [Mass("mass", m, x0=x0, v0=v0)],
        [Element("spring", law("linear_spring", k=k), a, b),
         Element("dashpot", law("bingham", gamma=gamma, tau=tau), "ground", "mass", F0=F0)],
        {"mass": forcing} if forcing is not None else None,
    )


# ---------------------------------------------------------------------------------------
# agreement with the closed form (issue item 5)

params = st.fixed_dictionaries({
    "m": st.floats(0.1, 10.0), "k": st.floats(1.0, 1000.0),
    "gamma": st.floats(0.01, 100.0), "tau": st.floats(0.0, 10.0),
    "x0": st.floats(-1.0, 1.0), "v0": st.floats(-3.0, 3.0),
    "dt": st.floats(1e-4, 1e-2), "n": st.integers(2, 60),
    "amp": st.floats(-20.0, 20.0), "omega": st.floats(0.0, 40.0), "t_off": st.floats(0.0, 2.0),
})


@given(params, st.sampled_from(["bdf1", "bdf2"]))
def test_generic_equals_closed_form(p, formula):
    forcing = SineBurst(p["amp"], p["omega"], p["t_off"])
    if abs(p["v0"]) < 1e-200:  # speeds below ~1e-260 count as rest (see integrators)
        p["v0"] = 0.0
    sc = paper_scene(p["m"], p["k"], p["gamma"], p["tau"], p["x0"], p["v0"], forcing)
    t_end = p["n"] * p["dt"]
    gen = simulate(sc, method=formula, dt=p["dt"], t_end=t_end)
    osc = BinghamOscillator(p["m"], p["k"], p["gamma"], p["tau"])
    traj = integrate(osc, x0=p["x0"], v0=p["v0"], forcing=forcing, dt=p["dt"],
                     n_steps=gen.stats["steps"], method=formula)
    ref = np.column_stack([traj.t, traj.x, traj.v, traj.F_s, traj.F_d])
    # both forces come out of the node's balance, so each carries the round-off of the
    # largest force there (a stop: F_d = 2.46 from terms of 270, 1e-11 apart)
    scale = np.abs(ref).max(axis=0)
    scale[3:] = scale[3:].max()
    assert_columns_close(gen.data, ref, scale=scale)


def test_closed_methods_reproduce_integrate_and_flip_orientation():
    sc = paper_scene(x0=0.5, flip_spring=True)
    sol = simulate(sc, method="closed-bdf1", dt=1e-3, t_end=1.0)
    traj = integrate(BinghamOscillator(1.0, 100.0, 1.0, 1.0), x0=0.5, dt=1e-3, t_end=1.0)
    np.testing.assert_array_equal(sol.column("F_spring"), -traj.F_s)
    np.testing.assert_array_equal(sol.column("x_mass"), traj.x)
    gen = simulate(sc, method="bdf1", dt=1e-3, t_end=1.0)
    assert_columns_close(gen.data, sol.data)


def test_auto_runs_what_the_arguments_ask_for():
    """``dt`` alone: a fixed-step method (the closed form only on the paper's scene);
    ``rtol``/``atol``, or neither: ``radau5`` (issue 29: ``rtol`` was refused on the
    paper's scene, which asked for ``dt``)."""
    paper = paper_scene(x0=0.1)
    assert simulate(paper, dt=1e-3, t_end=0.01).method == "closed-bdf2"
    assert simulate(paper, rtol=1e-8, t_end=0.01).method == "radau5"
    assert simulate(paper, atol=1e-9, t_end=0.01).method == "radau5"
    assert simulate(paper, t_end=0.01).method == "radau5"
    sampled = simulate(paper, rtol=1e-8, dt=1e-3, t_end=0.01)
    assert sampled.method == "radau5" and len(sampled.t) == 11
    sc = Scene([Mass("mass", 1.0, x0=0.1)],
               [Element("spring", law("linear_spring", k=100.0), "ground", "mass"),
                Element("dashpot", law("newtonian", c=1.0), "ground", "mass")])
    assert simulate(sc, dt=1e-3, t_end=0.01).method == "bdf2"
    assert simulate(sc, rtol=1e-6, t_end=0.01).method == "radau5"
    assert simulate(sc, t_end=0.01).method == "radau5"
    with pytest.raises(ValueError, match="closed-bdf1.*linear_spring"):
        simulate(sc, method="closed-bdf1", dt=1e-3, t_end=0.01)


@pytest.mark.parametrize("bad", ["bdf3", "closed", "", None, "BDF1"])
def test_bad_method_names(bad):
    with pytest.raises(ValueError, match="`method` must be one of"):
        simulate(paper_scene(), method=bad, dt=1e-3, t_end=0.01)


def test_methods_tuple():
    assert METHODS == ("auto", "bdf1", "bdf2", "jit-bdf1", "jit-bdf2", "closed-bdf1",
                       "closed-bdf2", "exact", "radau5")


@pytest.mark.parametrize("kw, match", [({"dt": 0.0}, "dt"), ({"dt": math.nan}, "dt"),
                                       ({"t_end": -1.0}, "t_end")])
def test_bad_steps(kw, match):
    args = {"dt": 1e-3, "t_end": 0.1, **kw}
    with pytest.raises(ValueError, match=match):
        simulate(paper_scene(), **args)


# ---------------------------------------------------------------------------------------
# Newton budget (issue item 6)

@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
@pytest.mark.parametrize("x0, forcing", [(0.5, None), (0.0, paper_F2)])
def test_newton_budget_on_the_bingham_scene(formula, x0, forcing):
    sol = simulate(paper_scene(x0=x0, forcing=forcing), method=formula, dt=1e-3, t_end=5.0)
    st_ = sol.stats
    assert st_["newton_iterations"] / st_["steps"] <= 2.0
    assert st_["max_newton_iterations"] <= 4
    assert st_["factorizations"] <= st_["newton_iterations"] + st_["steps"]


# ---------------------------------------------------------------------------------------
# consistent initial conditions


@given(st.floats(-1.0, 1.0), st.floats(-2.0, 2.0), st.floats(-5.0, 5.0), st.floats(0.0, 3.0))
def test_initial_dashpot_force_matches_closed_form(x0, v0, F0, tau):
    osc = BinghamOscillator(1.0, 10.0, 2.0, tau)
    sc = paper_scene(k=10.0, gamma=2.0, tau=tau, x0=x0, v0=v0, forcing=F0)
    sol = simulate(sc, method="bdf1", dt=1e-3, t_end=1e-3)
    # (the limit step of bdf1's initial state: a v0 it reverses counts as rest)
    expected = initial_dashpot_force(osc, x0, v0, F0, h=1e-20 * 1e-3)
    assert sol.column("F_dashpot")[0] == pytest.approx(expected, rel=1e-12, abs=1e-12)
    assert sol.column("F_spring")[0] == pytest.approx(10.0 * x0, rel=1e-12, abs=1e-12)


def test_user_initial_forces_checked():
    sol = simulate(paper_scene(x0=0.5, F0=0.0), method="bdf1", dt=1e-3, t_end=0.01)
    assert sol.column("F_dashpot")[0] == 0.0  # the paper's admissible choice F_d(0) = 0
    with pytest.raises(InconsistentInitialForce, match="dashpot.*'bingham'"):
        simulate(paper_scene(x0=0.5, F0=5.0), method="bdf1", dt=1e-3, t_end=0.01)
    sc = Scene([Mass("mass", 1.0, x0=0.5)],
               [Element("spring", law("linear_spring", k=100.0), "ground", "mass", F0=1.0)])
    with pytest.raises(InconsistentInitialForce, match="spring.*'linear_spring'"):
        simulate(sc, method="bdf2", dt=1e-3, t_end=0.01)


# ---------------------------------------------------------------------------------------
# Maxwell chain against its exact (matrix-exponential) solution


def maxwell_scene(m=1.0, k=50.0, c=2.0, x0=0.3, xj0=0.0, v0=0.0):
    """ground --dashpot(c)-- j --spring(k)-- mass."""
    return Scene(
        [Mass("mass", m, x0=x0, v0=v0), Junction("j", x0=xj0)],
        [Element("dashpot", law("newtonian", c=c), "ground", "j"),
         Element("spring", law("linear_spring", k=k), "j", "mass")],
    )


def maxwell_exact(t, m=1.0, k=50.0, c=2.0, x0=0.3, xj0=0.0, v0=0.0):
    # state (x, v, xj): x' = v, m v' = -k (x - xj), c xj' = k (x - xj); t uniform
    A = np.array([[0, 1, 0], [-k / m, 0, k / m], [k / c, 0, -k / c]])
    step = scipy.linalg.expm(A * (t[1] - t[0]))
    out = [np.array([x0, v0, xj0])]
    for _ in t[1:]:
        out.append(step @ out[-1])
    return np.array(out)


def test_maxwell_initial_state_is_consistent():
    sol = simulate(maxwell_scene(), method="bdf1", dt=1e-3, t_end=1e-3)
    assert sol.column("F_spring")[0] == pytest.approx(50.0 * 0.3)
    assert sol.column("F_dashpot")[0] == pytest.approx(50.0 * 0.3)
    assert sol.column("v_j")[0] == pytest.approx(50.0 * 0.3 / 2.0)


@pytest.mark.parametrize("formula, order", [("bdf1", 1), ("bdf2", 2)])
def test_maxwell_relaxation_converges_at_the_order_of_the_method(formula, order):
    errors, dts = [], [2e-3, 1e-3, 5e-4]
    for dt in dts:
        sol = simulate(maxwell_scene(), method=formula, dt=dt, t_end=1.0)
        exact = maxwell_exact(sol.t)
        err = max(np.abs(sol.column("x_mass") - exact[:, 0]).max(),
                  np.abs(sol.column("x_j") - exact[:, 2]).max())
        F_exact = 50.0 * (exact[:, 0] - exact[:, 2])
        np.testing.assert_allclose(sol.column("F_spring"), sol.column("F_dashpot"), atol=1e-9)
        err = max(err, np.abs(sol.column("F_spring") - F_exact).max() / 50.0)
        errors.append(err)
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.15, (errors, slope)
    assert errors[-1] < (3e-2 if order == 1 else 2e-3)


def test_maxwell_relaxes_to_rest():
    sol = simulate(maxwell_scene(), method="bdf2", dt=1e-2, t_end=20.0)
    assert abs(sol.column("F_spring")[-1]) < 1e-6 * 15.0
    assert abs(sol.column("v_mass")[-1]) < 1e-6


# ---------------------------------------------------------------------------------------
# the laws' limits in simulation


def two_law_scene(dashpot_law, x0=0.5, forcing=None):
    return Scene([Mass("mass", 1.0, x0=x0)],
                 [Element("spring", law("linear_spring", k=100.0), "ground", "mass"),
                  Element("dashpot", dashpot_law, "ground", "mass")],
                 {"mass": forcing} if forcing is not None else None)


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
@pytest.mark.parametrize("x0, forcing", [(0.5, None), (0.0, paper_F2), (0.005, None)])
def test_coulomb_equals_bingham_at_huge_gamma(formula, x0, forcing):
    co = simulate(two_law_scene(law("coulomb", tau=1.0, r=1.0), x0, forcing), method=formula,
                  dt=1e-3, t_end=2.0)
    bi = simulate(two_law_scene(law("bingham", gamma=1e12, tau=1.0), x0, forcing),
                  method=formula, dt=1e-3, t_end=2.0)
    assert_columns_close(co.data, bi.data, rel=1e-9)


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
@pytest.mark.parametrize("x0, forcing", [(0.5, None), (0.0, paper_F2)])
def test_herschel_bulkley_n1_equals_bingham(formula, x0, forcing):
    hb = simulate(two_law_scene(law("herschel_bulkley", gamma=1.0, tau=1.0, n=1.0), x0,
                                forcing), method=formula, dt=1e-3, t_end=2.0)
    bi = simulate(two_law_scene(law("bingham", gamma=1.0, tau=1.0), x0, forcing),
                  method=formula, dt=1e-3, t_end=2.0)
    assert_columns_close(hb.data, bi.data, rel=1e-10)


@pytest.mark.parametrize("dashpot", [
    ("herschel_bulkley", {"gamma": 1.0, "tau": 1.0, "n": 0.5}),  # shear-thinning
    ("herschel_bulkley", {"gamma": 1.0, "tau": 1.0, "n": 2.0}),  # shear-thickening
    ("coulomb", {"tau": 1.0, "r": 50.0}),
    ("newtonian", {"c": 0.3}),
])
@pytest.mark.parametrize("spring", [
    ("linear_spring", {"k": 100.0}),
    ("implicit_spring", {"k": 100.0, "L0": 0.01, "F0": 5.0}),
])
def test_bdf1_solution_satisfies_the_discrete_equations(dashpot, spring):
    """Each step solves m (v1 - v0)/dt = f - F_s - F_d, x1 = x0 + dt v1 and both laws."""
    (sname, sp), (dname, dp) = spring, dashpot
    s_law, d_law = law(sname, **sp), law(dname, **dp)
    sc = Scene([Mass("mass", 1.0)],
               [Element("spring", s_law, "ground", "mass"),
                Element("dashpot", d_law, "ground", "mass")], {"mass": paper_F2})
    dt = 1e-3
    sol = simulate(sc, method="bdf1", dt=dt, t_end=2.0)
    t, x, v = sol.t, sol.column("x_mass"), sol.column("v_mass")
    Fs, Fd = sol.column("F_spring"), sol.column("F_dashpot")
    f = np.array([paper_F2(ti) for ti in t])
    momentum = (v[1:] - v[:-1]) / dt - (f[1:] - Fs[1:] - Fd[1:])
    assert np.abs(momentum).max() <= 1e-9 * (np.abs(v).max() / dt + np.abs(Fs).max() + 10)
    np.testing.assert_allclose(x[1:], x[:-1] + dt * v[1:], rtol=0, atol=1e-15)
    for lw, q, F in ((s_law, x, Fs), (d_law, v, Fd)):
        for qi, Fi in zip(q, F, strict=True):
            R, Rq, RF = lw.kernel(qi, Fi)
            assert abs(R) <= 1e-9 * (abs(Rq * qi) + abs(RF * Fi)) + 1e-11
    assert sol.stats["max_newton_iterations"] <= 50
    assert np.abs(v).max() > 0.01  # it did slip


@settings(max_examples=100)
@given(st.floats(0.05, 1.0), st.floats(1.0, 50.0), st.floats(-1.0, 1.0),
       st.sampled_from(["bdf1", "bdf2"]))
def test_string_spring_never_exceeds_L(L, pull, v0, formula):
    sc = Scene([Mass("mass", 1.0, v0=v0)],
               [Element("string", law("string_spring", k=10.0, L=L), "ground", "mass"),
                Element("damper", law("newtonian", c=0.5), "ground", "mass")],
               {"mass": SineBurst(pull, 3.0, 10.0)})
    sol = simulate(sc, method=formula, dt=5e-3, t_end=1.5)
    assert (sol.column("x_mass") <= L * (1 + 1e-12) + 1e-15).all()


def test_string_spring_goes_taut():
    sc = Scene([Mass("mass", 1.0)],
               [Element("string", law("string_spring", k=10.0, L=0.1), "ground", "mass")],
               {"mass": 5.0})
    sol = simulate(sc, method="bdf1", dt=1e-3, t_end=1.0)
    x = sol.column("x_mass")
    assert x.max() == pytest.approx(0.1, rel=1e-12)
    assert sol.column("F_string")[-1] == pytest.approx(5.0, rel=1e-6)


# ---------------------------------------------------------------------------------------
# a non-monotone law: follow the branch or stop, never jump


def s_scene(ramp):
    """An S-shaped spring q = F^3 - F, started on its upper branch (F = 1.5), then
    unloaded slowly: the upper branch ends in a fold at F = 1/sqrt(3)."""
    F0 = 1.5
    return Scene([Mass("mass", 0.01, x0=F0**3 - F0)],
                 [Element("s", bound("s_shaped"), "ground", "mass"),
                  Element("damper", law("newtonian", c=0.02), "ground", "mass")],
                 {"mass": (lambda t: F0 - ramp * t)})


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
def test_s_shaped_follows_its_branch_before_the_fold(formula):
    sol = simulate(s_scene(0.5), method=formula, dt=1e-3, t_end=1.0)  # F stays > 0.9
    F = sol.column("F_s")
    assert (F > 1 / math.sqrt(3)).all()
    assert np.abs(np.diff(F)).max() < 0.01


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
def test_s_shaped_stops_at_the_fold_instead_of_jumping(formula):
    with pytest.raises(SolverError, match=r"t = \d") as info:
        simulate(s_scene(0.5), method=formula, dt=1e-3, t_end=4.0)
    assert "'s'" in str(info.value) or "node" in str(info.value)
    sol = simulate(s_scene(0.5), method=formula, dt=1e-3, t_end=4.0, throw=False)
    assert sol.status is not Status.SUCCESS and sol.message
    F = sol.column("F_s")
    assert np.abs(np.diff(F)).max() < 0.05  # no silent jump to the lower branch
    assert (F > 0.0).all()


def test_branch_error_names_element_and_time():
    """With a coarse step, Newton converges on the lower branch: caught, not accepted."""
    with pytest.raises(BranchError) as info:
        simulate(s_scene(0.5), method="bdf1", dt=0.05, t_end=4.0)
    err = info.value
    assert err.status is Status.BRANCH_LOST and "element 's'" in str(err)
    assert 1.5 < err.t < 4.0


def test_fold_detector():
    kernel = bound("s_shaped").kernel

    def pt(F):
        q = F**3 - F
        return q, F, *kernel(q, F)[1:]

    def jump(F0, F1):
        q0, F0, Rq0, RF0 = pt(F0)
        q1, F1, Rq1, RF1 = pt(F1)
        return left_branch(kernel, q0, F0, Rq0, RF0, q1, F1, Rq1, RF1)

    assert not jump(1.2, 1.19)  # along the upper branch
    assert not jump(-1.2, -1.21)  # along the lower branch
    assert jump(0.7, 0.4)  # over the fold into the middle branch
    q = 0.7**3 - 0.7
    lower = -1.1  # roughly the same q on the lower branch
    assert left_branch(kernel, q, 0.7, *kernel(q, 0.7)[1:], lower**3 - lower, lower,
                        *kernel(lower**3 - lower, lower)[1:])
    # monotone piecewise-linear laws never trip it: Bingham stick -> slip
    bk = bound("bingham", gamma=1.0, tau=1.0).kernel
    assert not left_branch(bk, 0.0, 0.3, *bk(0.0, 0.3)[1:], 0.5, 1.5, *bk(0.5, 1.5)[1:])
    assert not left_branch(bk, 0.0, 0.9, *bk(0.0, 0.9)[1:], 0.0, -0.9, *bk(0.0, -0.9)[1:])


# ---------------------------------------------------------------------------------------
# Solution, CSV, failures


def test_csv_header_and_precision(tmp_path):
    sc = maxwell_scene()
    sol = simulate(sc, method="bdf2", dt=1e-2, t_end=0.1)
    path = sol.to_csv(tmp_path / "out.csv")
    lines = path.read_text().splitlines()
    assert lines[0] == "t,x_mass,v_mass,x_j,v_j,F_dashpot,F_spring"
    back = np.loadtxt(path, delimiter=",", skiprows=1)
    np.testing.assert_array_equal(back, sol.data)
    assert set(sol.F) == {"dashpot", "spring"} and set(sol.x) == {"mass", "j"}
    assert sol.forces.shape == (len(sol.t), 2)


def test_failed_newton_raises_or_returns_partial():
    def blow_up(q, F):
        return (F - q if q < 0.05 else math.nan), -1.0, 1.0

    from _fake_laws import FakeBound, FakeLaw
    bad = FakeBound(FakeLaw("brittle", "spring"), {}, blow_up)
    sc = Scene([Mass("mass", 1.0)], [Element("e", bad, "ground", "mass")], {"mass": 1.0})
    with pytest.raises(SolverError, match=r"t = .*element 'e'"):
        simulate(sc, method="bdf1", dt=1e-2, t_end=2.0)
    sol = simulate(sc, method="bdf1", dt=1e-2, t_end=2.0, throw=False)
    assert sol.status is Status.NON_FINITE
    assert 1 < len(sol.t) < 201 and np.isfinite(sol.data).all()


# ---------------------------------------------------------------------------------------
# the built-in S-shaped law under a slowly rising load


def builtin_s_scene(ramp, t_start=-3.0):
    """Start on the branch ``t < -1`` of the built-in curve and raise the load: the
    branch ends at the force maximum ``F_max = (2 q0, F0)``."""
    from lumped.laws import s_shaped_point

    q_start, F_start = s_shaped_point(t_start)
    return Scene([Mass("mass", 0.01, x0=q_start)],
                 [Element("s", law("s_shaped", q0=1.0, F0=1.0), "ground", "mass"),
                  Element("damper", law("newtonian", c=0.05), "ground", "mass")],
                 {"mass": (lambda t: F_start + ramp * t)})


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
@pytest.mark.parametrize("dt", [1e-3, 2e-2])
def test_builtin_s_shaped_follows_or_stops_never_jumps(formula, dt):
    from lumped.laws import s_shaped_turning_points

    F_max = s_shaped_turning_points()["F_max"][1]
    ramp = 2.0  # the load passes F_max = 1 at t = 5
    before = simulate(builtin_s_scene(ramp), method=formula, dt=dt, t_end=4.0)
    F = before.column("F_s")
    assert np.abs(np.diff(F)).max() < 50 * ramp * dt  # continuous along its branch
    with pytest.raises(SolverError, match=r"t = \d"):
        simulate(builtin_s_scene(ramp), method=formula, dt=dt, t_end=8.0)
    sol = simulate(builtin_s_scene(ramp), method=formula, dt=dt, t_end=8.0, throw=False)
    F = sol.column("F_s")
    assert not sol.ok and (F <= F_max + 1e-6).all()  # never on the far branch
    assert np.abs(np.diff(F)).max() < 50 * ramp * dt


# ---------------------------------------------------------------------------------------
# a network of several masses against its exact solution


def chain_scene(forcing=None):
    """ground -k1- m1 -k2- m2, with a Newtonian dashpot c between m1 and m2 (drawn from
    m2 to m1, the other orientation) and a force on m2."""
    return Scene(
        [Mass("m1", 1.0, x0=0.2), Mass("m2", 2.0, v0=-0.5)],
        [Element("k1", law("linear_spring", k=30.0), "ground", "m1"),
         Element("k2", law("linear_spring", k=20.0), "m1", "m2"),
         Element("c", law("newtonian", c=0.7), "m2", "m1")],
        {"m2": forcing} if forcing is not None else None,
    )


def chain_exact(t):
    # state (x1, v1, x2, v2); dashpot from m2 to m1: q = v1 - v2, +F on m2, -F on m1
    k1, k2, c, m1, m2 = 30.0, 20.0, 0.7, 1.0, 2.0
    A = np.array([
        [0, 1, 0, 0],
        [(-k1 - k2) / m1, -c / m1, k2 / m1, c / m1],
        [0, 0, 0, 1],
        [k2 / m2, c / m2, -k2 / m2, -c / m2],
    ])
    step = scipy.linalg.expm(A * (t[1] - t[0]))
    out = [np.array([0.2, 0.0, 0.0, -0.5])]
    for _ in t[1:]:
        out.append(step @ out[-1])
    return np.array(out)


@pytest.mark.parametrize("formula, order", [("bdf1", 1), ("bdf2", 2)])
def test_two_mass_chain_converges_to_its_exact_solution(formula, order):
    errors, dts = [], [4e-3, 2e-3, 1e-3]
    for dt in dts:
        sol = simulate(chain_scene(), method=formula, dt=dt, t_end=1.0)
        ex = chain_exact(sol.t)
        got = np.column_stack([sol.column(c) for c in ("x_m1", "v_m1", "x_m2", "v_m2")])
        errors.append(np.abs(got - ex).max())
        # element forces obey their laws and orientation at every step
        np.testing.assert_allclose(sol.column("F_k2"), 20.0 * (got[:, 2] - got[:, 0]),
                                   atol=1e-10)
        np.testing.assert_allclose(sol.column("F_c"), 0.7 * (got[:, 1] - got[:, 3]),
                                   atol=1e-10)
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.2, (errors, slope)


@given(st.lists(st.floats(-10.0, 10.0), min_size=10, max_size=10),
       st.sampled_from(["paper", "maxwell", "chain"]), st.sampled_from([1e-3, 2e-3 / 3]))
@settings(max_examples=100)
def test_generated_step_system_equals_the_generic_one(vals, which, h):
    from lumped.solvers.implicit.step_system import generate_evaluate, make_evaluate

    scene = {"paper": paper_scene(x0=0.1), "maxwell": maxwell_scene(),
             "chain": chain_scene()}[which]
    N, E = len(scene.nodes), len(scene.elements)
    uref, x_hat, f = vals[:N], vals[N:2 * N], [vals[-1]] * N
    outs = []
    for make in ("generic", "generated"):
        qs, rq, rf = [0.0] * E, [0.0] * E, [0.0] * E
        if make == "generic":
            ev = make_evaluate(scene, h, [m / h for m in scene.masses], [0.0] * N, [1.0] * N,
                                uref, x_hat, f, qs, rq, rf)
        else:
            ev = generate_evaluate(scene, h, uref, x_hat, f)
        outs.append(ev(vals[2 * N:2 * N + N + E]))
    assert outs[0] == outs[1]


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
@pytest.mark.parametrize("which", ["paper", "maxwell", "chain"])
def test_fast_path_is_newton_exactly(formula, which, monkeypatch):
    """The step loop's shortcut takes Newton's own path: same numbers, same counters."""
    import lumped.solvers.bdf.step_loop as integ

    def scene():
        return {"paper": paper_scene(x0=0.5, forcing=paper_F2), "maxwell": maxwell_scene(),
                "chain": chain_scene(SineBurst(3.0, 7.0, 0.5))}[which]

    fast = simulate(scene(), method=formula, dt=1e-3, t_end=1.5)
    monkeypatch.setattr(integ, "fast_step", lambda *args: None)
    slow = simulate(scene(), method=formula, dt=1e-3, t_end=1.5)
    np.testing.assert_array_equal(fast.data, slow.data)
    for key in ("steps", "newton_iterations", "residual_evals", "jacobian_evals",
                "factorizations", "max_newton_iterations"):
        assert fast.stats[key] == slow.stats[key], key


@pytest.mark.parametrize("value, error", [
    (math.inf, ValueError), (-math.inf, ValueError), (math.nan, ValueError),
    (True, TypeError), ("1", TypeError), (-2.0, ValueError)])
def test_a_bad_float_argument_is_named(value, error):
    # (a float takes a shortcut past the abstract-class check: it must refuse the same)
    with pytest.raises(error, match="t_end"):
        simulate(paper_scene(), method="bdf1", dt=1e-3, t_end=value)


@pytest.mark.parametrize("value", [0.01, np.float64(0.01), 1, np.int64(1)])
def test_any_real_argument_is_taken_as_a_float(value):
    sol = simulate(paper_scene(), method="closed-bdf1", dt=1e-3, t_end=value)
    assert sol.t[-1] == pytest.approx(float(value))
