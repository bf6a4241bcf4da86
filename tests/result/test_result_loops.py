"""Hysteresis loops and cycles (lumped.post.loops) against closed forms: a linear
oscillator's dashpot (pi c omega X^2 per cycle), a Kelvin-Voigt pair, a Coulomb slider
(4 tau X per cycle, a rectangle) and a Bingham dashpot."""

from __future__ import annotations

import dataclasses
import math
import sys

import numpy as np
import pytest

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.post import cycles, hysteresis
from lumped.scene import SineBurst

M, K, F0 = 1.0, 100.0, 5.0


def _oscillator(extra: list[Element], omega: float) -> Scene:
    """A mass on a spring to ground, with ``extra`` elements, pushed by F0 sin(omega t)."""
    spring = Element("spring", get_law("linear_spring").bind(k=K), "ground", "mass")
    return Scene([Mass("mass", m=M)], [spring, *extra], forces={"mass": SineBurst(F0, omega)})


def _viscous(c: float, omega: float, *, reversed_dashpot: bool = False) -> Scene:
    ends = ("mass", "ground") if reversed_dashpot else ("ground", "mass")
    return _oscillator([Element("dashpot", get_law("newtonian").bind(c=c), *ends)], omega)


# -- a linear viscous dashpot: E_d = pi c omega X^2 ------------------------------------------
C, OMEGA = 2.0, 8.0                     # zeta = 0.1, omega / omega_n = 0.8
X = F0 / math.hypot(K - M * OMEGA**2, C * OMEGA)   # the steady amplitude
T = 2 * math.pi / OMEGA


@pytest.fixture(scope="module")
def viscous_runs():
    # the transient decays like exp(-t): 20 cycles (15.7 s) leave about 1e-7 of it
    return {dt: simulate(_viscous(C, OMEGA), method="bdf2", dt=dt, t_end=20 * T)
            for dt in (2e-3, 1e-3)}


def test_viscous_energy_per_steady_cycle_is_pi_c_omega_x2(viscous_runs):
    exact = math.pi * C * OMEGA * X**2
    errors = []
    for sol in viscous_runs.values():
        report = cycles(sol, "dashpot", omega=OMEGA, rtol=1e-3, stiffness=K)
        assert len(report.cycles) == 20 and report.period == pytest.approx(T)
        assert report.steady_from is not None and report.steady_from <= 12
        assert [c.steady for c in report.cycles] == [c.index >= report.steady_from
                                                     for c in report.cycles]
        last = report.cycles[-1]
        errors.append(abs(last.energy / exact - 1))
        assert abs(report.energy / exact - 1) < 1e-3
        assert report.amplitude == pytest.approx(X, rel=1e-3)
        assert last.offset == pytest.approx(0.0, abs=1e-4 * X)
        assert last.force_amplitude == pytest.approx(C * OMEGA * X, rel=1e-3)
        # against the structure's stiffness: the classical zeta_eq = c omega / (2 k)
        assert report.k_eff == K
        assert report.zeta_eq == pytest.approx(C * OMEGA / (2 * K), rel=1e-3)
        assert last.zeta_eq == pytest.approx(C * OMEGA / (2 * last.k_eff), rel=1e-3)
    assert errors[0] < 1e-3 and errors[1] < errors[0] / 2.5, errors   # BDF2: order 2


def test_a_lone_dashpot_against_its_own_secant_stiffness_is_one_half(viscous_runs):
    report = cycles(viscous_runs[1e-3], "dashpot", omega=OMEGA, rtol=1e-3)
    assert report.k_eff == pytest.approx(C * OMEGA, rel=1e-3)       # F_0 / u_0 = c omega
    assert report.zeta_eq == pytest.approx(0.5, rel=1e-3)


