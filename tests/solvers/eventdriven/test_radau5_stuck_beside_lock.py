"""A dashpot held at rate 0 by a lock beside it goes on its stuck branch
(:func:`lumped.solvers.modes.force_bounds.stuck_beside_locks`).

The scene is seed 23009's draw of the ``LUMPED_LARGE`` tight-tolerance property of
``radau5`` (``test_random_network_tight_tolerance``), written out: a shear-thickening
Herschel-Bulkley dashpot (``n = 2``, ``e6``) beside a Bingham one (``e5``) between a
junction and a mass. When ``e5`` sticks at ``t = 0.3987`` the mode probe read ``e6`` on its
slip branch, ``8e-9`` above its yield force, where that branch is flat in the force; every
stage Newton from there failed and the step was halved: 2355 steps, 6379 rejected and
40 s of CPU over ``[0, 0.5]``, against 128 steps, 16 rejected and under 2 s with ``e6``
on its stuck branch. The motion is the same; the split of the forces on the cycle is free.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven.setup import scene_plan
from lumped.solvers.modes.force_bounds import stuck_beside_locks

HB, BINGHAM, COULOMB = (get_law(n) for n in ("herschel_bulkley", "bingham", "coulomb"))
#: the property's tolerances (``test_random_networks.TIGHT_RTOL``, ``TIGHT_ATOL``)
RTOL, ATOL = 1e-10, 1e-13
#: ``x, v`` of ``m0``, ``m1`` at ``t = 0.5`` as the run with ``e6`` on its slip branch
#: gave them (``radau5`` before this rule, 2355 steps): the same motion
BEFORE = {"x_m0": -0.20359452956072205, "v_m0": -1.0305328607001905,
          "x_m1": -0.726421227873099, "v_m1": -1.0305328607001905}


def _draw_23009() -> Scene:
    nodes = [Mass("m0", m=1.896448177114999, x0=0.37737375313456156, v0=-1.3011861916564573),
             Mass("m1", m=1.0, x0=-0.3185022605858657, v0=-0.45748112774997507),
             Junction("j2", x0=-0.34425747173261), Junction("j3", x0=0.8289995390463272)]
    elements = [
        Element("e0", get_law("string_spring").bind(k=2.65899000711969, L=0.39955577537723447),
                "ground", "m0"),
        Element("e1", HB.bind(gamma=8.52318607682181, tau=1.0, n=1.5), "m0", "m1"),
        Element("e2", COULOMB.bind(tau=0.4261356086459855, r=1.0), "m0", "j2"),
        Element("e3", COULOMB.bind(tau=0.07693955713269156, r=1.0), "j2", "j3"),
        Element("e4", get_law("newtonian").bind(c=1.0), "ground", "j3"),
        Element("e5", BINGHAM.bind(gamma=0.30749455353057803, tau=0.15238528052714148),
                "j2", "m1"),
        Element("e6", HB.bind(gamma=0.9046886471689398, tau=0.03723684534337339, n=2.0),
                "j2", "m1")]
    return Scene(nodes, elements, {})


def test_the_draw_runs_in_a_few_hundred_steps_with_e6_stuck_beside_e5():
    sol = simulate(_draw_23009(), method="radau5", dt=0.025 / 4, t_end=0.5, rtol=RTOL,
                   atol=ATOL, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats["steps"] <= 400 and sol.stats["rejected"] <= 100, sol.stats
    switches = [(ev.element, ev.to_branch) for ev in sol.events if ev.kind == "switch"]
    lbs = scene_plan(_draw_23009()).branches
    stuck = {e: next(i for i, info in enumerate(lbs[e].info) if info.locks) for e in (5, 6)}
    assert ("e5", stuck[5]) in switches and ("e6", stuck[6]) in switches, switches
    # after the stick, the two dashpots' forces lie within their yield forces and carry
    # the load between j2 and m1 together
    t = np.asarray(sol.t)
    after = t > 0.41
    for name, tau in (("e5", 0.15238528052714148), ("e6", 0.03723684534337339)):
        F = np.asarray(sol.F[name])[after]
        assert np.all(np.abs(F) <= tau * (1.0 + 1e-6)), (name, np.abs(F).max())
    assert np.allclose(np.asarray(sol.v["m1"])[after], np.asarray(sol.v["j2"])[after],
                       rtol=0.0, atol=1e-9)
    end = dict(zip(sol.columns, sol.data[-1].tolist(), strict=True))
    for key, want in BEFORE.items():
        assert end[key] == pytest.approx(want, rel=1e-8, abs=1e-9), key


def _pair(second, *, a: str = "ground", b: str = "m0") -> Scene:
    """One mass on a stuck Bingham dashpot and ``second`` beside it."""
    return Scene([Mass("m0", m=1.0, x0=0.0, v0=0.0)],
                 [Element("s", BINGHAM.bind(gamma=1.0, tau=1.0), "ground", "m0"),
                  Element("d", second, a, b)], {})


def _branch(lb, locks: bool) -> int:
    return next(i for i, info in enumerate(lb.info) if bool(info.locks) == locks)


def test_a_dashpot_on_its_slip_end_beside_a_lock_goes_stuck():
    tau = 0.25
    scene = _pair(HB.bind(gamma=1.0, tau=tau, n=2.0))
    lbs = scene_plan(scene).branches
    modes = [_branch(lbs[0], True), lbs[1].branch(0.0, 2.0 * tau)]  # (a slip branch)
    assert not lbs[1].info[modes[1]].locks
    F_edge = tau + 8e-9
    got = stuck_beside_locks(scene, lbs, modes, [0.5, F_edge], 1e-10)
    assert got == [modes[0], _branch(lbs[1], True)] and got is not modes
    # beyond the stuck interval by more than sqrt(rtol) (1 + |F|): it slips
    far = tau + 2.0 * math.sqrt(1e-10) * (1.0 + tau + 1e-3)
    assert stuck_beside_locks(scene, lbs, modes, [0.5, far], 1e-10) == modes
    # the lock beside it slipping: nothing holds the dashpot at rate 0
    slipping = [lbs[0].branch(0.0, 2.0), modes[1]]
    assert not lbs[0].info[slipping[0]].locks
    assert stuck_beside_locks(scene, lbs, slipping, [1.5, F_edge], 1e-10) == slipping


def test_only_a_dashpot_between_the_same_two_nodes_as_the_lock_is_moved():
    tau = 0.25
    # between another pair of nodes (m0 and a second mass): not held by the lock
    scene = Scene([Mass("m0", m=1.0, x0=0.0, v0=0.0), Mass("m1", m=1.0, x0=0.0, v0=0.0)],
                  [Element("s", BINGHAM.bind(gamma=1.0, tau=1.0), "ground", "m0"),
                   Element("d", HB.bind(gamma=1.0, tau=tau, n=2.0), "m0", "m1")], {})
    lbs = scene_plan(scene).branches
    modes = [_branch(lbs[0], True), lbs[1].branch(0.0, 2.0 * tau)]
    assert stuck_beside_locks(scene, lbs, modes, [0.5, tau], 1e-10) == modes
    # a slack string beside a stuck dashpot is a spring: never put on its lock
    string = _pair(get_law("string_spring").bind(k=10.0, L=1.0))
    lbs = scene_plan(string).branches
    slack = [_branch(lbs[0], True), _branch(lbs[1], False)]
    assert stuck_beside_locks(string, lbs, slack, [0.5, 0.0], 1e-10) == slack
