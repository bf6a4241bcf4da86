"""A load that touches the joint yield force of two stuck dashpots at its peaks: a guard
that touches zero costs a few landing tries, and a load a hair beyond breaks out on time
(issue 29, "never a hang").

The scene of :mod:`test_radau5_stuck_forces_output`: one mass at rest on a Coulomb and a
Bingham dashpot (yield force 1 each) and a newtonian one to ground, under ``2 (1 + eps)
sin(10 t)``. With ``eps = 0`` the load reaches the joint yield force 2 at its peaks and
the stuck mode's guards touch zero there without crossing (a double root). A step of
0.13 s over the peak overshot on its collocation polynomial; the landing bisected towards
that step, its end values never below zero, and redid it about 300 times (637 Newton
iterations for 12 steps). The landing now searches the dip of the end-of-step values
(:class:`lumped.solvers.eventdriven.landing.Landing`).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst

DT = 0.005
RTOL, ATOL = DT**2, DT**3


def _scene(eps: float) -> Scene:
    elements = [Element("e0", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "m0"),
                Element("e1", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m0"),
                Element("e2", get_law("newtonian").bind(c=1.0), "ground", "m0")]
    return Scene([Mass("m0", m=1.0)], elements,
                 {"m0": SineBurst(2.0 * (1.0 + eps), 10.0, math.inf)})


def _run(eps: float, compiled: bool = False):
    return simulate(_scene(eps), method="radau5", dt=DT, t_end=0.5, rtol=RTOL, atol=ATOL,
                    compiled=compiled)


@pytest.mark.parametrize("eps", [0.0, -1e-9, 1e-9])
def test_a_load_that_touches_the_joint_yield_force_costs_a_few_landing_tries(eps):
    sol = _run(eps)
    assert sol.ok, sol.message
    if eps <= 0.0:  # it stays stuck (eps = 1e-9: the landing finds the break-out, but its
        # slip, 9e-6 s at 1e-14 m/s, is far below the velocity tolerance: not asserted)
        assert np.all(sol.v["m0"] == 0.0) and not sol.events
    # the work: 45-55 Newton iterations (637, 477 and 519 before; 12 steps either way)
    assert sol.stats["newton_iterations"] <= 100 and sol.stats["steps"] <= 15
    if eps == 0.0:  # the compiled loop (here Python's: locks in parallel) lands alike
        assert np.array_equal(_run(eps, compiled=True).data, sol.data)


@pytest.mark.parametrize("eps", [1e-4, 1e-3])
def test_a_load_beyond_the_joint_yield_force_breaks_out_when_it_reaches_it(eps):
    # the break-out at the first t with 2 (1 + eps) sin(10 t) = 2: the guards' dip was
    # searched on end values; before, eps = 1e-4 lost the first two break-outs (the first
    # event at t = 0.47) and eps = 1e-3 broke out 5.5e-5 s late (the first slip step read
    # its start off the guard by the stage forces' quadratic, and the mode went back)
    sol = _run(eps)
    assert sol.ok, sol.message
    t1 = (0.5 * math.pi - math.acos(1.0 / (1.0 + eps))) / 10.0
    first = [ev for ev in sol.events if ev.t == sol.events[0].t]
    assert {(ev.element, ev.from_branch, ev.to_branch) for ev in first} == {
        ("e0", 2, 1), ("e1", 2, 1)}  # both dashpots slip forwards
    # within the landing's tolerance: |g| <= 64 eps (1 + |F|) over the guard's slope
    assert first[0].t == pytest.approx(t1, abs=1e-9)
    assert sol.stats["newton_iterations"] <= 150  # (99, 109; 551 and 235 before)
