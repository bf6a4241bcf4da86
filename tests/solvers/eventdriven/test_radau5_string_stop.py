"""``radau5``: a mass stopped by a string between two yield dashpots to ground, held there
while a load pushes it on (issue 29; a draw of the tight random-network property, seed
22046 of the ``long`` profile, draw 2841, shrunk).

m0, pushed by a sine burst, slips from rest at ``t = 0.0061`` against a Bingham dashpot e4
and a Herschel-Bulkley ``n = 2`` dashpot e5 to ground, and reaches the length of the
string e0 at ``t = 0.1012``: a plastic impact stops it, and the burst holds it on the
string until it ends at ``t = 0.1819``; the spring of the string (``k L = 0.011``) is then
below the two yield forces, so m0 stays. While m0 is held, e4 and e5 have rate 0: the
exact forces of the three are not unique (locks in parallel), and the dashpots must be
on their locks. The mode choice after the impact read both on their slip branches at rate
0: the probe's rate of m0 was the round-off of its position over the probe (``8e-10``),
above the forces' round-off it was compared with. Held on its slip branch at rate 0,
e5's law ``q = gamma (F - tau)^2`` has a double root, where the stage Newton's
corrections only halve: three steps in four failed, 5992 steps and 16080 rejected ones
for 0.3 s of the run (34 s of CPU; the draw itself 90 s).
"""

from __future__ import annotations

import numpy as np
import pytest
from _lock_scenes import mass_stopped_by_a_string_between_yield_dashpots
from _yield_check import check_yield

from lumped import simulate

L, TAU4, TAU5 = 0.01, 0.03405872114191103, 0.8867371614238684


@pytest.mark.parametrize("compiled", [False, True])
def test_a_mass_held_on_a_string_puts_its_yield_dashpots_on_their_locks(compiled):
    scene = mass_stopped_by_a_string_between_yield_dashpots()
    sol = simulate(scene, method="radau5", t_end=0.3, rtol=1e-10, atol=1e-13,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0
    # the work of a run that steps through the hold (5992 steps, 16080 rejected before)
    assert sol.stats["steps"] < 400 and sol.stats["rejected"] < 200, sol.stats
    stop = [ev.t for ev in sol.events if ev.element == "e0" and ev.kind == "impact"]
    assert len(stop) == 1 and stop[0] == pytest.approx(0.1012, abs=1e-4), sol.events
    locked = {ev.element: ev.to_branch for ev in sol.events if ev.t == stop[0]
              and ev.kind == "switch"}
    assert locked == {"e4": 2, "e5": 2}, sol.events  # (branch 2: each law's lock)
    ts = np.linspace(stop[0] + 1e-3, 0.3, 80)
    y, col = sol.sol(ts), sol.columns.index
    np.testing.assert_allclose(y[:, col("x_m0")], L, rtol=1e-12)
    np.testing.assert_allclose(y[:, col("v_m0")], 0.0, atol=1e-9)
    assert np.all(np.abs(y[:, col("F_e4")]) <= TAU4 * (1 + 1e-12))
    assert np.all(np.abs(y[:, col("F_e5")]) <= TAU5 * (1 + 1e-12))
    check_yield(scene, sol, 1e-8, 1e-13 + 1e-10, 1e-10)
    # bdf2 agrees before, through and after the stop
    ref = simulate(scene, method="bdf2", t_end=0.3, dt=2.5e-4)
    ts = np.linspace(0.0, 0.3, 61)
    y, yr = sol.sol(ts), ref.sol(ts)
    for name in ("x_m0", "x_m3", "v_m3"):
        np.testing.assert_allclose(y[:, col(name)], yr[:, col(name)], atol=2e-4)
