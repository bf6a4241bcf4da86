"""The closed-form BDF1 (Algorithm 1) and BDF2 steps: exact solutions, properties, limits."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import log_uniform
from hypothesis import assume, given
from hypothesis import strategies as st

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst, zero_forcing
from lumped.solvers.closed.closed_form import (
    BinghamOscillator,
    bdf1_step,
    bdf2_step,
    correct,
    initial_dashpot_force,
    initial_velocity,
    steps_for,
)
from lumped.solvers.closed.integrate import integrate

EPS = np.finfo(float).eps


def states(bound: float) -> st.SearchStrategy[float]:
    """Initial states and forces in [-bound, bound]. Subnormal inputs are left out: their
    products underflow to zero, where no sign survives to check (16) against."""
    return st.floats(-bound, bound, allow_subnormal=False)


oscillators = st.builds(
    BinghamOscillator,
    m=log_uniform(1e-3, 1e3),
    k=log_uniform(1e-2, 1e6),
    gamma=log_uniform(1e-3, 1e12),
    tau=st.one_of(st.just(0.0), log_uniform(1e-3, 1e2)),
)
forcings = st.one_of(
    st.just(zero_forcing),
    st.builds(SineBurst, amplitude=states(20), omega=log_uniform(0.1, 100.0),
              t_off=st.floats(0.0, 1.0)),
)


def algorithm1_literal(osc, dt, v_n, Fs_n, F_next):
    """Algorithm 1 transcribed line by line from the paper (loses digits as gamma grows)."""
    m, k, g, tau = osc.m, osc.k, osc.gamma, osc.tau
    Ft = m / dt * v_n + F_next - Fs_n
    if abs(Ft) <= tau:
        v, Fd = 0.0, Ft
    else:
        a = 1 + dt**2 * k / m
        Fd = (g * a * math.copysign(1, Ft) * tau + dt / m * Ft) / (g * a + dt / m)
        v = g * (Fd - math.copysign(1, Fd) * tau)
    Fs = Fs_n + dt * k * v
    return Fs / k, v, Fs, Fd


def run(osc, x0, v0, forcing, dt, n, method):
    return integrate(osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=n, method=method)


# --- exact solutions of Section 3 ------------------------------------------------------

@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_eq19_forcing_F1_is_stuck_exactly(method):
    from lumped.scenarios import PAPER_OSCILLATOR
    from lumped.scene import paper_F1

    traj = integrate(PAPER_OSCILLATOR, x0=0.0, forcing=paper_F1, dt=1e-4, t_end=5.0,
                     method=method)
    assert np.all(traj.x == 0.0) and np.all(traj.v == 0.0) and np.all(traj.F_s == 0.0)
    assert np.array_equal(traj.F_d, np.array([paper_F1(t) for t in traj.t]))


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_release_0005_never_moves(method):
    from lumped.scenarios import run_scenario

    traj = run_scenario("release-0.005", method=f"closed-{method}")
    assert np.all(traj.x == 0.005) and np.all(traj.v == 0.0)
    assert np.all(traj.F_d == -traj.F_s)  # the dashpot holds the spring


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_release_05_rests_with_a_stretched_spring(method):
    from lumped.scenarios import PAPER_OSCILLATOR as osc
    from lumped.scenarios import run_scenario

    traj = run_scenario("release-0.5", method=f"closed-{method}")
    moving = np.flatnonzero(traj.v != 0.0)
    last = moving[-1] + 1  # first step of the final stick
    assert last < len(traj) - 1000, "the mass must come to rest well before t_end"
    assert np.all(traj.v[last:] == 0.0)
    rest = traj.x[-1]
    assert 0.0 < abs(rest) <= osc.tau / osc.k
    assert np.all(np.abs(traj.F_d[last:]) <= osc.tau)
    drift = np.abs(np.diff(traj.x[last:]))
    if method == "bdf1":
        assert np.all(drift == 0.0)
    else:  # BDF2 on x' = 0 lets x_{n+1} - x_n = (x_n - x_{n-1}) / 3 die out geometrically
        assert np.all(drift[1:] <= drift[:-1] / 3.0 * (1 + 1e-9) + 4 * EPS * abs(rest))
        assert drift[20:].max() <= 1e-9 * abs(rest)


# --- properties of every step (hypothesis) ---------------------------------------------

@given(osc=oscillators, x0=states(1), v0=states(10), forcing=forcings,
       dt=log_uniform(1e-5, 1e-1), method=st.sampled_from(["bdf1", "bdf2"]))
def test_sign_relation_law_and_balance_hold_at_every_step(osc, x0, v0, forcing, dt, method):
    traj = run(osc, x0, v0, forcing, dt, 40, method)
    x, v, Fs, Fd, Ft = traj.x, traj.v, traj.F_s, traj.F_d, traj.predictor
    m, k, g, tau = osc.m, osc.k, osc.gamma, osc.tau
    # (16): sgn(F~) = sgn(F_d) at every step
    assert np.array_equal(np.sign(Ft[1:]), np.sign(Fd[1:]))
    # stuck => |F_d| <= tau ;  (6) written in force units, free of gamma-sized round-off
    stuck = v[1:] == 0.0
    assert np.all(np.abs(Fd[1:][stuck]) <= tau)
    slip = ~stuck
    assert np.array_equal(np.sign(v[1:][slip]), np.sign(Fd[1:][slip]))
    lhs = np.abs(Fd[1:][slip]) - tau
    assert np.all(lhs >= 0.0)  # |F_d| may round to tau when the excess is below an ulp
    assert np.allclose(lhs, np.abs(v[1:][slip]) / g, rtol=64 * EPS,
                       atol=8 * EPS * max(tau, 1.0) + 0.0)
    # the discrete balance (13a-b), or its BDF2 twin, to round-off
    F = np.array([forcing(t) for t in traj.t])
    if method == "bdf1":
        dv, dx, h = v[1:] - v[:-1], x[1:] - x[:-1], dt
    else:
        dv = np.concatenate([[v[1] - v[0]], 1.5 * v[2:] - 2 * v[1:-1] + 0.5 * v[:-2]])
        dx = np.concatenate([[x[1] - x[0]], 1.5 * x[2:] - 2 * x[1:-1] + 0.5 * x[:-2]])
        h = dt
    # the terms each row is made of, with the BDF2 history (v_{n-1}, F_s^{n-1}) where it enters
    hist_v = np.concatenate([[0.0], np.abs(v[:-2])])
    hist_F = np.concatenate([[0.0], np.abs(Fs[:-2])])
    scale_a = m * (np.abs(v[1:]) + np.abs(v[:-1]) + hist_v) + h * (
        np.abs(F[1:]) + np.abs(Fs[1:]) + np.abs(Fs[:-1]) + hist_F + np.abs(Fd[1:]) + tau)
    assert np.all(np.abs(m * dv - h * (F[1:] - Fs[1:] - Fd[1:])) <= 64 * EPS * scale_a)
    scale_b = np.abs(x[1:]) + np.abs(x[:-1]) + h * np.abs(v[1:])
    assert np.all(np.abs(dx - h * v[1:]) <= 16 * EPS * scale_b)
    assert np.allclose(Fs, k * x, rtol=0, atol=0)


@given(osc=oscillators, x0=states(1), v0=states(10), dt=log_uniform(1e-5, 1e-1))
def test_bdf1_energy_never_increases_without_forcing(osc, x0, v0, dt):
    traj = run(osc, x0, v0, zero_forcing, dt, 60, "bdf1")
    E = 0.5 * osc.m * traj.v**2 + traj.F_s**2 / (2 * osc.k)
    assert np.all(np.diff(E) <= 16 * EPS * E[:-1])


@given(osc=oscillators, x_n=states(1), v_n=states(10), F=states(50),
       dt=log_uniform(1e-5, 1e-1))
def test_bdf1_step_equals_the_literal_algorithm1(osc, x_n, v_n, F, dt):
    assume(osc.gamma <= 1e3)  # the literal line 9 cancels digits for larger gamma
    x, v, Fd, Ft = bdf1_step(osc.m, osc.k, 1 / osc.gamma, osc.tau, dt, x_n, v_n, F)
    assume(abs(abs(Ft) - osc.tau) > 1e-6 * max(1.0, osc.tau))
    xl, vl, Fsl, Fdl = algorithm1_literal(osc, dt, v_n, osc.k * x_n, F)
    scale_v = max(abs(v), abs(v_n), 1e-300)
    # the literal line 9 carries an absolute error of about gamma * eps * |F_d|
    assert abs(v - vl) <= 1e-12 * scale_v + 4 * osc.gamma * EPS * max(abs(Fd), osc.tau)
    assert abs(Fd - Fdl) <= 1e-12 * max(abs(Fd), osc.tau, abs(Ft))
    assert abs(x - xl) <= 1e-12 * max(abs(x), abs(x_n)) + dt * abs(v - vl) + 4 * EPS


# --- the Coulomb limit (Remark 2.1) ----------------------------------------------------

def coulomb_step(m, k, tau, dt, x_n, v_n, F):
    """The analytic gamma -> infinity limit of one BDF1 step."""
    Ft = m / dt * v_n + F - k * x_n
    if abs(Ft) <= tau:
        return x_n, 0.0, Ft
    v = math.copysign((dt / m) * (abs(Ft) - tau) / (1 + dt * dt * k / m), Ft)
    return x_n + dt * v, v, math.copysign(tau, Ft)


@given(m=log_uniform(1e-3, 1e3), k=log_uniform(1e-2, 1e6), tau=log_uniform(1e-3, 1e2),
       x_n=states(1), v_n=states(10), F=states(50),
       dt=log_uniform(1e-5, 1e-1))
def test_gamma_1e12_matches_the_analytic_coulomb_step(m, k, tau, x_n, v_n, F, dt):
    x, v, Fd, _ = bdf1_step(m, k, 1e-12, tau, dt, x_n, v_n, F)
    xc, vc, Fdc = coulomb_step(m, k, tau, dt, x_n, v_n, F)
    assert abs(v - vc) <= 1e-12 * abs(vc) * (1 + dt / m) + 2 * EPS * abs(vc)
    assert abs(Fd - Fdc) <= 1e-12 * abs(Fdc) + 1e-12 * abs(vc)
    assert abs(x - xc) <= 4 * EPS * max(abs(x), abs(xc), abs(x_n)) + dt * abs(v - vc)


def test_coulomb_limit_does_not_lose_digits_to_cancellation():
    # v ~ 1e-13 while F_d ~ 1: forming F_d - sgn(F_d) tau would leave no correct digit.
    v, Fd = correct(1.0 + 1e-13, 1.0, 1e-4, 1.0, 1e-12)
    assert v == pytest.approx(1e-4 * 1e-13 * (1.0 + 2.2e-16 / 1e-13), rel=1e-2)  # excess rounding
    exact_excess = (1.0 + 1e-13) - 1.0  # what the predictor carries, computed once
    assert v == 1e-4 * exact_excess / (1.0 + 1e-4 * 1e-12)
    assert Fd == 1.0 + v * 1e-12


def test_trajectory_at_gamma_1e12_agrees_with_coulomb_limit_relative_1e12():
    osc = BinghamOscillator(m=1.0, k=100.0, gamma=1e12, tau=1.0)
    traj = integrate(osc, x0=0.5, dt=1e-3, t_end=2.0)
    x, v = 0.5, 0.0
    x_scale_to_v = 0.5 * math.sqrt(100.0)  # |v| <= omega x(0)
    for i in range(1, len(traj)):
        x, v, Fd = coulomb_step(1.0, 100.0, 1.0, 1e-3, x, v, 0.0)
        # relative to each variable's scale over the run (x and v cross zero)
        assert abs(traj.x[i] - x) <= 1e-12 * 0.5
        assert abs(traj.v[i] - v) <= 1e-12 * x_scale_to_v
        # the models differ by |v| / gamma in the force; nothing more may be lost
        assert abs(traj.F_d[i] - Fd) <= 1.001e-12 * abs(v) + 4 * EPS * abs(Fd)


# --- orders on the linear damped oscillator (tau = 0) ----------------------------------

def damped_exact(m, k, c, x0, v0, t):
    """Exact solution of m x'' + c x' + k x = 0 (under-damped)."""
    w0 = math.sqrt(k / m)
    zeta = c / (2 * math.sqrt(k * m))
    wd = w0 * math.sqrt(1 - zeta**2)
    e = np.exp(-zeta * w0 * t)
    x = e * (x0 * np.cos(wd * t) + (v0 + zeta * w0 * x0) / wd * np.sin(wd * t))
    v = e * (v0 * np.cos(wd * t) - (w0 * x0 + zeta * v0) / math.sqrt(1 - zeta**2)
             * np.sin(wd * t))
    return x, v


