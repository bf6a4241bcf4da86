"""The adaptive method ``radau5``: tolerance, order, events, exact sticking, bad input.

Accuracy is measured against exact solutions (:mod:`lumped.reference`, a linear
oscillator, a step load) or an independent high-accuracy scipy run, never against
another run of ``radau5``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import log_uniform
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from lumped import Element, Junction, Mass, Scene, SolverError, Status, get_law, simulate
from lumped.reference import exact_solution
from lumped.scenarios import get_scenario, scenario_scene
from lumped.solvers.radau.stage import StageSystem
from lumped.solvers.radau.tableau import A


def _reference(name: str, t: np.ndarray):
    sc = get_scenario(name)
    return exact_solution(sc.osc, x0=sc.x0, v0=sc.v0, forcing=sc.forcing, t_eval=t)


def _error(name: str, rtol: float, t_end: float = 5.0) -> tuple[float, int]:
    sol = simulate(scenario_scene(name), method="radau5", t_end=t_end, rtol=rtol,
                   atol=rtol * 1e-3)
    t = np.linspace(0.0, t_end, 2001)
    ex = _reference(name, t)
    got = sol.sol(t)
    return float(np.max(np.abs(got[:, 1] - ex.trajectory.x))), sol.stats["steps"]


@pytest.mark.parametrize("name", ["release-0.5", "forcing-F2"])
def test_error_falls_in_proportion_to_the_tolerance(name):
    e5, n5 = _error(name, 1e-5)
    e8, n8 = _error(name, 1e-8)
    assert e5 <= 1e-5 * 0.5 and e8 <= 1e-8 * 0.5
    # 1000 times the tolerance: between 100 and 10^4 times the error
    assert 1e2 <= e5 / e8 <= 1e4
    # order across the stick-slip events: a first- or second-order method would need
    # 1000 or 30 times the steps; fifth-order steps under a fourth-order estimate, 5.6
    slope = math.log(e5 / e8) / math.log(n8 / n5)
    assert slope >= 3.5, slope


@pytest.mark.parametrize("name", ["release-0.5", "forcing-F2"])
def test_event_times_match_the_exact_reference(name):
    sol = simulate(scenario_scene(name), method="radau5", t_end=5.0, rtol=1e-10,
                   atol=1e-13)
    ex = _reference(name, np.array([0.0, 5.0]))
    exact = [ev.t for ev in ex.events if ev.kind != "forcing-off"]
    ours = [ev for ev in sol.events if ev.kind == "switch"]
    assert len(ours) == len(exact)
    for ev, te in zip(ours, exact, strict=True):
        assert ev.element == "dashpot"
        assert abs(ev.t - te) <= 1e-10, (ev, te)
    # the time event of the forcing (t_off = 1) where there is one
    times = [ev.t for ev in sol.events if ev.kind == "time"]
    assert times == ([1.0] if name == "forcing-F2" else [])


def test_eq19_is_reproduced_exactly():
    scene = scenario_scene("forcing-F1")
    sol = simulate(scene, method="radau5", t_end=2.0, rtol=1e-6)
    assert sol.ok and not [ev for ev in sol.events if ev.kind == "switch"]
    assert np.all(sol.column("x_mass") == 0.0) and np.all(sol.column("v_mass") == 0.0)
    assert np.all(sol.column("F_spring") == 0.0)
    F1 = scene.forcing[0]
    assert np.array_equal(sol.column("F_dashpot"), [F1(t) for t in sol.t])
    dense = sol.sol(np.linspace(0.0, 2.0, 777))
    assert np.all(dense[:, 1] == 0.0) and np.all(dense[:, 2] == 0.0)


def test_coulomb_friction_against_the_exact_reference():
    """The projection-form Coulomb law (its slip branches leave q free): events and
    motion as the exact Coulomb reference."""
    from lumped.scene import SineBurst

    forcing = SineBurst(amplitude=10.0, omega=5 * math.pi, t_off=1.0)
    scene = Scene([Mass("mass", m=1.0)],
                  [Element("s", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
                   Element("d", get_law("coulomb").bind(tau=1.0, r=10.0), "ground", "mass")],
                  forces={"mass": forcing})
    sol = simulate(scene, method="radau5", t_end=3.0, rtol=1e-8, atol=1e-11)
    t = np.linspace(0.0, 3.0, 601)
    ex = exact_solution(m=1.0, k=100.0, tau=1.0, coulomb=True, x0=0.0, forcing=forcing,
                        t_eval=t)
    assert np.max(np.abs(sol.sol(t)[:, 1] - ex.trajectory.x)) <= 1e-8
    exact = [ev.t for ev in ex.events if ev.kind != "forcing-off"]
    ours = [ev.t for ev in sol.events if ev.kind == "switch"]
    assert len(ours) == len(exact)
    assert max(abs(a - b) for a, b in zip(ours, exact, strict=True)) <= 1e-8


def test_a_release_below_the_yield_force_never_moves():
    sol = simulate(scenario_scene("release-0.005"), method="radau5", t_end=5.0, rtol=1e-10)
    assert sol.ok and not sol.events
    assert np.all(sol.column("x_mass") == 0.005) and np.all(sol.column("v_mass") == 0.0)
    assert np.all(sol.sol(np.linspace(0.0, 5.0, 101))[:, 2] == 0.0)


def _bingham_scene(m, k, gamma, tau, x0, amplitude, omega):
    from lumped.scene import SineBurst

    return Scene(
        [Mass("mass", m=m, x0=x0)],
        [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=gamma, tau=tau), "ground", "mass")],
        forces={"mass": SineBurst(amplitude=amplitude, omega=omega, t_off=1.0)},
    ), SineBurst(amplitude=amplitude, omega=omega, t_off=1.0)


@settings(max_examples=20)
@given(m=log_uniform(0.3, 3.0), k=log_uniform(10.0, 300.0), gamma=log_uniform(0.1, 10.0),
       tau=log_uniform(0.3, 3.0), x0=st.floats(-0.05, 0.05),
       amplitude=st.floats(0.0, 10.0), omega=st.floats(1.0, 20.0))
def test_exact_sticking_against_the_reference(m, k, gamma, tau, x0, amplitude, omega):
    from lumped.solvers.closed.closed_form import BinghamOscillator

    scene, forcing = _bingham_scene(m, k, gamma, tau, x0, amplitude, omega)
    rtol = 1e-8
    t_end = 2.0
    sol = simulate(scene, method="radau5", t_end=t_end, rtol=rtol, atol=1e-11)
    t = np.linspace(0.0, t_end, 401)
    ex = exact_solution(BinghamOscillator(m=m, k=k, gamma=gamma, tau=tau), x0=x0,
                        forcing=forcing, t_eval=t)
    got = sol.sol(t)
    scale = max(abs(x0), amplitude / k, tau / k, 1e-3)
    assert np.max(np.abs(got[:, 1] - ex.trajectory.x)) <= 1e3 * rtol * scale
    # inside every stuck interval of the reference, the velocity is exactly 0
    for iv in ex.intervals:
        if iv.phase != "stick":
            continue
        lo, hi = iv.t_start, min(iv.t_end, t_end)
        margin = 1e-6 * (1.0 + hi)
        if hi - lo <= 2 * margin:
            continue
        inner = np.linspace(lo + margin, hi - margin, 23)
        assert np.all(sol.sol(inner)[:, 2] == 0.0)


def test_order_five_on_a_linear_oscillator():
    """Fixed steps of the Radau IIA stage system (spring + newtonian dashpot): slope 5."""
    m, k, c = 1.0, 100.0, 0.5
    system = StageSystem([m], [-1, -1], [0, 0], [True, False])
    spring = get_law("linear_spring").bind(k=k).kernel
    dashpot = get_law("newtonian").bind(c=c).kernel
    x0, T = 0.1, 1.0
    wd = math.sqrt(k / m - (c / (2 * m)) ** 2)
    exact = x0 * math.exp(-c * T / (2 * m)) * (math.cos(wd * T)
                                                + c / (2 * m * wd) * math.sin(wd * T))
    errs, hs = [], []
    for n_steps in (20, 40, 80):
        h = T / n_steps
        x, v, F = [x0], [0.0], [k * x0, 0.0]
        zero = [[0.0]] * 3
        for _ in range(n_steps):
            U = (v + F) * 3
            U, _, _ = system.solve(U, h, x, v, zero, (spring, dashpot), [1e-8] * 9, tol=1e-4)
            x = [x[0] + h * sum(A[2][j] * U[3 * j] for j in range(3))]
            v, F = [U[6]], U[7:9]
        errs.append(abs(x[0] - exact))
        hs.append(h)
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert 4.6 <= slope <= 5.6, (slope, errs)


def _spring_reference(bound, m, x0, v0, t):
    """x(t) of a mass on a smooth implicit spring, by DOP853 with F(q) from the law."""
    def force(q):
        lo, hi = -1.0, 1.0
        while bound.residual(q, lo) * bound.residual(q, hi) > 0:
            lo, hi = 2 * lo, 2 * hi
        return brentq(lambda F: bound.residual(q, F), lo, hi, xtol=1e-15, rtol=1e-15)

    out = solve_ivp(lambda _t, y: [y[1], -force(y[0]) / m], (0.0, t[-1]), [x0, v0],
                    method="DOP853", rtol=1e-13, atol=1e-15, t_eval=t)
    return out.y[0]


@pytest.mark.parametrize("law, params, x0", [
    ("implicit_spring", {"k": 100.0, "L0": 0.01, "F0": 2.0}, 0.1),
    ("s_shaped", {"q0": 1.0, "F0": 1.0}, 0.8),  # stays on the middle branch (|q| < 2)
])
def test_fully_implicit_laws(law, params, x0):
    bound = get_law(law).bind(**params)
    scene = Scene([Mass("mass", m=1.0, x0=x0)], [Element("s", bound, "ground", "mass")])
    sol = simulate(scene, method="radau5", t_end=3.0, rtol=1e-9, atol=1e-12)
    t = np.linspace(0.0, 3.0, 301)
    ref = _spring_reference(bound, 1.0, x0, 0.0, t)
    assert np.max(np.abs(sol.sol(t)[:, 1] - ref)) <= 1e-7


def test_a_slip_branch_without_continuation_ends_in_an_event():
    """Herschel-Bulkley with n = 2: its slip branch q = gamma (F - tau)^2 cannot carry the
    rate through zero (Newton fails on every step past it, with no guard crossing), so the
    step shrinks to its floor, where the full laws choose the next branch (a reversal).
    BDF2 converges to the result."""
    hb = get_law("herschel_bulkley").bind(gamma=1.0, tau=0.5, n=2.0)
    scene = Scene([Mass("m", m=1.0, x0=0.3, v0=0.5)],
                  [Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m"),
                   Element("d", hb, "ground", "m")])
    sol = simulate(scene, method="radau5", t_end=3.0, rtol=1e-8, atol=1e-11)
    assert [(ev.from_branch, ev.to_branch) for ev in sol.events] == [(0, 1), (1, 0)]
    diffs = []
    for dt in (1e-3, 2.5e-4):
        ref = simulate(scene, method="bdf2", dt=dt, t_end=3.0)
        diffs.append(np.max(np.abs(sol.sol(ref.t)[:, 1] - ref.column("x_m"))))
    assert diffs[1] <= 0.5 * diffs[0] and diffs[1] <= 1e-4, diffs


def test_a_fold_of_the_law_stops_the_run():
    """``s_shaped`` pushed past its turning point (q = 2 q0): no solution continues the
    branch, so radau5 stops there (BRANCH_LOST), as the fixed-step methods do."""
    from lumped import BranchError

    scene = Scene([Mass("mass", m=0.01, x0=-6.0)],
                  [Element("s", get_law("s_shaped").bind(q0=1.0, F0=1.0), "ground", "mass"),
                   Element("damper", get_law("newtonian").bind(c=0.05), "ground", "mass")],
                  forces={"mass": "-9 + 2*t"})
    sol = simulate(scene, method="radau5", t_end=8.0, throw=False)
    assert sol.status is Status.BRANCH_LOST and "fold" in sol.message
    # at the elongation fold q = (5/3)^(3/2) q0, where BDF2 stops too (its Newton fails)
    assert abs(sol.column("x_mass")[-1] - (5.0 / 3.0) ** 1.5) <= 1e-4
    bdf = simulate(scene, method="bdf2", dt=1e-3, t_end=8.0, throw=False)
    assert not bdf.ok and abs(sol.t[-1] - bdf.t[-1]) <= 2e-3
    with pytest.raises(BranchError, match="'s'"):
        simulate(scene, method="radau5", t_end=8.0)


def test_a_forcing_with_a_jump_is_a_time_event():
    k, m, P, t0 = 50.0, 2.0, 3.0, 0.37
    scene = Scene([Mass("mass", m=m)],
                  [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass")],
                  forces={"mass": f"Piecewise((0, t < {t0!r}), ({P!r}, True))"})
    sol = simulate(scene, method="radau5", t_end=2.0, rtol=1e-10, atol=1e-13)
    assert [(ev.t, ev.kind) for ev in sol.events] == [(t0, "time")]
    t = np.linspace(0.0, 2.0, 1001)
    w = math.sqrt(k / m)
    exact = np.where(t < t0, 0.0, P / k * (1.0 - np.cos(w * (t - t0))))
    assert np.max(np.abs(sol.sol(t)[:, 1] - exact)) <= 1e-9


def test_event_accumulation_ends_with_a_clear_status():
    scene = scenario_scene("forcing-F2")
    sol = simulate(scene, method="radau5", t_end=5.0, throw=False, zeno_events=3,
                   zeno_window=1.0, bridge=False)
    assert sol.status is Status.TOO_MANY_EVENTS
    assert "accumulation" in sol.message and "dashpot" in sol.message
    assert sol.t[-1] < 1.0
    with pytest.raises(SolverError, match="max_events = 2"):
        simulate(scene, method="radau5", t_end=5.0, max_events=2)
    with pytest.raises(SolverError, match="max_events = 2"):  # never bridged
        simulate(scene, method="radau5", t_end=5.0, max_events=2, bridge=True)


def test_an_accumulation_is_bridged_by_backward_euler():
    # the same "accumulation" (3 events within 1 s, by the keywords): by default backward
    # Euler bridges it from the last accepted state and radau5 goes on to t_end, each
    # bridge named in the message; the motion stays the exact one to the bridges'
    # first-order error (3 bridges of steps sqrt(rtol) h_max: 2.4e-11, 3.5e-12 without)
    scene = scenario_scene("forcing-F2")
    sol = simulate(scene, method="radau5", t_end=5.0, zeno_events=3, zeno_window=1.0,
                   rtol=1e-8, atol=1e-10)
    assert sol.ok and sol.t[-1] == 5.0
    assert sol.stats["bridges"] >= 1 and sol.stats["bridged_steps"] >= 32
    assert sol.message.count("over: radau5 stopped at") == sol.stats["bridges"]
    assert "accumulation" in sol.message
    ref = simulate(scene, method="exact", dt=1e-3, t_end=5.0)
    t = np.linspace(0.0, 5.0, 501)
    assert np.abs(sol.sol(t)[:, 1] - ref.sol(t)[:, 1]).max() <= 1e-9
    with pytest.raises(TypeError, match="`bridge` must be True or False, got 1"):
        simulate(scene, method="radau5", t_end=5.0, bridge=1)


def test_dense_output_on_a_grid_and_auto():
    scene = scenario_scene("release-0.5")
    grid = simulate(scene, method="radau5", t_end=1.0, dt=0.01, rtol=1e-7)
    assert len(grid.t) == 101 and grid.t[-1] == pytest.approx(1.0)
    free = simulate(scene, method="radau5", t_end=1.0, rtol=1e-7)
    np.testing.assert_allclose(grid.data, free.sol(grid.t), rtol=0, atol=1e-15)
    maxwell = Scene([Mass("mass", m=1.0, x0=0.1), Junction("j")],
                    [Element("spring", get_law("linear_spring").bind(k=10.0), "ground", "mass"),
                     Element("s2", get_law("linear_spring").bind(k=50.0), "j", "mass"),
                     Element("d", get_law("bingham").bind(gamma=1.0, tau=0.2), "ground", "j")])
    assert simulate(maxwell, t_end=0.5, rtol=1e-6).method == "radau5"


@pytest.mark.parametrize("kw, match", [
    ({"rtol": -1e-6}, "`rtol` must be positive"),
    ({"rtol": 0.0}, "`rtol` must be positive"),
    ({"atol": float("nan")}, "`atol` must be finite"),
    ({"max_events": 0}, "`max_events` must be a positive integer"),
    ({"restitution": 1.5}, "`restitution` must be a number in \\[0, 1\\]"),
    ({"zeno_window": -1.0}, "`zeno_window` must be a positive number"),
])
def test_bad_tolerances_are_refused(kw, match):
    with pytest.raises(ValueError, match=match):
        simulate(scenario_scene("release-0.5"), method="radau5", t_end=1.0, **kw)


def _has_impacts() -> bool:
    import importlib.util

    return importlib.util.find_spec("lumped.solvers.nonsmooth.impacts") is not None


def test_an_impact_is_applied_or_stops_cleanly():
    """Issue 11's impact scene: x = sin t until the string goes taut at t = pi/6, a perfectly
    inelastic impact, then x = 0.5 cos(t - pi/6). With the impact model
    (``lumped.solvers.nonsmooth.impacts``) radau5 applies the impulse; without it, it stops
    there with a message, never a silently wrong answer."""
    string = get_law("string_spring").bind(k=1.0, L=0.5)
    scene = Scene([Mass("mass", m=1.0, v0=1.0)], [Element("s", string, "ground", "mass")])
    sol = simulate(scene, method="radau5", t_end=3.0, rtol=1e-8, throw=False)
    if not _has_impacts():
        assert sol.status is Status.INCONSISTENT and "impact" in sol.message
        assert "'s'" in sol.message and abs(sol.t[-1] - math.pi / 6) <= 1e-9
        return
    assert sol.ok
    (impact,) = [ev for ev in sol.events if ev.kind == "impact"]
    assert impact.element == "s" and abs(impact.t - math.pi / 6) <= 1e-9
    assert impact.impulse == pytest.approx(math.sqrt(3) / 2, rel=1e-8)
    assert impact.energy_lost == pytest.approx(3 / 8, rel=1e-8)
    t = np.linspace(0.0, 3.0, 601)
    exact = np.where(t < math.pi / 6, np.sin(t), 0.5 * np.cos(t - math.pi / 6))
    assert np.max(np.abs(sol.sol(t)[:, 1] - exact)) <= 1e-6


def _linear_network():
    """Two masses and a Maxwell arm (spring into a junction, newtonian dashpot to ground):
    a linear DAE whose exact solution is a matrix exponential."""
    m1, m2, k1, k12, c12, k3, c3 = 1.0, 0.5, 40.0, 25.0, 0.3, 60.0, 2.0
    lin = get_law("linear_spring")
    newt = get_law("newtonian")
    scene = Scene(
        [Mass("m1", m=m1, x0=0.1), Mass("m2", m=m2, v0=-0.5), Junction("j", x0=0.02)],
        [Element("k1", lin.bind(k=k1), "ground", "m1"),
         Element("k12", lin.bind(k=k12), "m1", "m2"),
         Element("c12", newt.bind(c=c12), "m1", "m2"),
         Element("k3", lin.bind(k=k3), "j", "m2"),
         Element("c3", newt.bind(c=c3), "ground", "j")])
    # y = (x1, v1, x2, v2, xj)
    M = np.array([
        [0, 1, 0, 0, 0],
        [(-k1 - k12) / m1, -c12 / m1, k12 / m1, c12 / m1, 0],
        [0, 0, 0, 1, 0],
        [k12 / m2, c12 / m2, (-k12 - k3) / m2, -c12 / m2, k3 / m2],
        [0, 0, k3 / c3, 0, -k3 / c3]])
    return scene, M, np.array([0.1, 0.0, 0.0, -0.5, 0.02])


def test_a_linear_network_with_a_junction_against_its_exact_solution():
    from scipy.linalg import expm

    scene, M, y0 = _linear_network()
    t = np.linspace(0.0, 2.0, 101)
    exact = np.array([expm(M * tt) @ y0 for tt in t])
    errs = []
    for rtol in (1e-6, 1e-9):
        got = simulate(scene, method="radau5", t_end=2.0, rtol=rtol, atol=1e-3 * rtol).sol(t)
        cols = [1, 2, 3, 4, 5]  # x_m1, v_m1, x_m2, v_m2, x_j
        errs.append(np.max(np.abs(got[:, cols] - exact)))
    assert errs[0] <= 1e-5 and errs[1] <= 1e-8
    assert 1e2 <= errs[0] / errs[1] <= 1e4


def test_a_two_mass_bingham_chain_agrees_with_bdf2():
    """Stick-slip in a chain, against the fixed-step BDF2 to BDF2's own accuracy."""
    lin, bing = get_law("linear_spring"), get_law("bingham")
    scene = Scene(
        [Mass("a", m=1.0, x0=0.3), Mass("b", m=0.7, x0=-0.1)],
        [Element("s1", lin.bind(k=50.0), "ground", "a"),
         Element("d1", bing.bind(gamma=0.5, tau=1.5), "ground", "a"),
         Element("s2", lin.bind(k=30.0), "a", "b"),
         Element("d2", bing.bind(gamma=2.0, tau=0.8), "a", "b")])
    ours = simulate(scene, method="radau5", t_end=1.5, rtol=1e-9, atol=1e-12)
    assert ours.ok and len([ev for ev in ours.events if ev.kind == "switch"]) >= 4
    diffs = []
    for dt in (4e-4, 1e-4):
        ref = simulate(scene, method="bdf2", dt=dt, t_end=1.5)
        got = ours.sol(ref.t)
        cols = [ref.columns.index(c) for c in ("x_a", "x_b")]
        diffs.append(np.max(np.abs(got[:, cols] - ref.data[:, cols])))
    # BDF2 converges to radau5's answer as dt shrinks (order 1 to 2 across the events)
    assert diffs[1] <= 3e-5 and diffs[1] <= 0.4 * diffs[0], diffs


