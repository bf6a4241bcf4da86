"""Prescribed ground motion in the relative frame (issue 28): exact solutions, the three
kinds of input, the absolute outputs, the energy ledger with the support's work, and
every refused input."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.io import Table
from lumped.scene import GroundMotion, SineBurst

M, TAU = 2.0, 3.0  # a slider of mass 2 kg and yield force 3 N: m |a0| <= tau for |a0| <= 1.5


def slider(a0: float) -> Scene:
    return Scene([Mass("m", m=M)],
                 [Element("slider", get_law("coulomb").bind(tau=TAU, r=1.0), "ground", "m")],
                 ground_motion=GroundMotion(acceleration=a0))


RUNS = [("bdf2", {"dt": 1e-3}), ("radau5", {"rtol": 1e-10, "atol": 1e-12}),
        ("jit-bdf2", {"dt": 1e-3})]


@pytest.mark.parametrize(("method", "kw"), RUNS)
@pytest.mark.parametrize("a0", [1.5, -1.0, 0.4])
def test_slider_stays_stuck_while_m_a0_below_tau_with_the_force_it_carries(method, kw, a0):
    sol = simulate(slider(a0), method=method, t_end=1.0, **kw)
    assert np.all(sol.x["m"] == 0.0) and np.all(sol.v["m"] == 0.0)  # exactly
    # the balance 0 = -m a0 - F: the stuck slider carries the inertial force
    np.testing.assert_allclose(sol.F["slider"], -M * a0, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(sol.absolute.x["m"], 0.5 * a0 * sol.t ** 2, atol=1e-14)


@pytest.mark.parametrize(("method", "kw", "tol"),
                         [("bdf2", {"dt": 1e-3}, 2e-6), ("radau5", {"rtol": 1e-10}, 1e-12)])
@pytest.mark.parametrize("a0", [2.5, -4.0])
def test_slider_slides_with_the_closed_form_relative_acceleration(method, kw, tol, a0):
    sol = simulate(slider(a0), method=method, t_end=1.0, **kw)
    a_rel = -(a0 - math.copysign(TAU / M, a0))  # -(a0 + sgn(v) tau / m), sgn(v) = -sgn(a0)
    np.testing.assert_allclose(sol.x["m"], 0.5 * a_rel * sol.t ** 2, atol=tol)
    np.testing.assert_allclose(sol.v["m"][1:], a_rel * sol.t[1:], atol=tol * 10)
    np.testing.assert_allclose(sol.a["m"][2:], a_rel, rtol=1e-9)
    np.testing.assert_allclose(sol.F["slider"][2:], -math.copysign(TAU, a0), rtol=1e-12)


def oscillator(**motion) -> Scene:
    return Scene([Mass("m", m=1.0)],
                 [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "m"),
                  Element("damper", get_law("bingham").bind(gamma=0.5, tau=0.0),
                          "ground", "m")],
                 ground_motion=GroundMotion(**motion))


def steady_state(t, A, w, m=1.0, k=100.0, c=2.0):
    """m x'' + c x' + k x = -m A sin(w t): the periodic solution."""
    return (-m * A / complex(k - m * w * w, c * w) * np.exp(1j * w * t)).imag


@pytest.mark.parametrize(("method", "kw", "tol"),
                         [("bdf2", {"dt": 1e-3}, 1e-4), ("radau5", {"rtol": 1e-9}, 1e-6),
                          ("auto", {"dt": 1e-3}, 1e-4)])
def test_harmonic_base_acceleration_against_the_closed_form_steady_state(method, kw, tol):
    A, w = 3.0, 7.0
    sol = simulate(oscillator(acceleration=SineBurst(A, w)), method=method, t_end=20.0, **kw)
    last = sol.t > 20.0 - 3 * 2 * math.pi / w
    exact = steady_state(sol.t[last], A, w)
    err = np.abs(sol.x["m"][last] - exact).max() / np.abs(exact).max()
    assert err < tol, err
    if method == "auto":  # the paper's oscillator on a shaken base: the closed form runs
        assert sol.method == "closed-bdf2"