@pytest.mark.parametrize("method,order", [("bdf1", 1.0), ("bdf2", 2.0)])
def test_observed_order_on_the_linear_damped_oscillator(method, order):
    osc = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=0.0)  # F_d = v / gamma
    dts = [2e-3, 1e-3, 5e-4, 2.5e-4, 1.25e-4]
    errors = []
    for dt in dts:
        traj = integrate(osc, x0=0.5, v0=0.3, dt=dt, t_end=1.0, method=method)
        x, v = damped_exact(1.0, 100.0, 1.0, 0.5, 0.3, traj.t)
        errors.append(max(np.abs(traj.x - x).max(), np.abs(traj.v - v).max() / 10.0))
    slope = np.polyfit(np.log(dts), np.log(errors), 1)[0]
    assert abs(slope - order) < 0.1, (slope, errors)


# --- consistent initial state and bad input --------------------------------------------

def test_initial_dashpot_force_is_consistent():
    osc = BinghamOscillator(m=1.0, k=100.0, gamma=2.0, tau=1.0)
    assert initial_dashpot_force(osc, 0.005, 0.0, 0.0) == -0.5      # holds the spring
    assert initial_dashpot_force(osc, 0.5, 0.0, 0.0) == -1.0        # at yield, starts slipping
    assert initial_dashpot_force(osc, 0.0, -0.4, 0.0) == -1.0 - 0.2  # law (6) with v = -0.4