def test_the_compiled_stage_newton_gives_the_same_run():
    """``compiled=True``: the compiled loop (:mod:`lumped.solvers.eventdriven.loop_jit`), and the
    stage Newton of :mod:`lumped.solvers.radau.stage_jit` (numba) in the Python loop's own
    solves, in place of the pure-Python ones, bit for bit."""
    scene = scenario_scene("forcing-F2")
    ours = simulate(scene, method="radau5", t_end=1.5, rtol=1e-7, compiled=False)
    compiled = simulate(scene, method="radau5", t_end=1.5, rtol=1e-7, compiled=True)
    assert compiled.stats.pop("loop") == "compiled"
    assert ours.stats.pop("loop") == "python: compiled=False"
    assert np.array_equal(compiled.data, ours.data) and compiled.stats == ours.stats
    assert [(ev.t, ev.element) for ev in compiled.events] == [
        (ev.t, ev.element) for ev in ours.events]


def test_radau5_refuses_an_unbounded_slope_without_inverse_form_and_auto_runs_bdf2():
    # a steep branch (dq/dF infinite at its boundary) that radau5 cannot solve for F in
    # closed form (two powers of F): the stage Newton of a step starting on the boundary
    # would fail at every step size, so radau5 refuses the scene (issue 11)
    from lumped.laws import ElementLaw

    law = ElementLaw("two_powers", "dashpot",
                     "q - Piecewise((sqrt(F - tau) + (F - tau)**2, F > tau),"
                     " (-sqrt(-F - tau) - (-F - tau)**2, F < -tau), (0, True))", ["tau"])
    scene = Scene([Mass("m", m=1.0, x0=0.5)],
                  [Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m"),
                   Element("d", law.bind(tau=1.0), "ground", "m")])
    with pytest.raises(ValueError, match=r"does not take element 'd'.*two_powers.*inverse"):
        simulate(scene, method="radau5", t_end=1.0)
    with pytest.raises(ValueError, match=r"`dt` is required .*`auto` runs it .*'radau5'"):
        simulate(scene, t_end=1.0)  # auto says why it needs a step size here
    sol = simulate(scene, dt=1e-3, t_end=1.0)  # auto
    assert sol.method == "bdf2" and sol.ok
    with pytest.raises(ValueError, match=r"`auto` runs the fixed-step method 'bdf2'.*rtol"):
        simulate(scene, dt=1e-3, rtol=1e-6, t_end=1.0)
    # Herschel-Bulkley n < 1 is steep too, but solved in its inverse form: radau5 takes it
    for n in (0.5, 2.0):
        hb = Scene(scene.nodes, [scene.elements[0], Element(
            "d", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=n), "ground", "m")])
        assert simulate(hb, rtol=1e-6, t_end=1.0).method == "radau5"
