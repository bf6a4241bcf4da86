"""``modes.probe_locks.lock_probe_rates``: the dashpots a mode probe leaves at rate 0
beside a taut string go on their locks, at the edge of their set at rest."""

from __future__ import annotations

import math

import pytest

from lumped.codegen.branches import law_branches
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.modes.probe_locks import lock_probe_rates

TAU_B, TAU_HB, GAMMA_HB = 0.03, 0.9, 4.0
EPS = 2.220446049250313e-16


def _scene() -> Scene:
    # m0 on a string to ground (taut: branch 1 locks q = L) between a Bingham and a
    # Herschel-Bulkley n = 2 dashpot to ground; m1 hangs on a spring from m0
    return Scene([Mass("m0", m=1.0, x0=0.01), Mass("m1", m=1.0, x0=0.5)],
                 [Element("e0", get_law("string_spring").bind(k=1.0, L=0.01), "ground", "m0"),
                  Element("e1", get_law("bingham").bind(gamma=1.0, tau=TAU_B), "m0", "ground"),
                  Element("e2", get_law("herschel_bulkley").bind(gamma=GAMMA_HB, tau=TAU_HB,
                                                                 n=2.0), "ground", "m0"),
                  Element("e3", get_law("linear_spring").bind(k=10.0), "m0", "m1")])


def _probe(v0: float, v1: float, h_p: float):
    """A probe's state: m0 at rate v0 (> 0), each dashpot slipping at it on its law."""
    scene = _scene()
    lbs = [law_branches(el.law) for el in scene.elements]
    # e1 (m0 -> ground) slips at -v0: F = -tau - v0; e2 (ground -> m0) at +v0:
    # F = tau + sqrt(v0 / gamma); the string holds the rest of a load of 5
    F1, F2 = -TAU_B - v0, TAU_HB + math.sqrt(v0 / GAMMA_HB)
    F = [5.0 - F1 - F2, F1, F2, 0.0]
    modes = [1, 0, 0, 0]  # the string taut, both dashpots on their slip branches
    return scene, lbs, modes, [v0, v1], F, [0.01, 0.5], h_p


def test_a_string_held_rate_within_the_positions_round_off_locks_at_the_edges():
    h_p = 2e-8
    v0 = 0.5 * 4 * EPS * 0.5 / h_p  # (half the positions' round-off over the probe)
    scene, lbs, modes, v, F, x, h_p = _probe(v0, 0.3, h_p)
    new, F_out = lock_probe_rates(scene, lbs, modes, v, F, x, h_p, 1.0)
    assert new == [1, 2, 2, 0]  # both dashpots on their locks (branch 2)
    assert F_out[1] == pytest.approx(-TAU_B, abs=1e-15)
    assert F_out[2] == pytest.approx(TAU_HB, abs=1e-15)
    assert abs(F_out[2]) <= TAU_HB and abs(F_out[1]) <= TAU_B  # within their sets at rest
    assert F_out[0] == F[0] and F_out[3] == F[3]


@pytest.mark.parametrize(("factor", "v1"), [(4.0, 0.3), (0.5, 0.0)],
                         ids=["beyond the round-off", "every mass at rest"])
def test_the_slip_branches_stay(factor, v1):
    # a rate beyond the positions' round-off slips; with every mass at rest the run is
    # held without steps (modes.stuck), where the split of the slip branches stays
    h_p = 2e-8
    scene, lbs, modes, v, F, x, h_p = _probe(factor * 4 * EPS * 0.5 / h_p, v1, h_p)
    new, F_out = lock_probe_rates(scene, lbs, modes, v, F, x, h_p, 1.0)
    assert new == modes and F_out == F
