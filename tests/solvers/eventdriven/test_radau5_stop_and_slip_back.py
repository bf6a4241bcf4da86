"""A mass that stops and slips back at once under a load a hair beyond its dashpots' joint
yield force, against its exact solution (issue 29).

A draw of the ``LUMPED_LARGE`` tight-tolerance property (session 24, seed 22037 of the
``long`` profile, after 4462 passing draws), shrunk: one mass (m = 1, ``v0 = 2^-7``) on
three Bingham dashpots (gamma = 1, tau = 1) and a newtonian one (c = 1) to ground, under
the constant load ``P = -3.0000690783`` (``6.9e-5`` beyond the joint yield force 3).
Forwards ``v' = P - 3 - 4 v`` until the stop at ``t_s``; then at once backwards, ``v' = P
+ 3 - 4 v``, towards ``(P + 3) / 4``. ``radau5`` at rtol 1e-10 is on this to round-off;
the property failed because the fixed-step references were not: the stop lies inside the
first step of every level of their ladders, and ``bdf1`` (off by 5e-6) and ``bdf2`` (off by
8.5e-4: it breaks out backwards with the velocity of the step before the stop) read a
ladder difference far below their error (the property's ladders now take the halvings an
early first event needs: ``test_random_networks.check_tight``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

P, V0 = -3.0000690783480803, 0.0078125


def _scene() -> Scene:
    def bingham(name: str) -> Element:
        return Element(name, get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m0")

    return Scene([Mass("m0", m=1.0, v0=V0)],
                 [bingham("e0"), Element("e1", get_law("newtonian").bind(c=1.0), "ground", "m0"),
                  bingham("e2"), bingham("e3")], {"m0": P})


def _exact(t: float) -> float:
    """``x(t)``: forwards with ``v' = -4 (v + b)``, ``b = (3 - P) / 4``, to the stop at
    ``t_s``; then ``v' = -4 (v - w)``, ``w = (P + 3) / 4``, from rest."""
    b, w = (3.0 - P) / 4.0, (P + 3.0) / 4.0
    t_s = math.log((V0 + b) / b) / 4.0
    if t <= t_s:
        return (V0 + b) * -math.expm1(-4.0 * t) / 4.0 - b * t
    s = t - t_s
    x_s = (V0 + b) * -math.expm1(-4.0 * t_s) / 4.0 - b * t_s
    return x_s + w * (s + math.expm1(-4.0 * s) / 4.0)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_mass_that_stops_and_slips_back_at_once_follows_its_exact_solution(compiled):
    sol = simulate(_scene(), method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10,
                   atol=1e-13, compiled=compiled)
    assert sol.ok, sol.message
    exact = np.array([_exact(float(t)) for t in sol.t])
    scale = float(np.abs(exact).max())  # 5.1e-6
    assert np.abs(sol.x["m0"] - exact).max() <= 1e-9 * scale
    # the three dashpots leave forward slip for backward slip together, at the stop
    t_s = math.log((V0 + (3.0 - P) / 4.0) / ((3.0 - P) / 4.0)) / 4.0
    assert {ev.element for ev in sol.events} == {"e0", "e2", "e3"}
    assert all(ev.t == pytest.approx(t_s, abs=1e-12) for ev in sol.events)
