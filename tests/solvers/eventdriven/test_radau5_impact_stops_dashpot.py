"""A ``radau5`` failure (issue 29), fixed: an impact that stops a mass left the force of
its slipping Herschel-Bulkley dashpot above the yield force.

A draw of the ``LUMPED_LARGE`` tight-tolerance property (session 23, seed 22034 of the
``dev`` profile, after 688 passing draws), shrunk: one mass (m = 1, at rest) on a string
(k = 1, L = 0.00347, slack) and a Herschel-Bulkley dashpot (gamma = 1, tau = 0.34036,
n = 1.5) to ground, under a sine load ``A sin t`` of amplitude ``A = tau + 1.5``. The
dashpot breaks out at ``t = 0.186``; the string goes taut with an impact at
``t = 0.4325`` (the mass at ``v = 0.04``) and holds the mass at ``x = L``, ``v = 0``. The
dashpot, at rate 0 from then on, must carry a force in its rest set ``|F| <= tau`` (the
string takes the rest). It kept the force the mode choice's probe read beside a slack
string, ``tau + (a h_p)^(1/n)``: ``2.3e-7`` above ``tau`` (a rate of ``1e-10`` over the
probe), and ``5.5e-4`` above it for ``n = 3``, where the string then also went slack
``3e-4`` s early. Now it stops at its yield force ``tau`` (as ``bdf2`` keeps it) and the
string carries the rest, until the load falls to ``tau + k L`` at ``t1 = pi - asin((tau +
k L) / A)``; the mass stays at rest until the load reaches ``k L - tau`` at ``t2 = pi +
asin((tau - k L) / A)``, where the dashpot breaks out backwards (an exact solution).

The mode choice after the impact runs in the Python loop for both values of
``compiled`` (the compiled loop leaves locks in parallel to it); both are run.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst

TAU = 0.34035925158995717
L = 0.0034696409959938798
A = TAU + 1.5


def _scene(n: float = 1.5) -> Scene:
    return Scene([Mass("m0", m=1.0)],
                 [Element("e0", get_law("string_spring").bind(k=1.0, L=L), "ground", "m0"),
                  Element("e2", get_law("herschel_bulkley").bind(gamma=1.0, tau=TAU, n=n),
                          "ground", "m0")],
                 {"m0": SineBurst(A, 1.0, math.inf)})


@pytest.mark.parametrize("compiled", [False, True])
def test_an_impact_that_stops_the_mass_puts_its_dashpot_in_its_rest_set(compiled):
    sol = simulate(_scene(), method="radau5", dt=0.025 / 16, t_end=0.5, rtol=1e-10,
                   atol=1e-13, compiled=compiled)
    assert sol.ok, sol.message
    assert any(ev.kind == "impact" for ev in sol.events)  # the string goes taut
    at_rest = sol.v["m0"] == 0.0
    assert at_rest[-1]
    # at rest the dashpot's force lies in its rest set (to the force tolerance 100 rtol)
    assert np.abs(sol.F["e2"][at_rest]).max() <= TAU * (1.0 + 1e-8)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_dashpot_stopped_by_an_impact_holds_its_yield_force_until_the_load_falls(compiled):
    # n = 3: the probe's force beside the slack string was tau + 5.5e-4
    rtol = 1e-10
    sol = simulate(_scene(3.0), method="radau5", dt=0.025 / 16, t_end=3.4, rtol=rtol,
                   atol=1e-13, compiled=compiled)
    assert sol.ok, sol.message
    t_imp = [ev.t for ev in sol.events if ev.kind == "impact"]
    assert len(t_imp) == 1
    t1 = math.pi - math.asin((TAU + L) / A)
    t2 = math.pi + math.asin((TAU - L) / A)
    held = (sol.t > t_imp[0]) & (sol.t < t2)
    # the motion: held on the taut string (exact)
    assert np.abs(sol.x["m0"][held] - L).max() <= 1e-12
    assert np.abs(sol.v["m0"][held]).max() <= 1e-12
    # the forces: the dashpot in its rest set, at its yield force while the string is
    # taut beyond k L, and the balance of the load (to the force tolerance 100 rtol)
    tol = 100.0 * rtol * A
    F_d, F_s = sol.F["e2"][held], sol.F["e0"][held]
    assert np.abs(F_d).max() <= TAU + tol
    assert np.abs(sol.F["e2"][held & (sol.t < t1)] - TAU).max() <= tol
    assert np.abs(F_s + F_d - A * np.sin(sol.t[held])).max() <= tol
    assert F_s.min() >= L - tol
    # the dashpot breaks out backwards at t2 (event location to 1e-8 s)
    out = [ev.t for ev in sol.events if ev.element == "e2" and ev.t > t_imp[0] + 1.0
           and ev.to_branch == 1]
    assert out == [pytest.approx(t2, abs=1e-8)]