@pytest.mark.parametrize("name,value", [
    ("m", 0.0), ("m", -1.0), ("k", 0.0), ("gamma", -2.0), ("gamma", math.inf),
    ("k", math.nan), ("tau", -1.0), ("tau", math.inf),
])
def test_bad_parameters_are_refused_with_their_name(name, value):
    params = {"m": 1.0, "k": 1.0, "gamma": 1.0, "tau": 1.0, name: value}
    with pytest.raises(ValueError, match=name):
        BinghamOscillator(**params)


@pytest.mark.parametrize("kwargs,match", [
    ({"dt": 0.0}, "dt"), ({"dt": -1e-3}, "dt"), ({"dt": math.nan}, "dt"),
    ({"x0": math.inf}, "x0"), ({"v0": math.nan}, "v0"), ({"t_end": -1.0}, "t_end"),
    ({"method": "rk4"}, "method"), ({"t_end": None}, "exactly one"),
])
def test_bad_run_arguments_are_refused(kwargs, match):
    args = {"x0": 0.1, "dt": 1e-3, "t_end": 1.0, **kwargs}
    with pytest.raises(ValueError, match=match):
        integrate(BinghamOscillator(1.0, 1.0, 1.0, 1.0), **args)


def test_wrong_types_are_refused():
    with pytest.raises(TypeError, match="m"):
        BinghamOscillator(m="1", k=1.0, gamma=1.0, tau=1.0)
    with pytest.raises(TypeError, match="forcing"):
        integrate(BinghamOscillator(1.0, 1.0, 1.0, 1.0), x0=0.0, dt=0.1, t_end=1.0, forcing=3.0)


