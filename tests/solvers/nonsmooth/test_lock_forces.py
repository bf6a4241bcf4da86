"""lumped.solvers.nonsmooth.lock_forces: forces of locked and stuck elements from the balance of
accelerations at a given state (no step, no division by a step size)."""

from __future__ import annotations

import pytest

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.nonsmooth.lock_forces import forces_from_accelerations


def _lock(load: float) -> Scene:
    return Scene([Mass("mass", m=1.0)],
                 [Element("string", get_law("string_spring").bind(k=1.0, L=0.5),
                          "ground", "mass"),
                  Element("friction", get_law("coulomb").bind(tau=0.2, r=10.0),
                          "ground", "mass")],
                 forces={"mass": load})


def test_a_taut_string_beside_stuck_friction_carries_the_rest_of_the_load():
    # at rest on the lock with the string's force far off (0.5, a remainder's round-off):
    # the friction keeps its 0.2, the string carries the rest of the load of 1
    F = forces_from_accelerations(_lock(1.0), 0.0, [0.5], [0.0], [0.5, 0.2], [0, 1])
    assert F == pytest.approx([0.8, 0.2], abs=1e-14)


def test_forces_leaving_their_sets_go_to_the_boundary():
    # a load of 0.1 cannot keep the string taut (it pulls k L = 0.5) nor the friction
    # stuck (0.4 > 0.2): both on the boundary of their sets, and the mass moves back
    F = forces_from_accelerations(_lock(0.1), 0.0, [0.5], [0.0], [0.5, 0.2], [0, 1])
    assert F == pytest.approx([0.5, -0.2], abs=1e-12)


def test_a_locked_pair_through_a_junction_accelerates_together():
    # m1 -- string (taut) -- junction -- stuck friction to ground ... and a load on m1:
    # the junction is massless, so the string's force is the friction's, which holds
    # while the load stays below its yield force
    scene = Scene([Mass("m1", m=2.0, x0=0.5), Junction("j")],
                  [Element("s", get_law("string_spring").bind(k=1.0, L=0.5), "j", "m1"),
                   Element("d", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "j")],
                  forces={"m1": 0.7})
    F = forces_from_accelerations(scene, 0.0, [0.5, 0.0], [0.0, 0.0], [0.5, 0.0], [0, 1])
    assert F == pytest.approx([0.7, 0.7], abs=1e-12)


def test_no_solution_is_none():
    # a load on a massless junction held only by a spring whose force is given (0): no
    # force of the free element (a string elsewhere) balances the junction
    scene = Scene([Mass("m", m=1.0, x0=0.5), Junction("j")],
                  [Element("s", get_law("string_spring").bind(k=1.0, L=0.5), "ground", "m"),
                   Element("g", get_law("linear_spring").bind(k=1.0), "ground", "j")],
                  forces={"j": 1.0})
    assert forces_from_accelerations(scene, 0.0, [0.5, 0.0], [0.0, 0.0], [0.5, 0.0],
                                   [0]) is None


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_dashpot_stopped_by_a_lock_keeps_its_yield_force(sign):
    # a Herschel-Bulkley n = 3 dashpot slipping at F = +-0.67 (> tau = 0.34) beside a
    # string that has just stopped the mass: at rate 0 its law leaves any |F| <= tau, and
    # the nearest to its force, its yield force +-tau, is kept (its root alone lay at
    # -0.33 from +0.67, issue 29); the string carries the rest of the load
    from lumped.solvers.nonsmooth.lock_forces import forces_with_held

    # (the string is strung the way the load pulls: from ground to the mass, or back)
    tau = 0.34
    ends = ("ground", "mass") if sign > 0 else ("mass", "ground")
    scene = Scene([Mass("mass", m=1.0, x0=sign * 0.5)],
                  [Element("string", get_law("string_spring").bind(k=1.0, L=0.5), *ends),
                   Element("hb", get_law("herschel_bulkley").bind(gamma=1.0, tau=tau, n=3.0),
                           "ground", "mass")],
                  forces={"mass": sign * 0.9})
    F = forces_with_held(scene, 0.0, [sign * 0.5], [0.0], [0.5, sign * 0.67], [0])
    assert F[1] == pytest.approx(sign * tau, abs=1e-12)
    assert F == pytest.approx([0.9 - tau, sign * tau], abs=1e-12)