def test_a_displacement_sine_is_differentiated_exactly():
    D, w = 0.02, 7.0
    g = GroundMotion(displacement=SineBurst(D, w))
    assert g.acceleration == SineBurst(-D * w ** 2, w)  # compiled paths take it exactly
    a = simulate(oscillator(displacement=SineBurst(D, w)), method="bdf2", dt=1e-3, t_end=2.0)
    b = simulate(oscillator(acceleration=SineBurst(-D * w ** 2, w)), method="bdf2", dt=1e-3,
                 t_end=2.0)
    np.testing.assert_array_equal(a.data, b.data)
    np.testing.assert_allclose(a.ground.x, D * np.sin(w * a.t), atol=1e-15)
    np.testing.assert_allclose(a.ground.v, D * w * np.cos(w * a.t), atol=1e-15)


def test_a_table_sampling_a_sine_converges_to_the_sine_run():
    A, w = 3.0, 7.0
    ref = simulate(oscillator(acceleration=SineBurst(A, w)), method="radau5", t_end=3.0,
                   dt=0.01, rtol=1e-10)
    errors = []
    for h in (0.04, 0.02, 0.01):
        t = np.arange(0.0, 3.0 + h / 2, h)
        table = Table(t, A * np.sin(w * t), quantity="acceleration")
        sol = simulate(oscillator(acceleration=table), method="radau5", t_end=3.0, dt=0.01,
                       rtol=1e-10)
        errors.append(np.abs(sol.x["m"] - ref.x["m"]).max())
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all(rates > 1.8), (errors, rates)  # linear interpolation: O(h^2)


@pytest.mark.parametrize("quantity", ["acceleration", "velocity", "displacement"])
def test_table_motions_are_consistent_and_hit_their_points(quantity):
    rng = np.random.default_rng(28)
    t = np.cumsum(rng.uniform(0.05, 0.15, 30)) - 0.05
    t[0] = 0.0
    table = Table(t, rng.normal(size=30), quantity=quantity)
    g = GroundMotion(**{quantity: table}, v0=0.3, x0=-0.1)
    x, v, a = g.motion(t)
    np.testing.assert_allclose({"acceleration": a, "velocity": v, "displacement": x}[quantity],
                               table.values, atol=1e-12)
    fine = np.linspace(-0.5, t[-1] + 0.5, 20001)
    xf, vf, af = g.motion(fine)
    h = fine[1] - fine[0]

    def integral(y):  # cumulative trapezoid: v integrates to x, a to v
        return np.concatenate([[0.0], np.cumsum(0.5 * h * (y[1:] + y[:-1]))])

    np.testing.assert_allclose(integral(vf), xf - xf[0], atol=1e-5)
    np.testing.assert_allclose(integral(af), vf - vf[0], atol=2e-2)  # a may jump
    for tk in fine[::997]:
        assert g.acceleration_at(float(tk)) == pytest.approx(
            float(g.motion(np.array([tk]))[2][0]), abs=1e-12)
    assert g.breakpoints(0.2, 1.0) == [tk for tk in t.tolist() if 0.2 < tk < 1.0]


def test_absolute_outputs_and_the_energy_ledger_with_the_support():
    w = 7.0
    t = np.arange(0.0, 4.0001, 0.005)
    table = Table(t, 2.0 * np.sin(w * t) * np.exp(-0.3 * t), quantity="acceleration")
    scene = Scene([Mass("base", m=2.0), Mass("top", m=1.0)],
                  [Element("iso", get_law("linear_spring").bind(k=40.0), "ground", "base"),
                   Element("slider", get_law("bingham").bind(gamma=0.1, tau=1.0),
                           "ground", "base"),
                   Element("storey", get_law("linear_spring").bind(k=300.0), "base", "top")],
                  forces={"top": SineBurst(0.5, 3.0)}, ground_motion=GroundMotion(
                      acceleration=table))
    sol = simulate(scene, method="bdf2", dt=5e-4, t_end=4.0)
    g = sol.ground
    for node in ("base", "top"):
        np.testing.assert_array_equal(sol.absolute.x[node], sol.x[node] + g.x)
        np.testing.assert_array_equal(sol.absolute.v[node], sol.v[node] + g.v)
        np.testing.assert_array_equal(sol.absolute.a[node], sol.a[node] + g.a)
    for frame in ("relative", "absolute"):
        ledger = sol.energy(frame)
        assert ledger.support and ledger.frame == frame
        assert np.abs(ledger.residual).max() < 1e-4 * ledger.scale(), frame
        without = ledger.residual + sum(ledger.support.values())
        assert np.abs(without).max() > 0.1 * ledger.scale()  # the support's work matters
    names = set(sol.energy().to_dict())
    assert {"support_base", "support_top", "work_top"} <= names


