"""lumped.solvers.modes.lock_events.hold_strung_junctions: after an impact, junctions that
taut strings tie to a mass (through other junctions too) take its velocity (issue 29)."""

from __future__ import annotations

import pytest

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven.setup import scene_plan
from lumped.solvers.modes.lock_events import hold_strung_junctions


def _strung_chain(last_to_ground: bool = False) -> Scene:
    # m0 -e0- j1 -e1- j2 by strings (then j2 -e2- ground by a string too, or a spring),
    # each junction on a Newtonian dashpot to ground, m0 on a spring
    string = get_law("string_spring").bind(k=1.0, L=0.1)
    dashpot = get_law("newtonian").bind(c=0.5)
    spring = get_law("linear_spring").bind(k=1.0)
    return Scene(
        [Mass("m0", m=1.0), Junction("j1"), Junction("j2")],
        [Element("e0", string, "m0", "j1"), Element("e1", string, "j1", "j2"),
         Element("e2", string if last_to_ground else spring, "j2", "ground"),
         Element("d1", dashpot, "ground", "j1"), Element("d2", dashpot, "ground", "j2"),
         Element("s0", spring, "ground", "m0")])


def _taut(branches, e) -> int:
    return next(i for i, info in enumerate(branches[e].info)
                if info.locks and info.lock_value is not None)


def test_junctions_strung_in_a_chain_take_the_mass_velocity():
    scene = _strung_chain()
    branches = scene_plan(scene).branches
    modes = [_taut(branches, 0), _taut(branches, 1)] + [0] * 4
    # the probe's velocities at t + h_p: both junctions off the mass's -0.7768
    v = [-0.7768, -0.7866, -0.7901]
    assert hold_strung_junctions(scene, branches, modes, v, 1e-9) == [0, 1]
    # (tying junction-to-mass strings alone left j2 at -0.7901)
    assert v == pytest.approx([-0.7768] * 3, abs=1e-15)
    assert v[0] == -0.7768  # (no mass moves: the junctions carry no momentum)


def test_a_string_to_ground_holds_its_junction_at_rest():
    scene = _strung_chain(last_to_ground=True)
    branches = scene_plan(scene).branches
    modes = [0, _taut(branches, 1), _taut(branches, 2)] + [0] * 3
    v = [-0.7768, 3e-4, -2e-4]  # (e0 slack: j1 is tied to ground through j2)
    assert hold_strung_junctions(scene, branches, modes, v, 1e-9) == [1, 2]
    assert v == pytest.approx([-0.7768, 0.0, 0.0], abs=1e-15)


def test_junctions_within_the_velocity_tolerance_keep_the_probes_velocities():
    scene = _strung_chain()
    branches = scene_plan(scene).branches
    modes = [_taut(branches, 0), _taut(branches, 1)] + [0] * 4
    v = [-0.7768, -0.7768 + 5e-10, -0.7768 - 4e-10]
    assert hold_strung_junctions(scene, branches, modes, v, 1e-9) == []
    assert v == [-0.7768, -0.7768 + 5e-10, -0.7768 - 4e-10]
    # ... and slack strings tie nothing
    v = [-0.7768, -0.7866, -0.7901]
    assert hold_strung_junctions(scene, branches, [0] * 6, v, 1e-9) == []
    assert v == [-0.7768, -0.7866, -0.7901]
