"""Tests of the exact event-driven reference (lumped.reference).

The reference is checked against independent solutions (a 4x4 matrix exponential for
``tau = 0``, the classical Coulomb free vibration, the turning-point recursion of the
viscous Bingham free vibration), against the defining relations (the ODE inside slip
intervals, stick conditions, continuity, energy balance), and against the closed-form
BDF1/BDF2 integrators, which must converge to it at their observed orders.
"""

from __future__ import annotations

import math

import mpmath  # a dependency of sympy
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from scipy.linalg import expm

from lumped.reference import (
    ExactSolution,
    ReferenceNotApplicable,
    TooManyEvents,
    exact_solution,
    reference_for_grid,
)
from lumped.scene import SineBurst, paper_F1, paper_F2, zero_forcing
from lumped.solvers.closed.closed_form import BinghamOscillator
from lumped.solvers.closed.integrate import integrate

PAPER = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)


# ----------------------------------------------------------------------------------------------
# independent solutions


def linear_oscillator_expm(m, k, c, x0, v0, A, w, t_off, t):
    """``m x'' + c x' + k x = A sin(w t) [t <= t_off]`` by the exponential of a 4x4 matrix.

    The state ``(x, v, sin(w t), cos(w t))`` obeys a linear autonomous ODE, so
    ``z(t) = expm(M t) z(0)``; after ``t_off`` the forcing rows are dropped and the
    solution restarts from ``z(t_off)``.
    """
    M_on = np.array([[0.0, 1.0, 0.0, 0.0],
                     [-k / m, -c / m, A / m, 0.0],
                     [0.0, 0.0, 0.0, w],
                     [0.0, 0.0, -w, 0.0]])
    M_off = M_on.copy()
    M_off[1, 2] = 0.0
    z0 = np.array([x0, v0, 0.0, 1.0])
    t = np.asarray(t, dtype=float)
    on = t <= t_off
    out = np.empty((t.size, 4))
    out[on] = expm(M_on[None] * t[on, None, None]) @ z0
    if np.any(~on):
        z_off = expm(M_on * t_off) @ z0
        out[~on] = expm(M_off[None] * (t[~on] - t_off)[:, None, None]) @ z_off
    return out[:, 0], out[:, 1]


def forcing_values(forcing, t):
    return np.array([forcing(float(s)) for s in t])


def check_relations(sol: ExactSolution, m, k, c, tau, forcing, *, rel=1e-6):
    """The DAE relations, checked on each interval from the solution's own evaluate()."""
    dense = sol.evaluate(np.concatenate(
        [np.linspace(iv.t_start, iv.t_end, 41) for iv in sol.intervals]))
    F_scale = tau + k * (np.max(np.abs(dense.x)) + 1e-300)
    w = steady = 0.0
    if isinstance(forcing, SineBurst):
        F_scale += abs(forcing.amplitude)
        w = abs(forcing.omega)
        if w:  # amplitude of the steady response (secular growth at undamped resonance)
            denom = max(math.hypot(k - m * w * w, c * w), 2 * m * w / (1 + w * sol.t_end))
            steady = abs(forcing.amplitude) / denom
    v_max = np.max(np.abs(dense.v)) + 1e-300
    F_scale += c * v_max  # the viscous part of F_d
    v_unit = F_scale / math.sqrt(k * m)  # a velocity made of the force scale
    for iv in sol.intervals:
        span = iv.t_end - iv.t_start
        if span <= 1e-12 * max(1.0, iv.t_end):  # no room for samples inside
            continue
        ts = iv.t_start + span * np.linspace(0.02, 0.98, 25)
        tr = sol.evaluate(ts)
        F = forcing_values(forcing, ts)
        if iv.phase == "stick":
            assert np.all(tr.v == 0.0)
            assert np.all(tr.x == iv.x_start)
            assert np.all(np.abs(tr.F_d) <= tau * (1 + 1e-12) + 1e-12 * F_scale)
            np.testing.assert_allclose(tr.F_d, F - k * tr.x, rtol=0, atol=1e-12 * F_scale)
            continue
        # slip: the direction is that of v (weakly), and F_d obeys the Bingham law
        if iv.direction != 0:
            v_scale = np.max(np.abs(tr.v)) + 1e-300
            assert np.all(iv.direction * tr.v >= -1e-9 * v_scale - 1e-13 * v_unit)
        np.testing.assert_allclose(tr.F_d, iv.direction * tau + c * tr.v,
                                   rtol=1e-12, atol=1e-12 * F_scale)
        # the ODE by central differences
        h = 1e-4 * min(span, math.sqrt(m / k), m / c if c else math.inf,
                       1.0 / w if w else math.inf)
        tp, tm = sol.evaluate(ts + h), sol.evaluate(ts - h)
        two_h = tp.t - tm.t  # the steps actually taken, after rounding of ts +- h
        acc = (tp.v - tm.v) / two_h
        vel = (tp.x - tm.x) / two_h
        # round-off of the differences: x carries the offset tau / k of the slip equilibrium
        v_scale = np.max(np.abs(tr.v)) + np.max(np.abs(vel)) + 1e-300
        # ... and the steady sinusoid, whose phase w t is rounded to ulp(w t)
        x_noise = 1e-15 * (np.max(np.abs(tr.x)) + tau / k + steady * (1 + w * iv.t_end)) / h
        v_noise = 1e-15 * (v_scale + F_scale / math.sqrt(k * m)) / h
        residual = m * acc - (F - tr.F_s - tr.F_d)
        assert np.max(np.abs(residual)) <= rel * F_scale + m * v_noise
        assert np.max(np.abs(vel - tr.v)) <= rel * v_scale + x_noise
    # continuity of x and v across every interval boundary
    for a, b in zip(sol.intervals[:-1], sol.intervals[1:], strict=True):
        assert a.t_end == b.t_start
        x_scale = max(abs(a.x_start), abs(b.x_start), 1e-300)
        left = sol.evaluate([max(a.t_start, np.nextafter(b.t_start, -np.inf))])
        assert abs(left.x[0] - b.x_start) <= 1e-9 * x_scale + 1e-12 * tau / k
        assert abs(left.v[0] - b.v_start) <= 1e-6 * v_max + 1e-13 * v_unit