def test_kelvin_voigt_pair_loop(viscous_runs):
    """Spring and dashpot in parallel: k_eff = sqrt(k^2 + (c omega)^2), the same energy."""
    sol = viscous_runs[1e-3]
    report = cycles(sol, ["spring", "dashpot"], omega=OMEGA, rtol=1e-3)
    k_eff = math.hypot(K, C * OMEGA)
    assert report.element == "spring+dashpot"
    assert report.k_eff == pytest.approx(k_eff, rel=1e-3)
    assert report.energy == pytest.approx(math.pi * C * OMEGA * X**2, rel=1e-3)
    assert report.zeta_eq == pytest.approx(C * OMEGA / (2 * k_eff), rel=1e-3)
    # an element drawn the other way round counts with -1: the same loop
    flipped = simulate(_viscous(C, OMEGA, reversed_dashpot=True), method="bdf2", dt=1e-3,
                       t_end=20 * T)
    again = cycles(flipped, ["spring", "dashpot"], omega=OMEGA, rtol=1e-3)
    assert again.energy == pytest.approx(report.energy, rel=1e-9)
    assert again.k_eff == pytest.approx(report.k_eff, rel=1e-9)


def test_the_steady_loop_is_the_ellipse_and_the_line(viscous_runs):
    sol = viscous_runs[1e-3]
    loop = hysteresis(sol, "dashpot", t0=18 * T, t1=19 * T)
    assert loop.t[0] == 18 * T and loop.t[-1] == 19 * T
    assert len(loop.t) == len(sol.t[(sol.t > 18 * T) & (sol.t < 19 * T)]) + 2
    ellipse = (loop.elongation / X) ** 2 + (loop.force / (C * OMEGA * X)) ** 2
    assert np.abs(ellipse - 1).max() < 2e-3
    np.testing.assert_allclose(loop.force, C * loop.rate, rtol=0, atol=1e-3 * C * OMEGA * X)
    assert loop.work() == pytest.approx(math.pi * C * OMEGA * X**2, rel=1e-3)
    fine = hysteresis(sol, "dashpot", t0=18 * T, t1=19 * T, points=2001)
    assert len(fine.t) == 2001 and fine.work() == pytest.approx(loop.work(), rel=1e-4)
    whole = hysteresis(sol, "spring")
    np.testing.assert_array_equal(whole.t, sol.t)
    np.testing.assert_array_equal(whole.elongation, sol.x["mass"])
    np.testing.assert_array_equal(whole.force, sol.F["spring"])


# -- friction: a rectangle of area 4 tau X -----------------------------------------------------
TAU, OMEGA_F = 1.0, 5.0
T_F = 2 * math.pi / OMEGA_F


def _friction(law: str, dt: float) -> Scene:
    params = ({"tau": TAU, "r": M / dt + dt * K} if law == "coulomb"
              else {"tau": TAU, "gamma": 100.0})
    return _oscillator([Element("dashpot", get_law("newtonian").bind(c=4.0), "ground", "mass"),
                        Element("slider", get_law(law).bind(**params), "ground", "mass")],
                       OMEGA_F)


def test_coulomb_slider_dissipates_4_tau_x_per_cycle():
    sol = simulate(_friction("coulomb", 1e-3), method="bdf2", dt=1e-3, t_end=8 * T_F)
    report = cycles(sol, "slider", period=T_F, rtol=1e-3)
    assert report.steady_from is not None and report.steady_from <= 4
    for c in report.steady:
        assert c.energy == pytest.approx(4 * TAU * c.amplitude, rel=1e-3)
        assert c.force_amplitude == pytest.approx(TAU, rel=1e-9)     # |F| <= tau
    assert report.zeta_eq == pytest.approx(2 / math.pi, rel=1e-3)    # a rigid-plastic loop
    # the isolator (spring + slider): bilinear, k_eff = k + tau / X
    isolator = cycles(sol, ["spring", "slider"], period=T_F, rtol=1e-3)
    u0 = isolator.amplitude
    assert isolator.k_eff == pytest.approx(K + TAU / u0, rel=1e-3)
    assert isolator.zeta_eq == pytest.approx(2 * TAU / (math.pi * (K * u0 + TAU)), rel=1e-3)
    sticks = sol.stick_intervals("slider")
    assert sticks and max(b - a for a, b in sticks[1:]) < 0.02 * T_F   # short sticking


