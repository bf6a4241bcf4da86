"""A known and not yet fixed ``radau5`` failure (issue 29): the forces of a stuck mass
under a sine load, read on the output grid between long steps, are off its balance.

A draw of the ``LUMPED_LARGE`` Python-loop property (session 22, after 1095 passing
draws): one mass at rest on a Coulomb and a Bingham dashpot (yield force 1 each) and a
newtonian one to ground, under a sine burst of amplitude exactly their joint yield force
2, ``omega = 10``. The mass never moves, so its three forces must carry the load at every
``t``: ``F0 + F1 + F2 = f(t)``. ``radau5`` takes 12 steps over ``[0, 0.5]`` (about
``0.04`` s each, ``omega h = 0.4``) and the stuck forces it gives on the output grid in
between are off that balance by up to ``9e-3`` (``3.6e-3`` at ``t = 0.155``; ``rtol =
2.5e-5``), each
yield force ``1.6e-3`` above its bound. The error control does not see the forces of a
stuck interval between its steps. A strict expected failure, so that a fix shows as an
unexpected pass.
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


@pytest.mark.xfail(strict=True, raises=AssertionError, reason="issue 29: open")
def test_a_stuck_mass_under_a_sine_load_keeps_its_balance_on_the_output_grid():
    sol = simulate(_scene(), method="radau5", dt=DT, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=False)
    assert sol.ok, sol.message
    assert np.all(sol.v["m0"] == 0.0)  # the mass never moves (the loads stay within 2)
    load = AMPLITUDE * np.sin(OMEGA * sol.t)
    carried = sol.F["e0"] + sol.F["e1"] + sol.F["e2"]
    # the sign convention: a dashpot from ground to m0 pulls m0 by -F, so F carries +f
    assert np.abs(carried - load).max() <= 10.0 * RTOL * AMPLITUDE
    for name in ("e0", "e1"):
        assert np.abs(sol.F[name]).max() <= 1.0 + RTOL * AMPLITUDE
