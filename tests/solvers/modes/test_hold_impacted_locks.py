"""lumped.solvers.modes.lock_events.hold_impacted_locks: the mode and forces after an
impact whose lock the mode choice's probe read off by round-off (issue 29)."""

from __future__ import annotations

import math

import pytest

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst
from lumped.solvers.eventdriven.setup import scene_plan
from lumped.solvers.modes.lock_events import hold_impacted_locks

TAU = 0.34035925158995717
L = 0.0034696409959938798
T = 0.4325359657348306  # the impact of the draw of issue 29
SLIP, BACK, STUCK = 0, 1, 2  # the Herschel-Bulkley branches: F > tau, F < -tau, else


def _scene() -> Scene:
    return Scene([Mass("m0", m=1.0)],
                 [Element("e0", get_law("string_spring").bind(k=1.0, L=L), "ground", "m0"),
                  Element("e2", get_law("herschel_bulkley").bind(gamma=1.0, tau=TAU, n=1.5),
                          "ground", "m0")],
                 {"m0": SineBurst(TAU + 1.5, 1.0, math.inf)})


@pytest.mark.parametrize(("read", "kept"), [(SLIP, SLIP), (BACK, STUCK)])
def test_the_dashpot_a_string_stops_takes_its_yield_force_not_the_probe_s(read, kept):
    # the state right after the string's plastic impact (the mass at x = L, v = 0; the
    # forces from before it, the dashpot slipping at 0.459); the probe read the string
    # slack and the dashpot at tau + 2.3e-7, its force at the probe's rate 1e-10
    scene = _scene()
    branches = scene_plan(scene).branches
    load = (TAU + 1.5) * math.sin(T)
    new, F_p = [0, read], [L, TAU + 2.268788730774851e-07]
    hold_impacted_locks(scene, branches, T, [0], 1e-13, [L], [0.0],
                        [L, 0.45874431755438005], new, F_p)
    # the string taut with the rest of the load; the dashpot at its yield force, on the
    # probe's branch where that branch admits it, else on the one its law reads there
    assert branches[0].info[new[0]].locks
    assert new[1] == kept
    assert F_p[1] == pytest.approx(TAU, abs=1e-15)
    assert F_p[0] + F_p[1] == pytest.approx(load, abs=1e-15)
