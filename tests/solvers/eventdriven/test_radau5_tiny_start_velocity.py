"""A mass released at a tiny velocity on a Herschel-Bulkley dashpot, stopped inside
``radau5``'s start probe (issue 29).

A draw of the ``LUMPED_LARGE`` tight-tolerance property (session 23, seed 22033 of the
``dev`` profile, after 2544 passing draws, shrunk): one mass (m = 1, x0 = 0, v0 = 1e-10)
on a Herschel-Bulkley dashpot (gamma = 10, tau = 1, n = 1.5) and a spring (k = 1) to
ground. The exact mass slips for about ``1e-10`` s (at the force ``tau + (v0 /
gamma)^(1/n) = 1 + 4.6e-8``) and then sticks. The start's probe (``5e-10`` s) stops it
and the full laws choose the stuck mode, but the probe's rate ends at ``5.7e-42``, not
zero, so the start's rule for a dashpot the probe stops
(:func:`lumped.solvers.implicit.initial_slip.start_at_known_rates`) did not apply: the
lock set ``v = 0`` and row 0 kept the initial state's slipping force, a dashpot at rest
above its yield force, and a spurious switch of ``e0`` was recorded at the first output
time. A dashpot the chosen mode locks now counts as stopped: row 0 holds ``v = 0`` with
a force in its rest set, as for a probe that stops the rate exactly.
"""

from __future__ import annotations

import numpy as np
import pytest
from _yield_check import check_yield

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.scene.forcing import SineBurst

RTOL, ATOL = 1e-10, 1e-13


def _scene(v0: float) -> Scene:
    return Scene([Mass("m0", m=1.0, x0=0.0, v0=v0)],
                 [Element("e0", get_law("herschel_bulkley").bind(gamma=10.0, tau=1.0, n=1.5),
                          "ground", "m0"),
                  Element("e1", get_law("linear_spring").bind(k=1.0), "ground", "m0")])


@pytest.mark.parametrize("compiled", [False, True])
def test_a_tiny_start_velocity_on_a_herschel_bulkley_dashpot_keeps_its_law(compiled):
    scene = _scene(1e-10)
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=compiled)
    assert sol.ok, sol.message
    check_yield(scene, sol, 100.0 * RTOL, ATOL + RTOL * 1e-10, RTOL)
    assert abs(sol.F["e0"][0]) <= 1.0  # row 0: at rest, inside the rest set
    # the exact travel is about v0^2 / (2 tau) = 5e-21: the mass stays put
    assert np.abs(sol.x["m0"]).max() <= ATOL
    assert not sol.events  # (the stop inside the start probe is the start's choice)


def test_a_start_velocity_the_probe_resolves_is_unchanged():
    # v0 = 1e-6 stops at t = 1e-6 (tau = 1, m = 1), well beyond the start probe: row 0 is
    # the initial state and the stop an event near 1e-6
    scene = _scene(1e-6)
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=False)
    assert sol.v["m0"][0] == 1e-6
    assert sol.F["e0"][0] > 1.0
    assert len(sol.events) == 1 and sol.events[0].t == pytest.approx(1e-6, rel=1e-4)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_mass_a_stuck_coulomb_link_holds_at_the_start_has_its_other_dashpots_at_rest(
        compiled):
    # A draw of the tight property (LUMPED_LARGE=1000, seed 22054, shrunk): one mass at
    # v0 = 4.4e-13 on a Herschel-Bulkley n = 2 dashpot and a Coulomb link, both to ground;
    # it stops at t = 2.2e-13, inside the start probe. The start's mode locks the Coulomb
    # link only (the probe's rate, 3.8e-17, is not round-off of v0), and its lock sets
    # v = 0; row 0 kept the Herschel-Bulkley force at v0, tau + sqrt(v0 / gamma) = 1 +
    # 6.6e-7: v = 0 beside a force above the yield force. The mass the lock holds is now
    # at the lock's rate before the known-rate dashpots take their forces.
    scene = Scene([Mass("m0", m=1.0, x0=0.0, v0=4.4168442794232634e-13)],
                  [Element("e0", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=2.0),
                           "ground", "m0"),
                   Element("e1", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "m0")])
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.v["m0"][0] == 0.0
    assert abs(sol.F["e0"][0]) <= 1.0 and abs(sol.F["e1"][0]) <= 1.0
    check_yield(scene, sol, 100.0 * RTOL, ATOL + RTOL * 1e-12, RTOL)
    assert np.abs(sol.x["m0"]).max() <= ATOL


def _against_the_spring(v0: float) -> Scene:
    """A draw of the tight property (``LUMPED_LARGE``, seed 25037 of the ``long`` profile,
    shrunk; its three unit springs as one): one mass released at ``v0`` against a spring
    whose load (``k x_0 = 1.5``) is beyond the Bingham dashpot's yield force (``tau =
    1``), under ``3.5 sin t``."""
    return Scene([Mass("m0", m=1.0, x0=0.5, v0=v0)],
                 [Element("e0", get_law("linear_spring").bind(k=3.0), "ground", "m0"),
                  Element("e2", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m0")],
                 {"m0": SineBurst(3.5, 1.0)})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_mass_stopped_inside_the_start_probe_slips_on_from_rest(compiled):
    # v0 = 1e-9 stops at t = 4e-10, inside the start probe (5e-10 s), and the spring
    # pulls it back beyond the yield force. The probe's lock read 1.5 - m v0 / h_p = 0.5,
    # within tau: the start put the mass at rest on the stuck branch, which the load does
    # not hold, and the held interval kept it at x = 0.5 for the whole run (the mass
    # slips to 0.4942). Chosen again from rest, the start is the v0 = 0 run's.
    kw = dict(method="radau5", dt=0.025 / 4, t_end=0.5, rtol=RTOL, atol=ATOL,
              compiled=compiled)
    scene = _against_the_spring(1e-9)
    sol = simulate(scene, **kw)
    assert sol.ok, sol.message
    assert sol.v["m0"][0] == 0.0 and sol.F["e2"][0] == -1.0  # slips from rest, backwards
    check_yield(scene, sol, 100.0 * RTOL, ATOL + RTOL, RTOL)
    rest = simulate(_against_the_spring(0.0), **kw)
    assert sol.x["m0"][-1] < 0.4943
    assert np.allclose(sol.data, rest.data, rtol=0.0, atol=1e-12)
