"""Time events of ``radau5``: the forcing's breakpoints (jumps and kinks).

Two forcings whose points lie closer than the step floor (a sine burst switched off an
ulp from a record's point) are one time event: before, the step between them was below
the floor, the run bridged it, and the breakpoint left behind the bridge gave negative
steps until the run stopped."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.io import Table
from lumped.scene import GroundMotion, SineBurst
from lumped.solvers.eventdriven.setup import breakpoints, time_events


def _scene(t_off: float, record: Table) -> Scene:
    """Two masses on a slider, springs and a Bingham link; a sine burst on ``m`` and the
    ground moved by ``record`` (any quantity)."""
    return Scene([Mass("m", 2.0), Mass("n", 1.0)],
                 [Element("slider", get_law("coulomb").bind(tau=1.5, r=1e3), "ground", "m"),
                  Element("k", get_law("linear_spring").bind(k=40.0), "ground", "m"),
                  Element("link", get_law("linear_spring").bind(k=25.0), "m", "n"),
                  Element("d", get_law("bingham").bind(gamma=2.0, tau=0.5), "m", "n")],
                 {"m": SineBurst(3.0, 4.0, t_off)},
                 ground_motion=GroundMotion(**{record.quantity: record}))


def _record() -> Table:
    ts = np.linspace(0.0, 2.0, 81)  # its point 48 is 1.2000000000000002
    return Table(ts, 4.0 * np.sin(5.0 * ts) * np.exp(-ts), quantity="acceleration")


def test_breakpoints_closer_than_the_floor_are_one_event():
    record = _record()
    knot = float(record.times[48])
    assert knot != 1.2 and abs(knot - 1.2) < 1e-15
    got = breakpoints(_scene(1.2, record), 2.5)
    assert 1.2 in got and knot not in got
    assert len(got) == 80  # the record's 80 points inside (0, 2.5), the sine's merged
    assert all(b > a for a, b in zip(got, got[1:], strict=False))
    # points further apart than the floor stay two events
    assert {1.2 - 1e-9, knot} <= set(breakpoints(_scene(1.2 - 1e-9, record), 2.5))


@pytest.mark.parametrize("compiled", [False, True])
def test_a_sine_switched_off_an_ulp_from_a_record_point_runs_through(compiled):
    record = _record()
    kw = dict(method="radau5", t_end=2.5, rtol=1e-8, atol=1e-10, compiled=compiled)
    ulp = simulate(_scene(1.2, record), **kw)  # raised SolverError (negative steps)
    assert ulp.stats.get("bridges", 0) == 0
    # the same load switched off on the record's point itself: one event from the start
    same = simulate(_scene(float(record.times[48]), record), **kw)
    t = np.linspace(0.0, 2.5, 501)
    scale = max(1.0, float(np.max(np.abs(same.sol(t)))))
    assert np.max(np.abs(ulp.sol(t) - same.sol(t))) <= 1e-6 * scale
    assert math.isclose(ulp.t[-1], 2.5)


@pytest.mark.parametrize(("quantity", "inner_kinks"),
                         [("acceleration", True), ("velocity", False),
                          ("displacement", True)])
def test_a_records_points_are_kinks_where_its_acceleration_is_continuous(quantity,
                                                                          inner_kinks):
    # a_g is the table (acceleration), its slope (velocity: a jump at every point) or a
    # natural spline's second derivative (displacement): continuous but at a velocity
    # record's points
    rng = np.random.default_rng(7)
    ts = np.linspace(0.0, 1.0, 21)
    record = Table(ts, rng.normal(0.0, 1.0, ts.size), quantity=quantity)
    scene = _scene(math.inf, record)
    breaks, kinks = time_events(scene, 2.0)
    assert breaks == ts[1:].tolist()
    inner = dict(zip(breaks, kinks, strict=True))
    assert all(inner[t] is inner_kinks for t in ts[1:-1].tolist())
    # the record's last point: a_g jumps to its value outside (0) unless it ends there
    a = scene.forcing[0]  # the inertial force -m a_g plus the load
    end = float(ts[-1])
    assert inner[end] is (abs(a(math.nextafter(end, -1.0)) - a(math.nextafter(end, 2.0)))
                          < 1e-9)


def test_a_record_longer_than_max_events_points_runs_through():
    # 12 001 points, every one a step end: the run is not stopped by max_events
    # (10 000), which counts guard crossings and impacts, not the forcing's points
    ts = np.linspace(0.0, 12.0, 12_001)
    rng = np.random.default_rng(3)
    acc = np.convolve(rng.normal(0.0, 2.0, ts.size), np.ones(10) / 10, mode="same")
    record = Table(ts, acc, quantity="velocity")  # a jump of a_g at every point
    scene = Scene([Mass("m", 1.0)],
                  [Element("k", get_law("linear_spring").bind(k=40.0), "ground", "m"),
                   Element("f", get_law("coulomb").bind(tau=0.5, r=1e3), "ground", "m")],
                  ground_motion=GroundMotion(velocity=record))
    sol = simulate(scene, method="radau5", t_end=12.0, rtol=1e-5, compiled=True,
                   throw=False)
    assert sol.success, sol.message
    time = [e for e in sol.events if e.kind == "time"]
    assert len(time) > 10_000  # the velocity record's jumps are time events
    assert len(sol.events) - len(time) <= 10_000
