"""Forces put back on the bounds their laws set (:mod:`lumped.solvers.modes.force_bounds`):
two scenes of ``benchmarks/tight_hunt.py`` that ``radau5`` at ``rtol = 1e-10`` bridged by
backward Euler (issue 29; non-strict expected failures before).

1. Seed 120: one mass stops and sticks on a Coulomb element and a Herschel-Bulkley
   ``n = 1.5`` dashpot under a load equal to their yield forces' sum to the last bit. The
   stage Newton left one force ``1.4e-13`` above its yield force and the other as far
   below (its force tolerance), the held interval's guard check read a crossing, the
   steps in the stuck mode read it again at ``t``, and the step fell below its floor at
   ``t = 0.0657507``. Now both forces go on their yield forces (the only split) and the
   interval is held to the end.
2. A Herschel-Bulkley ``n = 2`` dashpot (flat at its yield force) reversing under a sine
   at ``t = 0.47767``: the landing leaves the rate ``2e-15``, the mode probe's force was
   ``-tau - 2.4e-6`` (its own rate), off the law there, and every stage solve failed down
   to the step floor. Now a yield dashpot switching at a rate within the velocity
   tolerance of 0 takes its yield force at ``t``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst
from lumped.solvers.modes.force_bounds import onto_joint_bounds, onto_slip_ends

RTOL, ATOL = 1e-10, 1e-13
DT = 0.025 / 4  # the hunt's output grid


def _load_at_the_joint_yield_force() -> Scene:
    # benchmarks/tight_hunt.py seed 120 (the strategy drew the load factor 1.0 exactly)
    return Scene(
        [Mass("m0", m=0.10343232114176124, x0=-0.6174610335123901, v0=0.9066500463277607)],
        [Element("e0", get_law("coulomb").bind(tau=0.059441037291213514,
                                               r=1.5848931924611136), "ground", "m0"),
         Element("e1", get_law("herschel_bulkley").bind(gamma=0.10231849575911504,
                                                        tau=0.08992662090968018, n=1.5),
                 "ground", "m0")],
        {"m0": 0.1493676582008937})


def _flat_dashpot_under_a_sine() -> Scene:
    return Scene([Mass("m", m=1.0, v0=-1.0)],
                 [Element("k", get_law("linear_spring").bind(k=10.0), "ground", "m"),
                  Element("d", get_law("herschel_bulkley").bind(gamma=0.3, tau=0.4, n=2.0),
                          "ground", "m")],
                 {"m": SineBurst(amplitude=8.0, omega=9.0, t_off=math.inf)})


def _agrees_with_bdf2(scene: Scene, sol, name: str) -> None:
    """The finest of three ``bdf2`` runs (``dt`` halved) lies within twice its own error
    (its distance to the run at twice the step) of ``sol`` on the output grid."""
    runs = [simulate(scene, method="bdf2", dt=DT / 2**k, t_end=0.5).x[name][::2**k]
            for k in (2, 3)]
    own = float(np.abs(runs[0] - runs[1]).max())
    assert float(np.abs(runs[1] - sol.x[name]).max()) <= 2.0 * own


def _run_without_a_bridge(scene: Scene):
    """The hunt's run (the Python loop): it must run through with no bridge."""
    sol = simulate(scene, method="radau5", dt=DT, t_end=0.5, rtol=RTOL, atol=ATOL,
                   compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    return sol


def test_radau5_on_a_load_at_the_joint_yield_force_needs_no_bridge():
    scene = _load_at_the_joint_yield_force()
    sol = _run_without_a_bridge(scene)
    # stuck from t = 0.0657 on, both elements at their yield forces
    assert float(sol.v["m0"][-1]) == 0.0
    for el in scene.elements:
        assert float(sol.F[el.name][-1]) == pytest.approx(el.law.params["tau"], rel=1e-15)
    _agrees_with_bdf2(scene, sol, "m0")


def test_radau5_reverses_on_a_flat_dashpot_without_a_bridge():
    scene = _flat_dashpot_under_a_sine()
    sol = _run_without_a_bridge(scene)
    reversals = [ev.t for ev in sol.events if ev.element == "d"]
    assert len(reversals) == 2
    assert reversals[1] == pytest.approx(0.47767, abs=1e-5)
    _agrees_with_bdf2(scene, sol, "m")


def test_locks_in_parallel_at_their_joint_bound_go_on_it():
    # the two elements of seed 120 (ground -> m0) and one turned (m0 -> ground), each
    # stuck in [-tau, tau]; the load tau0 + tau1 split 1.4e-13 off the bounds
    scene = _load_at_the_joint_yield_force()
    t0, t1 = 0.059441037291213514, 0.08992662090968018
    cones = {0: (0.0, t0, -t0, t0), 1: (0.0, t1, -t1, t1)}
    got = onto_joint_bounds(scene, cones, [t0 - 1.4e-13, t1 + 1.4e-13], RTOL)
    assert got == [t0, t1]
    got = onto_joint_bounds(scene, cones, [-t0 + 1.4e-13, -t1 - 1.4e-13], RTOL)
    assert got == [-t0, -t1]
    inside = [0.5 * t0, t1]  # below the joint bound: the split is the steps' rule's
    assert onto_joint_bounds(scene, cones, inside, RTOL) == inside


def test_a_flat_dashpot_switching_at_a_vanishing_rate_takes_its_yield_force():
    scene = _flat_dashpot_under_a_sine()
    F = [0.98937, -0.4000024190362437]
    assert onto_slip_ends(scene, [0, 0], [0, 1], [2.1e-15], F, 1e-13, RTOL) == [0.98937, -0.4]
    # a rate beyond the tolerance, no switch, or a force far from the yield force (more
    # than sqrt(rtol) of it): the force stays
    assert onto_slip_ends(scene, [0, 0], [0, 1], [2.1e-12], F, 1e-13, RTOL) == F
    assert onto_slip_ends(scene, [0, 1], [0, 1], [2.1e-15], F, 1e-13, RTOL) == F
    far = [0.98937, -0.41]
    assert onto_slip_ends(scene, [0, 0], [0, 1], [2.1e-15], far, 1e-13, RTOL) == far
