"""lumped.solvers.modes.lock_events.hold_rate_locks: the rates a mode's locked dashpots fix,
set exactly at an event, a junction's where the event locks it to ground (issue 29)."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven.setup import scene_plan
from lumped.solvers.modes.lock_events import hold_rate_locks

STUCK = 2  # the Herschel-Bulkley and Bingham branches: F > tau, F < -tau, else (q = 0)


def _chain() -> Scene:
    # ground -e0- j0 -e1- j1 -e2- m2 -e3- j3, a spring from each node to ground
    hb = get_law("herschel_bulkley").bind(gamma=1.0, tau=0.5, n=0.5)
    bingham = get_law("bingham").bind(gamma=1.0, tau=0.5)
    spring = get_law("linear_spring").bind(k=1.0)
    return Scene(
        [Junction("j0"), Junction("j1"), Mass("m2", m=1.0), Junction("j3")],
        [Element("e0", hb, "ground", "j0"), Element("e1", bingham, "j0", "j1"),
         Element("e2", hb, "m2", "j1"), Element("e3", bingham, "m2", "j3")]
        + [Element(f"s{i}", spring, "ground", name)
           for i, name in enumerate(("j0", "j1", "m2", "j3"))])


def test_a_junction_the_event_locks_to_ground_takes_its_rate_exactly():
    scene = _chain()
    branches = scene_plan(scene).branches
    modes = [STUCK] * 4 + [0] * 4
    # the probe's velocities: the junctions a round-off rate off their locks (m2 at rest)
    v = [2e-7, -3e-8, 0.0, 4e-9]
    done = hold_rate_locks(scene, branches, modes, v, locked_now=[0])
    # e0 ties j0 to ground: set; e1, e2 and e3 tie two nodes: left as the probe had them
    assert done == [0]
    assert v == [0.0, -3e-8, 0.0, 4e-9]


def test_a_junction_locked_before_the_event_is_left_as_the_probe_found_it():
    scene = _chain()
    branches = scene_plan(scene).branches
    modes = [STUCK] * 4 + [0] * 4
    v = [2e-7, -3e-8, 0.0, 4e-9]
    assert hold_rate_locks(scene, branches, modes, v) == []
    assert v == [2e-7, -3e-8, 0.0, 4e-9]


@pytest.mark.parametrize("compiled", [False, True])
def test_a_junction_stuck_in_finite_time_rests_exactly_after_its_stop(compiled):
    """A junction on a spring pulled back through a Herschel-Bulkley ``n = 0.9`` dashpot to
    ground stops in finite time (``tests/solvers/eventdriven/test_radau5_finite_stop.py``).
    The mode choice's probe at the stop read the lock with the junction at ``-2e-7``; left
    there, the step after the stop started off its stages and its dense output carried
    ``6e-8`` into the samples after the stop. The junction now rests exactly."""
    scene = Scene([Mass("m0", m=1.0), Junction("j1", x0=0.05)],
                  [Element("e0", get_law("linear_spring").bind(k=1.0), "ground", "m0"),
                   Element("e1", get_law("herschel_bulkley").bind(gamma=10.0, tau=0.1, n=0.9),
                           "ground", "j1"),
                   Element("e2", get_law("linear_spring").bind(k=10.0), "j1", "ground")])
    sol = simulate(scene, method="radau5", dt=0.01, t_end=0.2, rtol=1e-6, atol=1e-9,
                   compiled=compiled)
    assert sol.ok, sol.message
    stop = [ev for ev in sol.events if ev.element == "e1"][-1]
    assert stop.to_branch == STUCK
    after = np.asarray(sol.t) > stop.t
    assert after.sum() >= 5
    assert np.all(np.asarray(sol.v["j1"])[after] == 0.0)