def test_a_friction_isolator_stuck_against_the_ground_motion_runs_through():
    scene = Scene([Mass("m", m=1.0)],
                  [Element("slider", get_law("coulomb").bind(tau=2.0, r=1.0), "ground", "m"),
                   Element("spring", get_law("linear_spring").bind(k=20.0), "ground", "m")],
                  ground_motion=GroundMotion(acceleration=SineBurst(3.0, 4.0)))
    # radau5 on an output grid, so that the stick intervals hold samples to check
    for method, kw in (("bdf2", {"dt": 1e-3}), ("radau5", {"dt": 1e-3})):
        sol = simulate(scene, method=method, t_end=4.0, **kw)
        assert sol.success
        sticks = sol.stick_intervals("slider")
        assert len(sticks) >= 3
        # inside each stick interval (two samples in: a BDF2 derivative reads two samples
        # back) the lock's force holds the inertial force: 0 = -m a_g - F_slider - F_spring
        stuck = np.zeros(len(sol.t), bool)
        for a, b in sticks:
            stuck |= (sol.t >= a + 2.5e-3) & (sol.t <= b)
        rows = sol.data[stuck]
        assert len(rows) >= 3
        cols = sol.columns
        v, Fs, Fk = (rows[:, cols.index(c)] for c in ("v_m", "F_slider", "F_spring"))
        a_g = scene.ground_motion.motion(rows[:, 0])[2]
        assert np.abs(v).max() < 1e-12
        np.testing.assert_allclose(Fs, -a_g - Fk, atol=1e-9)
        assert np.abs(Fs).max() <= 2.0 + 1e-12


@pytest.mark.parametrize(("kwargs", "exc", "words"), [
    ({}, ValueError, "exactly one of"),
    ({"acceleration": 1.0, "velocity": 1.0}, ValueError, "exactly one of"),
    ({"velocity": SineBurst(1.0, 2.0, t_off=1.0)}, ValueError, "t_off"),
    ({"acceleration": "x*t"}, ValueError, "unknown symbol 'x'"),
    ({"acceleration": "__import__('os')"}, ValueError, "acceleration"),
    ({"acceleration": "sin(t**3)"}, ValueError, "no closed-form integral"),
    ({"acceleration": lambda t: t}, TypeError, "must be an expression of t"),
    ({"acceleration": Table([0, 1], [0, 1], quantity="force")}, ValueError, "a force is not"),
    ({"acceleration": Table([0, 1], [0, 1], quantity="velocity")}, ValueError,
     "pass it as `velocity=`"),
    ({"displacement": Table([0, 1], [0, 1], quantity="acceleration")}, ValueError,
     "table of acceleration"),
    ({"acceleration": 1.0, "v0": math.nan}, ValueError, "v0"),
])
def test_every_bad_ground_motion_gets_its_error(kwargs, exc, words):
    with pytest.raises(exc, match=words.replace("(", r"\(").replace("[", r"\[")):
        GroundMotion(**kwargs)


def test_a_non_force_table_is_refused_as_a_force_and_a_bad_ground_motion_type():
    spring = Element("s", get_law("linear_spring").bind(k=1.0), "ground", "m")
    acc = Table([0, 1], [0, 1], quantity="acceleration")
    with pytest.raises(ValueError, match=r"`forces\['m'\]` is a table of acceleration"):
        Scene([Mass("m", m=1.0)], [spring], forces={"m": acc})
    with pytest.raises(TypeError, match="`ground_motion` must be a GroundMotion"):
        Scene([Mass("m", m=1.0)], [spring], ground_motion=acc)
    ok = Scene([Mass("m", m=1.0)], [spring],
               forces={"m": Table([0, 1], [0, 1], quantity="force")})
    assert ok.forcing[0](0.5) == 0.5
