"""``radau5`` on scenes with named supports (issue 28): exact solutions (a Coulomb slider
on a uniformly accelerating support, a shaken oscillator), agreement with ``bdf2`` as its
step halves (the belt example, a dashpot stuck to a shaking support, a string to the wall
driven by a support: switches, held intervals, an impact), a table-driven support
against the sine it samples, and ``auto``'s choice."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from scene.test_supports import VB, D, W, belt, belt_exact, belt_phases, shaken, shaken_exact

from lumped import Element, Mass, Scene, get_law, load_scene, simulate
from lumped.io import Table
from lumped.scene import GroundMotion, SineBurst

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"

# ---------------------------------------------------------------- a slider, exactly

TAU_S, XS0, VS0 = 1.0, 0.3, -0.2  # the slider's yield force; the support at t = 0


def slider(m: float, a0: float) -> Scene:
    """A mass ``m`` on a Coulomb contact (``tau = TAU_S``) to a support moving with the
    constant acceleration ``a0`` from ``x_s(0) = XS0``, ``v_s(0) = VS0``; the mass starts
    with the support's velocity. Contact from the mass (``a``) to the support (``b``):
    ``q = v_s - v``, ``m v' = F``."""
    return Scene([Mass("m", m, x0=0.1, v0=VS0)],
                 [Element("contact", get_law("coulomb").bind(tau=TAU_S, r=10.0), "m", "sled")],
                 supports={"sled": GroundMotion(acceleration=a0, v0=VS0, x0=XS0)})


def slider_exact(m: float, a0: float, t: np.ndarray):
    """``(x, v, F)``: stuck (``x = x0 + v_s(0) t + a0 t^2 / 2``, ``F = m a0``) while
    ``m |a0| <= tau``, else slipping from ``t = 0`` on with ``F = sign(a0) tau`` (the
    relative rate ``q = (a0 - F / m) t`` keeps the sign of ``a0``)."""
    acc = a0 if m * abs(a0) <= TAU_S else math.copysign(TAU_S, a0) / m
    return 0.1 + VS0 * t + 0.5 * acc * t * t, VS0 + acc * t, np.full(t.shape, m * acc)


@pytest.mark.parametrize(("m", "a0"), [(2.0, 0.3), (2.0, -0.45), (1.0, 1.0), (1.0, 1.7),
                                       (0.5, -3.0)])