# ----------------------------------------------------------------------------------------------
# tau = 0: the damped linear oscillator


@pytest.mark.parametrize("gamma,regime", [(1.0, "under"), (0.025, "critical"),
                                          (0.002, "over")])
@pytest.mark.parametrize("forcing", [zero_forcing, paper_F2, SineBurst(3.0, 7.0)])
def test_tau_zero_is_damped_linear_oscillator(gamma, regime, forcing):
    m, k = 1.0, 400.0  # critical damping: c = 1 / gamma = 2 sqrt(k m) = 40
    osc = BinghamOscillator(m=m, k=k, gamma=gamma, tau=0.0)
    t = np.linspace(0.0, 3.0, 301)
    sol = exact_solution(osc, x0=0.3, v0=-2.0, forcing=forcing, t_eval=t)
    assert [arc.regime for arc in sol._arcs] == [regime] * len(sol._arcs)
    A = getattr(forcing, "amplitude", 0.0)
    w = getattr(forcing, "omega", 0.0)
    t_off = getattr(forcing, "t_off", math.inf)
    x, v = linear_oscillator_expm(m, k, 1.0 / gamma, 0.3, -2.0, A, w, t_off, t)
    scale = np.max(np.abs(x)) + np.max(np.abs(v)) / math.sqrt(k / m)
    np.testing.assert_allclose(sol.trajectory.x, x, rtol=0, atol=1e-11 * scale)
    np.testing.assert_allclose(sol.trajectory.v, v, rtol=0,
                               atol=1e-11 * scale * math.sqrt(k / m))
    np.testing.assert_allclose(sol.trajectory.F_d, sol.trajectory.v / gamma, rtol=1e-14)
    assert all(iv.phase == "slip" for iv in sol.intervals)


