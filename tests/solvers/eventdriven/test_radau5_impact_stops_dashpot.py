"""A known and not yet fixed ``radau5`` failure (issue 29): an impact that stops a mass
leaves the force of its slipping Herschel-Bulkley dashpot above the yield force.

A draw of the ``LUMPED_LARGE`` tight-tolerance property (session 23, seed 22034 of the
``dev`` profile, after 688 passing draws; the same on the tree before the session),
shrunk: one mass (m = 1, at rest) on a string (k = 1, L = 0.00347, slack) and a
Herschel-Bulkley dashpot (gamma = 1, tau = 0.34036, n = 1.5) to ground, under a sine
load of amplitude ``tau + 1.5``. The dashpot breaks out at ``t = 0.186``; the string goes
taut with an impact at ``t = 0.4325`` and holds the mass at ``x = L``, ``v = 0``. The
dashpot, at rate 0 from then on, must carry a force in its rest set ``|F| <= tau`` (the
string takes the rest), but it keeps its last slipping force, ``2.3e-7`` above ``tau``
(its slip rate just before the impact was about ``1e-10``). A strict expected failure, so
that a fix shows as an unexpected pass.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst

TAU = 0.34035925158995717


def _scene() -> Scene:
    return Scene([Mass("m0", m=1.0)],
                 [Element("e0", get_law("string_spring").bind(k=1.0, L=0.0034696409959938798),
                          "ground", "m0"),
                  Element("e2", get_law("herschel_bulkley").bind(gamma=1.0, tau=TAU, n=1.5),
                          "ground", "m0")],
                 {"m0": SineBurst(TAU + 1.5, 1.0, math.inf)})


@pytest.mark.xfail(strict=True, raises=AssertionError, reason="issue 29: open")
def test_an_impact_that_stops_the_mass_puts_its_dashpot_in_its_rest_set():
    sol = simulate(_scene(), method="radau5", dt=0.025 / 16, t_end=0.5, rtol=1e-10,
                   atol=1e-13, compiled=False)
    assert sol.ok, sol.message
    assert any(ev.kind == "impact" for ev in sol.events)  # the string goes taut
    at_rest = sol.v["m0"] == 0.0
    assert at_rest[-1]
    # at rest the dashpot's force lies in its rest set (to the force tolerance 100 rtol)
    assert np.abs(sol.F["e2"][at_rest]).max() <= TAU * (1.0 + 1e-8)
