"""The forces of a stuck mass under a sine load, read on ``radau5``'s output grid between
long steps, keep its balance and its yield bands (issue 29).

A draw of the ``LUMPED_LARGE`` Python-loop property (session 22, after 1095 passing
draws): one mass at rest on a Coulomb and a Bingham dashpot (yield force 1 each) and a
newtonian one to ground, under a sine burst of amplitude exactly their joint yield force
2, ``omega = 10``. The mass never moves, so its three forces must carry the load at every
``t``: ``F0 + F1 + F2 = f(t)``. ``radau5`` takes 12 steps over ``[0, 0.5]`` (up to ``0.13``
s each, ``omega h = 1.3``): the stage values hold the balance at the collocation nodes,
but the collocation cubic between them was off it by up to ``9e-3`` (``rtol = 2.5e-5``),
each yield force ``1.6e-3`` above its bound. The dense output now puts the forces of the
locks between nodes at rest onto their balance at each output time
(:mod:`lumped.solvers.radau.locked_forces`), in both loops.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst

AMPLITUDE, OMEGA = 2.0, 10.0
DT = 0.005
RTOL, ATOL = DT**2, DT**3


def _scene() -> Scene:
    elements = [Element("e0", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "m0"),
                Element("e1", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m0"),
                Element("e2", get_law("newtonian").bind(c=1.0), "ground", "m0")]
    return Scene([Mass("m0", m=1.0)], elements,
                 {"m0": SineBurst(AMPLITUDE, OMEGA, math.inf)})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_stuck_mass_under_a_sine_load_keeps_its_balance_on_the_output_grid(compiled):
    sol = simulate(_scene(), method="radau5", dt=DT, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert np.all(sol.v["m0"] == 0.0)  # the mass never moves (the loads stay within 2)
    load = AMPLITUDE * np.sin(OMEGA * sol.t)
    carried = sol.F["e0"] + sol.F["e1"] + sol.F["e2"]
    # the sign convention: a dashpot from ground to m0 pulls m0 by -F, so F carries +f
    assert np.abs(carried - load).max() <= 10.0 * RTOL * AMPLITUDE
    for name in ("e0", "e1"):
        assert np.abs(sol.F[name]).max() <= 1.0 + RTOL * AMPLITUDE


def _partly_stuck(amplitude: float, omega: float) -> Scene:
    """m0 stuck on a Coulomb element (``tau = 2``) under a sine load, joined by a spring to
    m1, which oscillates on a spring to ground from ``x0 = 0.05``: m0's load stays within
    ``|f| + k |x1| <= 1.55 < 2``."""
    elements = [Element("e0", get_law("coulomb").bind(tau=2.0, r=1.0), "ground", "m0"),
                Element("e1", get_law("linear_spring").bind(k=1.0), "m0", "m1"),
                Element("e2", get_law("linear_spring").bind(k=10.0), "ground", "m1")]
    return Scene([Mass("m0", m=1.0), Mass("m1", m=1.0, x0=0.05)], elements,
                 {"m0": SineBurst(amplitude, omega, math.inf)})


def test_a_stuck_mass_beside_a_moving_one_keeps_its_balance_on_the_output_grid():
    # the steps follow m1 (15 over [0, 0.5]); m0's Coulomb force, interpolated, was off
    # m0's balance by 1.4e-3 (36 rtol times the load) between them
    amplitude, omega = 1.5, 20.0
    sols = [simulate(_partly_stuck(amplitude, omega), method="radau5", dt=DT, t_end=0.5,
                     rtol=RTOL, atol=ATOL, compiled=compiled) for compiled in (False, True)]
    assert np.array_equal(sols[0].data, sols[1].data)  # the same numbers in both loops
    sol = sols[0]
    assert sol.ok, sol.message
    assert np.all(sol.v["m0"] == 0.0) and np.abs(sol.v["m1"]).max() > 0.1
    load = amplitude * np.sin(omega * sol.t)
    # m0's balance: f - F_e0 (e0 ends at m0) + F_e1 (e1 starts at m0) = 0
    residual = load - sol.F["e0"] + sol.F["e1"]
    assert np.abs(residual).max() <= 10.0 * RTOL * amplitude