@pytest.mark.parametrize("ratio", [1e-9, 1e-6, 1e-3, 1 - 1e-12, 1 + 1e-12, 1 + 1e-6, 1e3, 1e6, 1e9])
def test_tau_zero_free_motion_against_high_precision(ratio):
    """Damping ratio c / (2 sqrt(k m)) from 1e-9 to 1e9, including both sides of critical
    damping, against the two-exponential solution in 50-digit arithmetic (mpmath).
    (The 4x4 expm loses up to 8 digits at the heavy end; the closed form must not.)"""
    mp = mpmath.mp
    m, k, x0, v0 = 1.0, 100.0, 0.3, -2.0
    c = ratio * 2.0 * math.sqrt(k * m)
    t = np.linspace(0.0, 5.0, 11)
    sol = exact_solution(m=m, k=k, gamma=1.0 / c, tau=0.0, x0=x0, v0=v0, t_eval=t)
    with mpmath.workdps(50):
        a = mp.mpf(c) / (2 * m)
        root = mp.sqrt(a * a - mp.mpf(k) / m)  # complex when under-damped
        r1, r2 = -a + root, -a - root
        A1 = (v0 - r2 * x0) / (r1 - r2)
        A2 = (r1 * x0 - v0) / (r1 - r2)
        exact_x = [float(mp.re(A1 * mp.exp(r1 * float(s)) + A2 * mp.exp(r2 * float(s))))
                   for s in t]
        exact_v = [float(mp.re(r1 * A1 * mp.exp(r1 * float(s)) + r2 * A2 * mp.exp(r2 * float(s))))
                   for s in t]
    x_scale = max(abs(x0), abs(v0) / math.sqrt(k / m))
    np.testing.assert_allclose(sol.trajectory.x, exact_x, rtol=1e-13, atol=1e-15 * x_scale)
    np.testing.assert_allclose(sol.trajectory.v, exact_v, rtol=1e-13, atol=1e-15 * abs(v0))


def test_tau_zero_undamped_resonance():
    """Coulomb limit with tau = 0 driven exactly at resonance: the secular solution."""
    m, k = 2.0, 50.0
    w = math.sqrt(k / m)
    t = np.linspace(0.0, 4.0, 201)
    sol = exact_solution(m=m, k=k, tau=0.0, coulomb=True, x0=0.1, v0=0.0,
                         forcing=SineBurst(1.5, w, 3.0), t_eval=t)
    x, v = linear_oscillator_expm(m, k, 0.0, 0.1, 0.0, 1.5, w, 3.0, t)
    np.testing.assert_allclose(sol.trajectory.x, x, rtol=0, atol=1e-12 * np.max(np.abs(x)))


@pytest.mark.parametrize("gamma", [1e3, 1e8, 1e12])
@pytest.mark.parametrize("detune", [0.0, 1e-9, 1e-5, 1e-2])
def test_tau_zero_near_resonance_keeps_its_digits(gamma, detune):
    """Light damping driven at (or next to) resonance: the steady sinusoid would be up to
    1e12 times the motion; the Duhamel form keeps full accuracy."""
    m, k = 1.0, 100.0
    w = 10.0 * (1.0 + detune)
    t = np.linspace(0.0, 5.0, 101)
    sol = exact_solution(m=m, k=k, gamma=gamma, tau=0.0, x0=0.05, v0=0.3,
                         forcing=SineBurst(2.0, w, 4.0), t_eval=t)
    x, v = linear_oscillator_expm(m, k, 1.0 / gamma, 0.05, 0.3, 2.0, w, 4.0, t)
    assert np.max(np.abs(sol.trajectory.x - x)) <= 1e-12 * np.max(np.abs(x)) * 50
    assert np.max(np.abs(sol.trajectory.v - v)) <= 1e-12 * np.max(np.abs(v)) * 50


@given(
    m=st.floats(0.05, 20.0), k=st.floats(0.5, 2000.0), gamma=st.floats(1e-3, 1e3),
    x0=st.floats(-1.0, 1.0), v0=st.floats(-5.0, 5.0), A=st.floats(-20.0, 20.0),
    w=st.floats(0.0, 60.0), t_off=st.floats(0.0, 3.0),
)
def test_tau_zero_property(m, k, gamma, x0, v0, A, w, t_off):
    osc = BinghamOscillator(m=m, k=k, gamma=gamma, tau=0.0)
    t = np.linspace(0.0, 3.0, 31)
    sol = exact_solution(osc, x0=x0, v0=v0, forcing=SineBurst(A, w, t_off), t_eval=t)
    x, v = linear_oscillator_expm(m, k, 1.0 / gamma, x0, v0, A, w, t_off, t)
    w0 = math.sqrt(k / m)
    # the closed form adds the steady sinusoidal response: its amplitude sets the round-off
    steady = abs(A) / math.hypot(k - m * w * w, w / gamma) if w else 0.0
    scale = np.max(np.abs(x)) + np.max(np.abs(v)) / w0 + abs(x0) + abs(v0) / w0 + steady
    assert np.max(np.abs(sol.trajectory.x - x)) <= 1e-9 * scale
    assert np.max(np.abs(sol.trajectory.v - v)) <= 1e-9 * scale * max(w0, 1.0 / (gamma * m))


# ----------------------------------------------------------------------------------------------
# the paper's scenarios