def test_a_forcing_that_returns_nan_is_reported_with_its_time():
    with pytest.raises(ValueError, match=r"forcing.*t = 0\.2"):
        integrate(BinghamOscillator(1.0, 1.0, 1.0, 1.0), x0=0.0, dt=0.1, t_end=1.0,
                  forcing=lambda t: math.nan if t > 0.15 else 0.0)


def test_overflow_never_leaks_into_a_trajectory():
    osc = BinghamOscillator(m=1e-300, k=1e300, gamma=1e300, tau=0.0)
    with pytest.raises(FloatingPointError, match="non-finite"):
        integrate(osc, x0=1e300, v0=1e300, dt=1.0, n_steps=3)


def test_steps_for_rounds_to_the_grid():
    assert steps_for(1e-4, 5.0) == 50_000
    assert steps_for(0.3, 1.0) == 4
    assert steps_for(0.1, 0.3) == 3


@given(osc=oscillators, x0=states(1), v0=states(10), forcing=forcings,
       dt=log_uniform(1e-5, 1.0))
def test_bdf2_first_step_is_bdf1_and_steps_are_pure(osc, x0, v0, forcing, dt):
    a = run(osc, x0, v0, forcing, dt, 1, "bdf1")
    b = run(osc, x0, v0, forcing, dt, 1, "bdf2")
    assert np.array_equal(a.as_array(), b.as_array())
    # the step functions are pure: the same inputs give the same outputs
    args = (osc.m, osc.k, 1 / osc.gamma, osc.tau, dt, x0, v0, x0, v0, forcing(dt))
    assert bdf2_step(*args) == bdf2_step(*args)


