"""The split of the forces the laws leave free among the junctions' balances
(:func:`lumped.solvers.nonsmooth.locks.split_free_forces`), as the consistent initial
state uses it: a balance row with tiny terms counts in the units of the forces it may
receive."""

from __future__ import annotations

import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.implicit.initial_state import consistent_initial_state

TAU0, TAU3, TAU5 = 0.13566077446148683, 0.031010777748433804, 0.01668698486490415


def _stuck_loop_of_three_dashpots(x_j0: float) -> Scene:
    # seed 68 of benchmarks/tight_hunt.py: the junctions j0 and j3 joined by a Coulomb
    # element (e3) and a spring (e4) at the elongation x_j0 - x_j3 (4.8e-37 drawn), j0
    # held to ground by a Herschel-Bulkley n = 1 dashpot (e0) and pulled by m2 through an
    # implicit spring (e2, 0.1317 N), j3 by a Herschel-Bulkley n = 0.3 dashpot (e5); m1
    # apart, under a load, on two dashpots
    hb = get_law("herschel_bulkley")
    return Scene(
        [Junction("j0", x0=x_j0),
         Mass("m1", m=0.24814255310164568, x0=2e-15, v0=3.266520966350331e-303),
         Mass("m2", m=1.0000000000023026, x0=0.2638526776964405, v0=-5.281785955336788e-243),
         Junction("j3", x0=-7.033471891911014e-100)],
        [Element("e0", hb.bind(gamma=3.612960145309005, tau=TAU0, n=1.0), "ground", "j0"),
         Element("e1", hb.bind(gamma=0.9999769744141629, tau=0.017172936580817665, n=1.5),
                 "ground", "m1"),
         Element("e2", get_law("implicit_spring").bind(k=1.0, L0=1.0, F0=1.0), "j0", "m2"),
         Element("e3", get_law("coulomb").bind(tau=TAU3, r=6.261362115646024), "j0", "j3"),
         Element("e4", get_law("linear_spring").bind(k=10.002302850208247), "j3", "j0"),
         Element("e5", hb.bind(gamma=4.7822226316342995, tau=TAU5, n=0.3), "j3", "ground"),
         Element("e6", get_law("coulomb").bind(tau=0.9999999999999994, r=7.397929212653803),
                 "m1", "ground")],
        {"m1": 3.592123679239016})


@pytest.mark.parametrize("x_j0", [4.826288134403629e-37, 0.0, 1e-20])
def test_a_junction_at_rest_on_a_loop_of_stuck_dashpots_has_an_initial_state(x_j0):
    """The state at rest exists: e2's ``0.1317`` N is below e0's yield force ``0.1357``,
    so j0 and j3 rest with ``F_e3 = F_e5`` anywhere in ``[-0.0167, 0.0039]`` and ``F_e0 =
    F_e2 + F_e3`` (e4's force ``1e-35`` aside). It was refused, 'no consistent initial
    state: Newton failed (diverged)': the split of the free forces weighted j3's balance
    by its own terms, e4's ``4.8e-36`` N (``2e35``), which swamped j0's, left unbalanced
    by ``0.13``; j3's row now counts in the units of the forces it may receive."""
    scene = _stuck_loop_of_three_dashpots(x_j0)
    v, F, _ = consistent_initial_state(scene, time_scale=0.025)
    assert abs(v[0]) < 1e-25 and abs(v[3]) < 1e-25  # (rates at the limit step's scale)
    e0, e2, e3, e4, e5 = F[0], F[2], F[3], F[4], F[5]
    assert e2 + e3 - e0 - e4 == pytest.approx(0.0, abs=1e-15)  # j0's balance
    assert e4 + e5 - e3 == pytest.approx(0.0, abs=1e-15)  # j3's
    for force, tau in ((e0, TAU0), (e3, TAU3), (e5, TAU5)):
        assert abs(force) <= tau * (1.0 + 1e-12)
    sol = simulate(scene, method="bdf1", dt=0.025, t_end=0.25)
    assert sol.ok, sol.message