def test_bingham_dashpot_dissipates_a_little_more_than_4_tau_x():
    sol = simulate(_friction("bingham", 1e-3), method="bdf2", dt=1e-3, t_end=8 * T_F)
    report = cycles(sol, "slider", omega=OMEGA_F, rtol=1e-3)
    X_s = report.amplitude
    rigid = 4 * TAU * X_s
    viscous = math.pi * OMEGA_F * X_s**2 / 100.0      # int qdot^2 / gamma dt, qdot harmonic
    assert rigid < report.energy < rigid + 1.5 * viscous


def test_a_run_that_ends_in_the_transient_has_no_steady_cycle():
    sol = simulate(_viscous(C, OMEGA), method="bdf2", dt=2e-3, t_end=4 * T)
    report = cycles(sol, "dashpot", omega=OMEGA, rtol=1e-3)
    assert report.steady_from is None and report.steady == ()
    assert report.energy is None and report.zeta_eq is None
    assert "no steady cycle" in repr(report)
    assert set(report.to_dict()) >= {"index", "energy", "amplitude", "zeta_eq", "steady"}
    assert len(report.to_dict()["energy"]) == 4


# -- arguments --------------------------------------------------------------------------------
@pytest.fixture(scope="module")
def short_run():
    return simulate(_viscous(C, OMEGA), method="bdf2", dt=2e-3, t_end=2.0)


@pytest.mark.parametrize(("kwargs", "match"), [
    ({}, "exactly one of `period` and `omega`"),
    ({"period": 1.0, "omega": 1.0}, "exactly one of `period` and `omega`"),
    ({"period": -1.0}, "`period` must be positive"),
    ({"omega": 0.0}, "`omega` must be positive"),
    ({"period": 3.0}, "no complete cycle"),
    ({"period": 0.5, "t_start": 2.0}, "`t_start` must lie in"),
    ({"period": 0.5, "rtol": 0.0}, "`rtol` must be positive"),
    ({"period": 0.5, "stiffness": -1.0}, "`stiffness` must be positive"),
    ({"period": 0.5, "points_per_cycle": 3}, "`points_per_cycle` must be at least 8"),
])
def test_cycles_arguments_are_checked(short_run, kwargs, match):
    with pytest.raises(ValueError, match=match):
        cycles(short_run, "dashpot", **kwargs)


def test_loop_arguments_are_checked(short_run):
    with pytest.raises(ValueError, match="no element 'damper' in the scene"):
        hysteresis(short_run, "damper")
    with pytest.raises(TypeError, match="`element` must be an element name"):
        hysteresis(short_run, 3)
    with pytest.raises(ValueError, match="the window .* must be a non-empty part"):
        hysteresis(short_run, "dashpot", t0=1.0, t1=0.5)
    with pytest.raises(ValueError, match="the window"):
        hysteresis(short_run, "dashpot", t1=5.0)
    with pytest.raises(ValueError, match="loops need the scene"):
        hysteresis(dataclasses.replace(short_run, scene=None), "dashpot")
    two = Scene([Mass("a", m=1.0), Mass("b", m=1.0)],
                [Element("s1", get_law("linear_spring").bind(k=1.0), "ground", "a"),
                 Element("s2", get_law("linear_spring").bind(k=1.0), "a", "b")])
    sol = simulate(two, method="bdf2", dt=0.1, t_end=1.0)
    with pytest.raises(ValueError, match="does not join the same two nodes"):
        hysteresis(sol, ["s1", "s2"])


def test_loop_plots_against_elongation_and_rate(short_run):
    matplotlib = pytest.importorskip("matplotlib")
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    loop = hysteresis(short_run, "dashpot")
    ax = loop.plot()
    assert ax.get_xlabel().startswith("elongation q = x_b - x_a")
    assert "tension" in ax.get_ylabel()
    _, other = plt.subplots()
    assert loop.plot(other, against="rate", color="k") is other
    assert other.get_xlabel().startswith("rate") and len(other.lines) == 1
    with pytest.raises(ValueError, match="`against` must be 'elongation' or 'rate'"):
        loop.plot(against="time")
    plt.close("all")


def test_loop_plot_without_matplotlib_says_which_extra(short_run, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)
    monkeypatch.setitem(sys.modules, "matplotlib.pyplot", None)
    with pytest.raises(ImportError, match=r"HysteresisLoop.plot\(\).*plot.*extra"):
        hysteresis(short_run, "dashpot").plot()
