"""The mode choice's probe (:func:`lumped.solvers.modes.choice.select_modes`) on a steep
dashpot starting to slip at exactly its yield force (issue 29, seed 22228's start)."""

from __future__ import annotations

import pytest
from _yielding_junction import TAU, yielding_junction

from lumped.codegen.branches import law_branches
from lumped.solvers.modes.choice import select_modes


@pytest.mark.parametrize("h_probe", [2.2e-13, 5e-10, 2.2e-7, 2.2e-4])
def test_a_junction_dashpot_at_its_yield_force_is_read_slipping_forward(h_probe):
    # junction j1's Herschel-Bulkley n = 0.3 dashpot at F = tau, moving at 1e-9 with the
    # loaded mass m2 (a stuck Bingham link): the probe's step must slip it forward, its
    # force at +tau (rounded: tau + (rate)^(1/0.3)), the mass accelerating at 2
    scene = yielding_junction()
    lbs = [law_branches(el.law) for el in scene.elements]
    v = [0.0, 1e-9, 1e-9, 1e-9]
    F = [0.0, TAU, TAU, 0.0, 0.0, 0.0]
    got = select_modes(scene, lbs, 0.0, [0.0] * 4, v, F, h_probe)
    assert not isinstance(got, str), got
    modes, v_p, F_p = got
    assert modes == [0, 0, 2, 0, 0, 0]  # (e1 slipping forward, e2 stuck)
    assert F_p[1] >= TAU and abs(F_p[2] - TAU) <= 1e-6  # (the springs at j3 take 1e-7)
    assert v_p[1] == v_p[2] and abs(v_p[2] - (1e-9 + 2.0 * h_probe)) <= 1e-6 * v_p[2]