def test_eq19_F1_never_moves():
    t = np.arange(50_001) * 1e-4
    sol = exact_solution(PAPER, x0=0.0, forcing=paper_F1, t_eval=t)
    tr = sol.trajectory
    assert np.all(tr.x == 0.0) and np.all(tr.v == 0.0) and np.all(tr.F_s == 0.0)
    assert np.array_equal(tr.F_d, forcing_values(paper_F1, t))
    assert [iv.phase for iv in sol.intervals] == ["stick", "stick"]
    assert [e.kind for e in sol.events] == ["forcing-off"]


def test_release_small_never_moves():
    tr = reference_for_grid(PAPER, x0=0.005, forcing=None, dt=1e-3, t_end=5.0)
    assert np.all(tr.x == 0.005) and np.all(tr.v == 0.0)
    np.testing.assert_array_equal(tr.F_d, -PAPER.k * 0.005)
    assert tr.stats["events"] == 0


def test_release_large_rests_inside_the_stick_band():
    sol = exact_solution(PAPER, x0=0.5, t_eval=np.linspace(0, 5, 501))
    rest = sol.rest_position()
    assert rest is not None
    assert 0.0 < abs(rest) <= PAPER.tau / PAPER.k
    kinds = [e.kind for e in sol.events]
    assert kinds[-1] == "stick" and set(kinds[:-1]) == {"reversal"}
    check_relations(sol, 1.0, 100.0, 1.0, 1.0, zero_forcing)


def test_paper_F2_relations_and_rest():
    sol = exact_solution(PAPER, x0=0.0, forcing=paper_F2, t_eval=np.linspace(0, 5, 501))
    assert sol.intervals[0].phase == "stick"
    # break-out when 10 sin(5 pi t) first reaches tau = 1
    assert sol.events[0].kind == "breakout"
    assert sol.events[0].t == pytest.approx(math.asin(0.1) / (5 * math.pi), rel=1e-14)
    assert abs(PAPER.k * sol.rest_position()) <= PAPER.tau
    check_relations(sol, 1.0, 100.0, 1.0, 1.0, paper_F2)


def test_viscous_free_vibration_turning_points():
    """Unforced underdamped slip from rest: x - x_eq flips sign and shrinks by
    exp(-a pi / w_d) every half period pi / w_d (x_eq = -s tau / k)."""
    m, k, gamma, tau = 1.0, 100.0, 2.0, 1.0
    a = 1.0 / (2 * gamma * m)
    wd = math.sqrt(k / m - a * a)
    sol = exact_solution(m=m, k=k, gamma=gamma, tau=tau, x0=0.5, t_eval=[0.0, 10.0])
    x, t, s = 0.5, 0.0, -1
    turns = [e for e in sol.events if e.kind in ("reversal", "stick")]
    for ev in turns:
        x_eq = -s * tau / k
        x = x_eq - (x - x_eq) * math.exp(-a * math.pi / wd)
        t += math.pi / wd
        assert ev.t == pytest.approx(t, rel=1e-12)
        assert ev.x == pytest.approx(x, rel=1e-12, abs=1e-14)
        s = -s
    assert turns[-1].kind == "stick" and abs(k * turns[-1].x) <= tau
    assert abs(k * x) <= tau  # the recursion agrees that it stops there


# ----------------------------------------------------------------------------------------------
# Coulomb limit


def test_coulomb_classical_free_vibration():
    """Amplitude drops by 4 tau / k per cycle; turning points every pi sqrt(m / k)."""
    m, k, tau, x0 = 2.0, 50.0, 1.0, 0.47
    sol = exact_solution(m=m, k=k, tau=tau, coulomb=True, x0=x0, t_eval=[0.0, 20.0])
    half = math.pi * math.sqrt(m / k)
    n_turns = math.ceil((abs(x0) - tau / k) / (2 * tau / k))
    turns = [e for e in sol.events if e.kind in ("reversal", "stick")]
    assert len(turns) == n_turns
    for n, ev in enumerate(turns, start=1):
        assert ev.t == pytest.approx(n * half, rel=1e-13)
        assert ev.x == pytest.approx((-1) ** n * (x0 - n * 2 * tau / k), rel=1e-12)
    assert turns[-1].kind == "stick"
    assert abs(k * sol.rest_position()) <= tau


@pytest.mark.parametrize("x0,forcing", [(0.5, None), (0.0, paper_F2), (0.02, SineBurst(3.0, 9.0)),
                                       (0.0, SineBurst(1.5, 10.0))])  # the last one resonant
