"""lumped.solvers.modes.after_impact.hold_impacted_locks: the mode and forces after an
impact whose lock the mode choice's probe read off by round-off (issue 29)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene, SineBurst
from lumped.solvers.eventdriven.setup import scene_plan
from lumped.solvers.modes.after_impact import hold_impacted_locks

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


def test_a_dashpot_stopped_by_an_impact_beside_stuck_friction_sits_at_its_yield_force():
    """A ``LUMPED_LARGE`` tight draw (issue 29), shrunk: a mass on a linear spring, a string
    (``L = 0.01``), a Coulomb element and a Herschel-Bulkley ``n = 2`` dashpot, all to
    ground, under ``3 sin(10 t)``. The string stops the mass at ``t = 0.0211`` and again
    at ``0.0739``; the Coulomb element sticks and carries the load while the mass rests.
    The choice's probe left the dashpot at ``tau + 3.9e-9`` (then ``tau + 2.5e-8``), on its
    slip branch at rate 0, for the whole hold: its force at rest must lie in its set."""
    scene = Scene([Mass("m0", m=1.0, x0=0.0, v0=0.5)],
                  [Element("e0", get_law("linear_spring").bind(k=1.0), "ground", "m0"),
                   Element("e1", get_law("string_spring").bind(k=1.0, L=0.01), "ground", "m0"),
                   Element("e2", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "m0"),
                   Element("e3", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=2.0),
                           "ground", "m0")],
                  {"m0": SineBurst(3.0, 10.0, math.inf)})
    sol = simulate(scene, method="radau5", t_end=0.1, dt=0.0025, rtol=1e-10, atol=1e-13,
                   compiled=False)
    assert [ev.kind for ev in sol.events if ev.element == "e1"][:2] == ["impact", "impact"]
    at_rest = sol.v["m0"] == 0.0
    assert at_rest.sum() >= 20
    assert np.abs(sol.F["e3"][at_rest]).max() <= 1.0
    assert np.abs(sol.F["e2"][at_rest]).max() <= 1.0
