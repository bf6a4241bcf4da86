"""Regressions of ``bdf1`` / ``bdf2`` found by the random-network property suite (issue 11,
session 8), each scene written out as drawn. As in ``test_network_bdf_regressions2``,
every run is checked against the laws: it completes, every value is finite and no stuck
dashpot carries more than its yield force."""

from __future__ import annotations

import numpy as np
import pytest
from _yield_check import run_checked as _run_ok

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene


def _string_taut_beside_a_stuck_parallel_pair() -> Scene:
    """Drawn by the suite (session 8, as drawn): ``m1`` runs away from ``m0`` (held by a
    Coulomb element ``e0``) and the string ``e1``, ``0.0066`` short of its length, goes
    taut in the first step; junction ``j2`` hangs on ``m1`` by a Bingham-like
    Herschel-Bulkley dashpot ``e2`` (``n = 1``) and a Coulomb element ``e3`` in parallel,
    both stuck (their split of the spring ``e5``'s force is free), while ``m1`` slips on
    a Herschel-Bulkley dashpot ``e4`` (``n = 0.3``) to ground."""
    return Scene(
        [Mass("m0", m=3.267642917017149, x0=-0.5934019634047084, v0=5.795687848153468e-157),
         Mass("m1", m=5.623413251903491, x0=7.183868578550699e-278, v0=0.38677848560916894),
         Junction("j2", x0=0.5070979777114681)],
        [Element("e0", get_law("coulomb").bind(tau=0.46971913285260636, r=57.38038306498419),
                 "ground", "m0"),
         Element("e1", get_law("string_spring").bind(k=1.0000000000000004,
                                                     L=0.5999609420416394), "m0", "m1"),
         Element("e2", get_law("herschel_bulkley").bind(gamma=2.124618119325982, tau=1.0,
                                                        n=1.0), "m1", "j2"),
         Element("e3", get_law("coulomb").bind(tau=0.12733782932613766, r=8.212538101258005),
                 "m1", "j2"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=1.0000000000000009, tau=1.0,
                                                        n=0.3), "ground", "m1"),
         Element("e5", get_law("linear_spring").bind(k=1.0), "m1", "j2")])


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("dt", [0.025, 0.0125, 0.00625])
def test_string_taut_beside_a_stuck_parallel_pair(method, dt):
    """Every level stopped with 'Newton failed (diverged)' in the step where ``e1`` goes
    taut: the rows of the stuck pair ``e2``, ``e3`` are proportional (ratio ``-8.2``), LU
    eliminated one to a pivot of an ulp instead of zero, and while ``e4``'s law was still
    converging the correction moved their free split by ``1e13``; Newton crawled back by
    halving and ran out. A correction that long along a null space hidden by rounding
    is now replaced by the minimum-norm one, which leaves the split alone."""
    scene = _string_taut_beside_a_stuck_parallel_pair()
    sol = _run_ok(scene, method, dt, 0.5)
    assert [ev.element for ev in sol.events][:1] == ["e1"]
    assert 0.0 < sol.events[0].t < 0.025
    assert np.array_equal(sol.v["j2"], sol.v["m1"])  # the pair stays stuck
    # the pair carries the spring's force between them, each within its yield force
    total = sol.F["e2"] + sol.F["e3"] + sol.F["e5"]
    assert np.abs(total).max() <= 1e-9

