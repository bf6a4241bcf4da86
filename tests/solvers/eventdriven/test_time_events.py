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
from lumped.solvers.eventdriven.setup import breakpoints


def _scene(t_off: float, record: Table) -> Scene:
    return Scene([Mass("m", 2.0), Mass("n", 1.0)],
                 [Element("slider", get_law("coulomb").bind(tau=1.5, r=1e3), "ground", "m"),
                  Element("k", get_law("linear_spring").bind(k=40.0), "ground", "m"),
                  Element("link", get_law("linear_spring").bind(k=25.0), "m", "n"),
                  Element("d", get_law("bingham").bind(gamma=2.0, tau=0.5), "m", "n")],
                 {"m": SineBurst(3.0, 4.0, t_off)},
                 ground_motion=GroundMotion(acceleration=record))


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