def test_coulomb_limit_matches_huge_gamma(x0, forcing):
    t = np.linspace(0.0, 5.0, 2001)
    exact_c = exact_solution(m=1.0, k=100.0, tau=1.0, coulomb=True, x0=x0, forcing=forcing,
                             t_eval=t)
    exact_g = exact_solution(BinghamOscillator(1.0, 100.0, 1e12, 1.0), x0=x0, forcing=forcing,
                             t_eval=t)
    assert np.max(np.abs(exact_c.trajectory.x - exact_g.trajectory.x)) <= 1e-9
    assert [e.kind for e in exact_c.events] == [e.kind for e in exact_g.events]
    # gamma is ignored in the Coulomb limit
    other = exact_solution(BinghamOscillator(1.0, 100.0, 3.0, 1.0), coulomb=True, x0=x0,
                           forcing=forcing, t_eval=t)
    np.testing.assert_array_equal(other.trajectory.x, exact_c.trajectory.x)


# ----------------------------------------------------------------------------------------------
# properties on random problems


def log_uniform(lo_exp: float, hi_exp: float):
    return st.floats(lo_exp, hi_exp).map(lambda e: 10.0**e)


@st.composite
def problems(draw):
    """Random problems over many decades, drawn in the natural units of each problem
    (x in tau / k, v in tau / sqrt(k m), F in tau, w in w0, time in periods)."""
    m, k, tau = draw(log_uniform(-3, 3)), draw(log_uniform(-3, 6)), draw(log_uniform(-3, 3))
    w0 = math.sqrt(k / m)
    p = {
        "m": m, "k": k, "tau": tau,
        "gamma": draw(log_uniform(-5, 12)) / math.sqrt(k * m),  # damping ratio 1e-12..1e5
        "coulomb": draw(st.booleans()),
        "x0": draw(st.floats(-40.0, 40.0)) * tau / k,
        "v0": draw(st.one_of(st.just(0.0), st.floats(-30.0, 30.0))) * tau / math.sqrt(k * m),
        "A": draw(st.one_of(st.just(0.0), st.floats(-20.0, 20.0))) * tau,
        "w": draw(log_uniform(-1.5, 1.5)) * w0,
        "T": 20.0 * math.pi / w0,  # ten undamped periods
    }
    p["t_off"] = draw(st.one_of(st.just(math.inf), st.floats(0.0, 1.0).map(lambda f: f * p["T"])))
    return p


@settings(max_examples=150)
@given(problems())
def test_relations_hold_on_random_problems(p):
    forcing = SineBurst(p["A"], p["w"], p["t_off"])
    sol = exact_solution(m=p["m"], k=p["k"], gamma=p["gamma"], tau=p["tau"], x0=p["x0"],
                         v0=p["v0"], forcing=forcing, coulomb=p["coulomb"],
                         t_eval=np.linspace(0.0, p["T"], 7))
    c = 0.0 if p["coulomb"] else 1.0 / p["gamma"]
    check_relations(sol, p["m"], p["k"], c, p["tau"], forcing)
    for iv in sol.intervals:
        if iv.phase == "stick":
            assert abs(p["k"] * iv.x_start) <= p["tau"] + (abs(p["A"]) if iv.forced else 0.0)


@settings(max_examples=100)
@given(problems())
def test_closed_form_bdf2_agrees_at_small_dt_on_random_problems(p):
    """An independent cross-check of the event logic: BDF2 with 2000 steps per period
    stays within 2 % of the motion's range of the reference (a missed or spurious event
    would give an O(1) discrepancy)."""
    if p["coulomb"]:
        p["gamma"] = 1e12 / math.sqrt(p["k"] * p["m"])  # integrate() needs a finite gamma
    osc = BinghamOscillator(p["m"], p["k"], p["gamma"], p["tau"])
    forcing = SineBurst(p["A"], p["w"], p["t_off"])
    dt = p["T"] / 20_000
    ref = reference_for_grid(osc, x0=p["x0"], v0=p["v0"], forcing=forcing, dt=dt, t_end=p["T"])
    num = integrate(osc, x0=p["x0"], v0=p["v0"], forcing=forcing, dt=dt, t_end=p["T"],
                    method="bdf2")
    scale = np.ptp(ref.x) + np.ptp(num.x) + p["tau"] / p["k"]
    assert np.max(np.abs(num.x - ref.x)) <= 0.02 * scale


