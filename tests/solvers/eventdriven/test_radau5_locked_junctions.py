"""``radau5`` at ``rtol = 1e-10`` on two junctions locked together by a stuck dashpot
while the one's dashpot to ground sticks and breaks out (issue 29, a ``LUMPED_LARGE``
tight-run draw: :func:`_lock_scenes.junctions_locked_by_a_stuck_dashpot`): the
junctions' velocity passes the stage Newton's test at the rounding of the dashpot that
sets it, which the lock carries to the other junction
(:func:`lumped.solvers.radau.roundoff.linked_roundoff`)."""

from __future__ import annotations

import numpy as np
import pytest
from _convergence import assert_within_bdf2s_own_error
from _lock_scenes import junctions_locked_by_a_stuck_dashpot

from lumped import simulate

#: e0's stop and break-out, as ``radau5`` finds them at ``rtol = 1e-7 .. 1e-11`` (within
#: 5e-11 s of each other from ``1e-8`` on).
STOP, BREAK_OUT = 0.2048444356819, 0.2257297765070


@pytest.fixture(scope="module")
def runs():
    scene = junctions_locked_by_a_stuck_dashpot()
    return scene, [simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10,
                            atol=1e-13, compiled=compiled) for compiled in (False, True)]


def test_the_locked_junctions_run_through_the_break_out_with_no_bridge(runs):
    """Just after e0 broke out the junctions' velocity (``1e-6``) carried e0's rounding,
    ``ulp(B) gamma = 7e-16`` (``B`` the terms of j0's balance), above the test's ``1e-3
    (atol + rtol |v|) = 1e-16``; e1's stuck row ``V_j1 - V_j0 = 0`` floored both
    velocities at its own terms' rounding, ``1e-21``. Every stage solve failed down to
    the step floor, backward Euler bridged 5 times, and the work budget stopped the run
    at ``t = 0.2257586`` (1345 rejected steps). Both loops now run through, bit for bit."""
    _, sols = runs
    for sol in sols:
        assert sol.ok, sol.message
        assert sol.stats.get("bridges", 0) == 0, sol.message
        assert sol.stats["rejected"] <= 10, sol.stats
    assert np.array_equal(sols[0].data, sols[1].data)
    events = [(ev.t, ev.element, ev.to_branch) for ev in sols[0].events if ev.element]
    assert events == [(ev.t, ev.element, ev.to_branch) for ev in sols[1].events
                      if ev.element]
    assert [(e, b) for _, e, b in events] == [("e0", 2), ("e0", 1)]


def test_e0_stops_where_the_tolerance_puts_it(runs):
    """The landing on e0's stop (the junctions' velocity falling to 0: the same test at
    its round-off) failed too: the bracket closed 1.1e-5 s early (``t = 0.2048336`` in a
    run to 0.3 at this tolerance); now within 1e-9 s of the converged stop."""
    _, sols = runs
    stop, out = (ev.t for ev in sols[0].events if ev.element == "e0")
    assert stop == pytest.approx(STOP, abs=1e-9)
    assert out == pytest.approx(BREAK_OUT, abs=1e-9)


def test_the_locked_junctions_move_as_one_and_agree_with_bdf2(runs):
    scene, sols = runs
    sol = sols[0]
    # e1 stuck throughout: the junctions move together, its force within its yield force
    np.testing.assert_array_equal(sol.v["j0"], sol.v["j1"])
    assert np.abs(sol.F["e1"]).max() < 1.0
    assert_within_bdf2s_own_error(scene, sol, ("j0", "j1", "m2", "m3"), 0.025 / 4, 0.5, 4)