def test_initial_dashpot_force_of_a_rate_the_limit_step_reverses_is_at_rest():
    # v0 = 1e-113 against a pull past tau: the slip that follows, -tau (relation (16));
    # against one within tau: the stick that follows, the pull held; with h = 0 (t = 0
    # itself) and for a rate the step keeps, the law (6) at v0
    osc = BinghamOscillator(1.0, 10.0, 2.0, 1.0)
    assert initial_dashpot_force(osc, 0.0, 1e-113, -3.0, h=1e-23) == -1.0
    assert initial_dashpot_force(osc, 0.0, 1e-113, -0.5, h=1e-23) == -0.5
    assert initial_dashpot_force(osc, 0.0, 1e-113, -3.0) == 1.0
    assert initial_dashpot_force(osc, 0.0, 1e-3, -3.0, h=1e-23) == 1.0 + 5e-4
    # the mass starts at rest then (row 0 holds law (6)); one the step keeps moves
    assert initial_velocity(osc, 0.0, 1e-113, -3.0, h=1e-23) == 0.0
    assert initial_velocity(osc, 0.0, 1e-113, -3.0) == 1e-113
    assert initial_velocity(osc, 0.0, 1e-3, -3.0, h=1e-23) == 1e-3
    sol = simulate(Scene([Mass("m", 1.0, x0=0.0, v0=1e-113)],
                         [Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m"),
                          Element("d", get_law("bingham").bind(gamma=2.0, tau=1.0),
                                  "ground", "m")], {"m": -3.0}),
                   method="closed-bdf1", dt=1e-3, t_end=1e-2)
    assert sol.F["d"][0] == pytest.approx(-1.0, rel=1e-15)
    assert sol.v["m"][0] == 0.0
