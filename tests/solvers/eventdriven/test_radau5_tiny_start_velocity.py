"""A known and not yet fixed ``radau5`` failure (issue 29): a mass released at a tiny
velocity on a Herschel-Bulkley dashpot reads, on its first row, the slipping force of
its initial state beside a velocity of zero.

A draw of the ``LUMPED_LARGE`` tight-tolerance property (session 23, seed 22033 of the
``dev`` profile, after 2544 passing draws, shrunk): one mass (m = 1, x0 = 0, v0 = 1e-10)
on a Herschel-Bulkley dashpot (gamma = 10, tau = 1, n = 1.5) and a spring (k = 1) to
ground. The exact mass slips for about ``1e-10`` s (its force ``tau + (v0/gamma)^(1/n) =
1 + 4.6e-8``) and then sticks. ``radau5`` at ``rtol = 1e-10`` takes no step, records a
switch of ``e0`` at the first output time ``t = 0.00625`` (not at about ``1e-10``), and
its first row holds ``v = 0`` with ``F = 1 + 4.6e-8``: a dashpot at rest above its
yield force, which ``tests/_yield_check.py`` refuses. The same on ``main`` before
session 23 (``fd2dfe1``). A strict expected failure, so that a fix shows as an
unexpected pass.
"""

from __future__ import annotations

import pytest
from _yield_check import check_yield

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

RTOL, ATOL = 1e-10, 1e-13


def _scene() -> Scene:
    return Scene([Mass("m0", m=1.0, x0=0.0, v0=1e-10)],
                 [Element("e0", get_law("herschel_bulkley").bind(gamma=10.0, tau=1.0, n=1.5),
                          "ground", "m0"),
                  Element("e1", get_law("linear_spring").bind(k=1.0), "ground", "m0")])


@pytest.mark.xfail(strict=True, raises=AssertionError, reason="issue 29: open")
def test_a_tiny_start_velocity_on_a_herschel_bulkley_dashpot_keeps_its_law():
    scene = _scene()
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=False)
    assert sol.ok, sol.message
    check_yield(scene, sol, 100.0 * RTOL, ATOL + RTOL * 1e-10, RTOL)