@given(problems())
def test_free_vibration_loses_energy_and_rests_in_band(p):
    m, k, tau = p["m"], p["k"], p["tau"]
    t = np.linspace(0.0, p["T"], 3001)
    sol = exact_solution(m=m, k=k, gamma=p["gamma"], tau=tau, x0=p["x0"], v0=p["v0"],
                         coulomb=p["coulomb"], t_eval=t)
    tr = sol.trajectory
    energy = 0.5 * m * tr.v**2 + 0.5 * k * tr.x**2
    assert np.all(np.diff(energy) <= 1e-12 * energy[0] + 1e-300)
    for iv in sol.intervals:
        if iv.phase == "stick":
            assert abs(k * iv.x_start) <= tau * (1 + 1e-12)
            assert iv is sol.intervals[-1]  # unforced: once stuck, stuck for ever


# ----------------------------------------------------------------------------------------------
# convergence of the closed-form integrators to the reference


DTS = np.array([1e-3, 5e-4, 2.5e-4, 1.25e-4])


def observed_orders(x0, forcing, method, t_end=5.0):
    max_err, end_err = [], []
    for dt in DTS:
        ref = reference_for_grid(PAPER, x0=x0, forcing=forcing, dt=dt, t_end=t_end)
        num = integrate(PAPER, x0=x0, forcing=forcing or zero_forcing, dt=dt, t_end=t_end,
                        method=method)
        assert np.array_equal(ref.t, num.t)
        max_err.append(np.max(np.abs(num.x - ref.x)))
        end_err.append(abs(num.x[-1] - ref.x[-1]))
    slope = np.polyfit(np.log(DTS), np.log(max_err), 1)[0]
    end_slope = np.polyfit(np.log(DTS), np.log(end_err), 1)[0]
    return slope, end_slope, max_err


@pytest.mark.parametrize("x0,forcing", [(0.5, None), (0.0, paper_F2)])
def test_bdf1_converges_at_order_one(x0, forcing):
    slope, _, max_err = observed_orders(x0, forcing, "bdf1")
    assert 0.9 <= slope <= 1.1
    assert max_err[-1] < 3e-3


@pytest.mark.parametrize("x0,forcing", [(0.5, None), (0.0, paper_F2)])
def test_bdf2_max_error_is_first_order_across_events(x0, forcing):
    """Across stick-slip events BDF2's max error in x is only first order (see
    docs/reference.md), but two orders of magnitude below BDF1's."""
    slope, _, max_err = observed_orders(x0, forcing, "bdf2")
    slope1, _, max_err1 = observed_orders(x0, forcing, "bdf1")
    assert 0.8 <= slope <= 1.6
    assert all(e2 < 0.05 * e1 for e1, e2 in zip(max_err1, max_err, strict=True))


def test_bdf2_second_order_before_the_first_event():
    """On the first smooth slip arc (before v first returns to 0) BDF2 is second order."""
    t_first = exact_solution(PAPER, x0=0.5, t_eval=[0.0, 1.0]).events[0].t
    errs = []
    for dt in DTS:
        t_end = dt * math.floor(0.9 * t_first / dt)
        ref = reference_for_grid(PAPER, x0=0.5, dt=dt, t_end=t_end)
        num = integrate(PAPER, x0=0.5, dt=dt, t_end=t_end, method="bdf2")
        errs.append(np.max(np.abs(num.x - ref.x)))
    slope = np.polyfit(np.log(DTS), np.log(errs), 1)[0]
    assert 1.9 <= slope <= 2.1


def test_bdf2_rest_position_second_order_unforced():
    """Unforced, the rest position does not depend on event timing: order 2."""
    _, end_slope, _ = observed_orders(0.5, None, "bdf2")
    assert 1.8 <= end_slope <= 2.2


# ----------------------------------------------------------------------------------------------
# API and bad input


def test_evaluate_matches_trajectory_and_grid():
    t = np.linspace(0.0, 5.0, 1001)
    sol = exact_solution(PAPER, x0=0.0, forcing=paper_F2, t_eval=t)
    again = sol.evaluate(t)
    np.testing.assert_array_equal(again.x, sol.trajectory.x)
    np.testing.assert_array_equal(again.F_d, sol.trajectory.F_d)
    grid = reference_for_grid(PAPER, x0=0.0, forcing=paper_F2, dt=5e-3, t_end=5.0)
    np.testing.assert_array_equal(grid.t, integrate(PAPER, x0=0.0, forcing=paper_F2, dt=5e-3,
                                                    t_end=5.0).t)
    np.testing.assert_allclose(grid.x, sol.trajectory.x, rtol=0, atol=1e-15)
    assert grid.method == "exact" and sol.trajectory.method == "exact"
    with pytest.raises(ValueError, match="beyond"):
        sol.evaluate([6.0])