def test_a_slider_on_an_accelerating_support_sticks_or_slips_exactly(m, a0):
    sol = simulate(slider(m, a0), method="radau5", rtol=1e-10, atol=1e-13, dt=0.01,
                   t_end=2.0)
    assert sol.ok, sol.message
    x, v, F = slider_exact(m, a0, sol.t)
    np.testing.assert_allclose(sol.x["m"], x, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(sol.v["m"], v, rtol=1e-10, atol=1e-13)
    np.testing.assert_allclose(sol.F["contact"], F, rtol=1e-10, atol=1e-13)
    rel = sol.supports["sled"].v - sol.v["m"]  # the contact's rate q
    if m * abs(a0) < TAU_S:  # the mass moves with the support: its rate 0 to round-off
        assert np.max(np.abs(rel)) <= 1e-12 and sol.stats["events"] == 0
    elif m * abs(a0) == TAU_S:  # at the yield force: stuck, or slipping at rate 0 (the
        assert np.max(np.abs(rel)) <= 1e-12  # same point of the law; one switch to it)
    else:
        np.testing.assert_allclose(rel, (a0 - F / m) * sol.t, rtol=1e-10, atol=1e-13)


@pytest.mark.parametrize("method", ["bdf1", "bdf2", "radau5"])
@pytest.mark.parametrize(("m", "a0"), [(2.0, 0.3), (2.0, -0.45), (1.0, 1.7)])
def test_a_slider_starts_with_the_force_of_its_supports_acceleration(method, m, a0):
    # the initial state's limit system reads the support's acceleration (F(0) was 0)
    sol = simulate(slider(m, a0), method=method, dt=0.01, t_end=0.05)
    assert sol.F["contact"][0] == pytest.approx(slider_exact(m, a0, np.zeros(1))[2][0],
                                                rel=1e-12)


# ---------------------------------------------------------------- a shaken oscillator


@pytest.mark.parametrize("end", ["a", "b"])
def test_a_shaken_oscillator_is_its_closed_form(end):
    # measured 1.2e-12 (x), 1.2e-11 (v) at rtol 1e-8; forgetting the offsets at the stage
    # times gives an error of the size of the motion
    sol = simulate(shaken(end), method="radau5", rtol=1e-8, atol=1e-11, t_end=3.0)
    assert sol.ok, sol.message
    assert sol.stats["loop"].startswith("python: moving supports")
    x, v = shaken_exact(sol.t)
    assert np.max(np.abs(sol.x["m"] - x)) < 1e-10
    assert np.max(np.abs(sol.v["m"] - v)) < 1e-9
    # the dense output between the steps too
    t = np.linspace(0.0, 3.0, 1001)
    dense = simulate(shaken(end), method="radau5", rtol=1e-8, atol=1e-11, dt=3e-3, t_end=3.0)
    x, _ = shaken_exact(dense.t)
    assert np.max(np.abs(dense.x["m"] - x)) < 1e-9 and len(dense.t) == len(t)


def test_the_belt_switches_at_the_exact_times():
    sol = simulate(belt(), method="radau5", rtol=1e-10, atol=1e-13, t_end=1.0)
    assert sol.ok, sol.message
    t1, t2 = belt_phases()
    assert [ev.kind for ev in sol.events] == ["switch", "switch"]
    assert abs(sol.events[0].t - t1) < 1e-10 and abs(sol.events[1].t - t2) < 1e-10
    x, _ = belt_exact(sol.t)
    assert np.max(np.abs(sol.x["m"] - x)) < 1e-12  # measured 1.3e-15
    stick = (sol.t > t1) & (sol.t < t2)
    assert np.max(np.abs(sol.v["m"][stick] - VB)) < 1e-14


# ---------------------------------------------------------------- radau5 against bdf2


def _held() -> Scene:
    """A mass on a wall spring with a Bingham dashpot to a support shaking with the
    velocity ``0.3 sin 4t``: stuck to the support (held: its rate ``v_s - v = 0``, the
    mass moving with it) from the start to 0.146, from 0.934 to 1.181 and from 1.790."""
    return Scene([Mass("m", 1.0)],
                 [Element("wall", get_law("linear_spring").bind(k=40.0), "ground", "m"),
                  Element("grip", get_law("bingham").bind(gamma=0.5, tau=1.5), "m", "table")],
                 supports={"table": GroundMotion(velocity=SineBurst(amplitude=0.3,
                                                                    omega=4.0))})


def _rope() -> Scene:
    """A mass driven by a shaken spring and held by a string to the wall: the string goes
    taut (an impact, 0.2206) and slack again (0.8953)."""
    return Scene([Mass("m", 1.0)],
                 [Element("rope", get_law("string_spring").bind(k=10.0, L=0.02), "ground",
                          "m"),
                  Element("drive", get_law("linear_spring").bind(k=100.0), "m", "shaker")],
                 supports={"shaker": GroundMotion(displacement=SineBurst(amplitude=0.05,
                                                                         omega=3.0))})


def _belt_file() -> Scene:
    return load_scene(EXAMPLES / "belt.toml")[0]


@pytest.mark.parametrize(("make", "node", "kinds"), [
    (_belt_file, "mass", ["switch", "switch"]),
    (_held, "m", ["switch"] * 4),
    (_rope, "m", ["impact", "switch"]),
])
def test_bdf2_converges_to_radau5_at_order_two(make, node, kinds):
    # measured (max |x| against radau5, dt = 1e-3, 5e-4, 2.5e-4): belt 2.4e-6, 5.9e-7,
    # 1.5e-7; held 1.8e-6, 4.4e-7, 1.1e-7; rope 4.6e-6, 1.2e-6, 2.9e-7 (rates 1.99-2.02)
    ref = simulate(make(), method="radau5", rtol=1e-10, atol=1e-13, dt=1e-3, t_end=2.0)
    assert ref.ok, ref.message
    assert [ev.kind for ev in ref.events] == kinds
    err = []
    for dt in (1e-3, 5e-4, 2.5e-4):
        sol = simulate(make(), method="bdf2", dt=dt, t_end=2.0)
        step = round(1e-3 / dt)
        err.append(float(np.max(np.abs(sol.x[node][::step] - ref.x[node]))))
    assert err[0] < 1e-5, err
    rates = [math.log2(err[i] / err[i + 1]) for i in range(2)]
    assert all(1.8 < r < 2.2 for r in rates), (err, rates)


def test_a_dashpot_stuck_to_a_shaking_support_moves_with_it_exactly():
    sol = simulate(_held(), method="radau5", rtol=1e-10, atol=1e-13, t_end=2.0)
    assert sol.ok, sol.message
    (s0, e0), (s1, e1), (s2, e2) = sol.stick_intervals("grip")
    assert s0 == 0.0 and e2 == 2.0
    assert [round(t, 3) for t in (e0, s1, e1, s2)] == [0.146, 0.934, 1.181, 1.79]
    rel = sol.supports["table"].v - sol.v["m"]
    for s, e in ((s0, e0), (s1, e1), (s2, e2)):
        inside = (sol.t > s) & (sol.t < e)
        # at the step points (the stage values) exactly: measured 0.0; the dense output
        # between them is off by its interpolation of the sine, 7e-11 at dt = 1e-3
        assert np.max(np.abs(rel[inside])) <= 1e-15
        assert np.max(np.abs(sol.F["grip"][inside])) <= 1.5 * (1 + 1e-12)
    assert sol.stats["held_intervals"] == 0  # (the steps hold it: the mass moves)


# ---------------------------------------------------------------- a table-driven support


def _tabled(quantity: str, n: int) -> Scene:
    """:func:`shaken` with the support's motion a table of ``n`` points of the sine's
    velocity (``v_s`` piecewise linear: its acceleration jumps at every point, a time
    event) or acceleration (``a_s`` piecewise linear: kinks)."""
    t = np.linspace(0.0, 3.0, n)
    if quantity == "velocity":
        motion = GroundMotion(velocity=Table(t, D * W * np.cos(W * t), quantity="velocity"))
    else:
        motion = GroundMotion(acceleration=Table(t, -D * W**2 * np.sin(W * t),
                                                 quantity="acceleration"), v0=D * W)
    scene = shaken()
    return Scene(list(scene.nodes), list(scene.elements), supports={"shaker": motion})


@pytest.mark.parametrize("quantity", ["velocity", "acceleration"])
def test_a_table_driven_support_reproduces_the_sine_it_samples(quantity):
    # measured (max |x - exact|, 31, 61, 121 points): velocity 2.1e-4, 5.1e-5, 1.3e-5;
    # acceleration 1.3e-3, 3.2e-4, 8.1e-5 (the tables' own O(dt^2))
    err = []
    for n in (31, 61, 121):
        sol = simulate(_tabled(quantity, n), method="radau5", rtol=1e-9, atol=1e-12,
                       t_end=3.0)
        assert sol.ok, sol.message
        x, _ = shaken_exact(sol.t)
        err.append(float(np.max(np.abs(sol.x["m"] - x))))
        times = [ev.t for ev in sol.events if ev.kind == "time"]
        knots = np.linspace(0.0, 3.0, n)[1:-1]
        # every point of a velocity table is a time event (a_s jumps), none of an
        # acceleration table's (a kink: a step ends there, no mode choice)
        assert len(times) == (len(knots) if quantity == "velocity" else 0)
        assert np.all(np.isin(knots, sol.t))
    assert err[0] < (3e-4 if quantity == "velocity" else 2e-3), err
    rates = [math.log2(err[i] / err[i + 1]) for i in range(2)]
    assert all(1.8 < r < 2.2 for r in rates), (err, rates)


# ---------------------------------------------------------------- auto


def test_auto_runs_radau5_without_dt_and_bdf2_with_dt_alone():
    adaptive = simulate(belt(), t_end=0.5)
    assert adaptive.method == "radau5" and adaptive.ok
    sampled = simulate(belt(), rtol=1e-8, dt=1e-3, t_end=0.5)
    assert sampled.method == "radau5" and len(sampled.t) == 501
    fixed = simulate(belt(), dt=1e-3, t_end=0.5)
    assert fixed.method == "bdf2"
    x, _ = belt_exact(sampled.t)
    assert np.max(np.abs(sampled.x["m"] - x)) < 1e-9


def test_radau5_takes_a_string_on_a_support_and_auto_runs_it_without_dt():
    """(tests/scene/test_support_strings.py: the impact and the moving lock)"""
    scene = Scene([Mass("m", 1.0)],
                  [Element("rope", get_law("string_spring").bind(k=1.0, L=0.1), "m", "belt")],
                  supports={"belt": GroundMotion(velocity=1.0)})
    sol = simulate(scene, t_end=0.3)
    assert sol.method == "radau5" and sol.ok
    assert [ev.kind for ev in sol.events] == ["impact"]


def test_a_network_on_one_support_is_the_moving_ground_network_in_absolute_terms():
    """The network of ``test_supports`` (Bingham dashpots, a junction: stick-slip) two
    ways, both by ``radau5``: on a support (absolute states, the offsets in the laws)
    and on a ground moving the same way (relative states, inertial forces)."""
    from scene.test_supports import DG, WG, _network

    motion = GroundMotion(displacement=SineBurst(amplitude=DG, omega=WG))
    ref = simulate(_network("ground", ground_motion=motion), method="radau5", rtol=1e-11,
                   atol=1e-13, dt=5e-4, t_end=4.0)
    sol = simulate(_network("base", supports={"base": motion}), method="radau5",
                   rtol=1e-10, atol=1e-13, dt=5e-4, t_end=4.0)
    assert sol.ok, sol.message
    err = max(float(np.max(np.abs(sol.x[n] - ref.absolute.x[n]))) for n in ("m", "j", "m2"))
    assert err < 1e-8, err
    assert [(ev.element, ev.kind) for ev in sol.events] == \
        [(ev.element, ev.kind) for ev in ref.events]
