"""``radau5``'s row 0 holds the junctions' velocities at ``t = 0``, not those of its start
probe (issue 29; :mod:`lumped.solvers.modes.junctions_at`).

The scene: a junction ``j1`` tied to a mass ``m2`` at rest by two stuck dashpots in
parallel (``e3``, ``e4``) and held to ground by a Herschel-Bulkley ``n = 1.5`` dashpot
``e1``; the load on ``m2`` exceeds ``e1``'s yield force and not the stuck pair's, so the
pair moves as one body from rest, ``e1`` slipping from its yield force. The start's mode
probe (``1e-9`` of the run long) gave row 0 its junction velocity ``7.5e-11`` beside the
mass at 0, and ``e1`` the force ``tau + 2.7e-7`` of that rate.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

M2, LOAD = 7.83640712338274, 1.207233329573393
GAMMA1, TAU1 = 0.5364445264145451, 0.02433199029053824


def _held_junction() -> Scene:
    hb = get_law("herschel_bulkley")
    return Scene(
        [Junction("j1", x0=1e-08), Mass("m2", m=M2)],
        [Element("e1", hb.bind(gamma=GAMMA1, tau=TAU1, n=1.5), "ground", "j1"),
         Element("e3", hb.bind(gamma=0.1, tau=0.11065334455818125, n=1.0), "j1", "m2"),
         Element("e4", get_law("bingham").bind(gamma=5.2343753905899035,
                                               tau=0.07224799472467348), "m2", "j1")],
        {"m2": LOAD})


def _run(compiled: bool):
    return simulate(_held_junction(), method="radau5", t_end=0.5, rtol=1e-10, atol=1e-13,
                    compiled=compiled)


def test_row_0_holds_the_junction_at_the_masss_rate_and_its_dashpot_at_its_yield_force():
    sol = _run(False)
    assert sol.ok, sol.message
    assert sol.v["m2"][0] == 0.0
    assert sol.v["j1"][0] == 0.0  # (the probe's: 7.5e-11)
    assert sol.F["e1"][0] == pytest.approx(TAU1, rel=1e-15, abs=0.0)  # (tau + 2.7e-7)
    # j1's balance (massless): the stuck pair carries e1's force
    F3, F4 = float(sol.F["e3"][0]), float(sol.F["e4"][0])
    assert abs(F3 - F4 - TAU1) <= 1e-15 * (abs(F3) + abs(F4) + TAU1)  # (round-off)
    assert sol.stats.get("bridges", 0) == 0, sol.message


def test_the_start_from_the_consistent_row_0_stays_accurate():
    """Until the stuck pair breaks out (``t = 0.244``) the two move as one body, ``m v' =
    f - tau - (v / gamma)^(2/3)``: its solution by ``solve_ivp`` at ``rtol = 1e-13``."""
    sol = _run(False)
    t = np.asarray(sol.t)
    keep = (t > 0.0) & (t < 0.24)
    exact = solve_ivp(lambda _, y: [(LOAD - TAU1 - (max(y[0], 0.0) / GAMMA1) ** (2.0 / 3.0))
                                    / M2], (0.0, 0.24), [0.0], method="DOP853",
                      t_eval=t[keep], rtol=1e-13, atol=1e-16).y[0]
    v2, v1 = np.asarray(sol.v["m2"])[keep], np.asarray(sol.v["j1"])[keep]
    assert np.max(np.abs(v2 - exact)) <= 1e-9 * np.max(np.abs(exact))
    assert np.max(np.abs(v1 - v2)) <= 1e-12 * np.max(np.abs(exact))


def test_both_loops_give_the_same_numbers():
    a, b = _run(False), _run(True)
    assert a.ok and b.ok
    assert np.array_equal(np.asarray(a.data), np.asarray(b.data))