def test_csv_has_the_numerical_methods_format(tmp_path):
    ref = reference_for_grid(PAPER, x0=0.5, dt=1e-2, t_end=1.0)
    num = integrate(PAPER, x0=0.5, dt=1e-2, t_end=1.0)
    a, b = ref.to_csv(tmp_path / "a.csv"), num.to_csv(tmp_path / "b.csv")
    ha, hb = a.read_text().splitlines(), b.read_text().splitlines()
    assert ha[0] == hb[0] == "t,x,v,F_s,F_d" and len(ha) == len(hb) == 102


def test_intervals_cover_the_horizon():
    sol = exact_solution(PAPER, x0=0.0, forcing=paper_F2, t_eval=[0.0, 2.0], t_end=5.0)
    assert sol.intervals[0].t_start == 0.0 and sol.intervals[-1].t_end == 5.0
    for a, b in zip(sol.intervals[:-1], sol.intervals[1:], strict=True):
        assert a.t_end == b.t_start


@pytest.mark.parametrize("forcing", [paper_F1.__call__, lambda t: 0.0, 3.0, "sine"])
def test_unsupported_forcing(forcing):
    with pytest.raises(ReferenceNotApplicable, match="covers only"):
        exact_solution(PAPER, x0=0.0, forcing=forcing, t_eval=[0.0, 1.0])
    with pytest.raises(ValueError, match="forcing"):
        reference_for_grid(PAPER, x0=0.0, forcing=forcing, dt=0.1, t_end=1.0)


@pytest.mark.parametrize("kwargs,match", [
    ({"m": -1.0, "k": 1.0, "gamma": 1.0, "tau": 1.0}, "`m` must be positive, got -1.0"),
    ({"m": 1.0, "k": 0.0, "gamma": 1.0, "tau": 1.0}, "`k` must be positive, got 0.0"),
    ({"m": 1.0, "k": 1.0, "gamma": math.nan, "tau": 1.0}, "`gamma` must be finite"),
    ({"m": 1.0, "k": 1.0, "gamma": 1.0, "tau": -2.0}, "`tau` must be non-negative, got -2.0"),
    ({"m": 1.0, "k": 1.0, "tau": 1.0}, "missing parameter.*gamma"),
])
def test_bad_parameters(kwargs, match):
    with pytest.raises(ValueError, match=match):
        exact_solution(x0=0.0, t_eval=[0.0, 1.0], **kwargs)


def test_bad_inputs():
    with pytest.raises(ValueError, match="not both"):
        exact_solution(PAPER, m=1.0, x0=0.0, t_eval=[0.0, 1.0])
    with pytest.raises(ValueError, match="`x0` must be finite, got nan"):
        exact_solution(PAPER, x0=math.nan, t_eval=[0.0, 1.0])
    with pytest.raises(ValueError, match="`v0` must be finite, got inf"):
        exact_solution(PAPER, x0=0.0, v0=math.inf, t_eval=[0.0, 1.0])
    with pytest.raises(ValueError, match="`t_eval` must be non-decreasing"):
        exact_solution(PAPER, x0=0.0, t_eval=[0.0, 2.0, 1.0])
    with pytest.raises(ValueError, match="`t_eval` must be non-negative, got -1.0"):
        exact_solution(PAPER, x0=0.0, t_eval=[-1.0, 1.0])
    with pytest.raises(ValueError, match="`t_eval` must be a non-empty"):
        exact_solution(PAPER, x0=0.0, t_eval=[])
    with pytest.raises(ValueError, match="`dt` must be positive, got 0.0"):
        reference_for_grid(PAPER, x0=0.0, dt=0.0, t_end=1.0)
    with pytest.raises(TypeError, match="`osc` must be a BinghamOscillator"):
        exact_solution((1.0, 100.0, 1.0, 1.0), x0=0.0, t_eval=[0.0])
    with pytest.raises(TypeError, match="`coulomb`"):
        exact_solution(PAPER, x0=0.0, t_eval=[0.0], coulomb="yes")


def test_runaway_events_stop_with_a_clear_error():
    # Coulomb free vibration from far outside the band: ~1e6 turning points.
    with pytest.raises(TooManyEvents, match="max_events = 50"):
        exact_solution(m=1.0, k=1e6, tau=1.0, coulomb=True, x0=1.0, t_eval=[0.0, 5.0],
                       max_events=50)


# ----------------------------------------------------------------------------------------------
# tangencies, ties and round-off-level motion


def test_forcing_that_only_touches_the_yield_force_never_moves():
    """A sin(w t) with A = tau touches |F_d| = tau tangentially: no break-out."""
    sol = exact_solution(PAPER, x0=0.0, forcing=SineBurst(1.0, 5 * math.pi, 3.0),
                         t_eval=np.linspace(0.0, 5.0, 501))
    assert np.all(sol.trajectory.x == 0.0)
    assert [iv.phase for iv in sol.intervals] == ["stick", "stick"]


@pytest.mark.parametrize("excess", [1e-12, 1e-8, 1e-4])
def test_forcing_barely_above_the_yield_force(excess):
    """Break-out by a hair: short slips near each extremum, motion of the order of the
    excess (below round-off for 1e-12), and the relations hold."""
    F = SineBurst(1.0 + excess, 5 * math.pi, 3.0)
    sol = exact_solution(PAPER, x0=0.0, forcing=F, t_eval=np.linspace(0.0, 5.0, 501))
    kinds = [e.kind for e in sol.events]
    assert kinds[:4] == ["breakout", "stick", "breakout", "stick"]
    assert np.max(np.abs(sol.trajectory.x)) <= 10 * excess / PAPER.k + 1e-15
    check_relations(sol, 1.0, 100.0, 1.0, 1.0, F)


@pytest.mark.parametrize("x0", [0.01, -0.01, math.nextafter(0.01, 1.0)])
def test_start_on_the_edge_of_the_stick_band(x0):
    sol = exact_solution(PAPER, x0=x0, t_eval=[0.0, 5.0])
    assert abs(PAPER.k * x0) <= PAPER.tau * (1 + 1e-15)
    assert [iv.phase for iv in sol.intervals] == ["stick"] and sol.events == []


def test_start_on_the_edge_with_the_force_pushing_out():
    """x0 = tau / k with F'(0) > 0: F - k x0 = -tau moves inwards, so stick first;
    x0 = -tau / k: F - k x0 = +tau moves outwards, so the mass slips at once."""
    F = SineBurst(2.0, 3.0)
    inward = exact_solution(PAPER, x0=0.01, forcing=F, t_eval=[0.0, 2.0])
    assert inward.intervals[0].phase == "stick" and inward.intervals[0].t_end > 0.5
    outward = exact_solution(PAPER, x0=-0.01, forcing=F, t_eval=[0.0, 2.0])
    assert outward.intervals[0].phase == "slip" and outward.intervals[0].direction == 1


@pytest.mark.parametrize("gamma,A,w", [(721.2822233877555, 3.977965183546584, 4.565470012563292),
                                       (6.312538188983729, 3.1036931960228817, 1.8567616530809823),
                                       (467.4314128035542, 3.533010202282213, 2.436624577458366)])
def test_brief_dips_of_v_between_samples_are_found(gamma, A, w):
    """Slow forcing on top of the free oscillation makes v dip through zero for a moment
    shorter than the bracketing samples (found by a random search): v must still keep its
    sign inside every slip interval, checked on a dense grid."""
    sol = exact_solution(m=1.0, k=100.0, gamma=gamma, tau=1.0, x0=0.0,
                         forcing=SineBurst(A, w), t_eval=[0.0, 5.0])
    for iv in sol.intervals:
        if iv.phase == "slip":
            tr = sol.evaluate(np.linspace(iv.t_start, iv.t_end, 4001))
            assert np.all(iv.direction * tr.v >= -1e-12 * np.max(np.abs(tr.v)))


@pytest.mark.parametrize("coulomb", [False, True])
def test_forced_stick_slip_alternation(coulomb):
    """The force breaks the dashpot loose and lets it stick again several times."""
    F = SineBurst(1.5, 10.0)  # w = sqrt(k/m): undamped resonance in the Coulomb limit
    sol = exact_solution(PAPER, x0=0.0, forcing=F, t_eval=np.linspace(0.0, 5.0, 11),
                         coulomb=coulomb)
    kinds = [e.kind for e in sol.events]
    assert kinds.count("breakout") >= 3 and kinds.count("stick") >= 2
    check_relations(sol, 1.0, 100.0, 0.0 if coulomb else 1.0, 1.0, F)
