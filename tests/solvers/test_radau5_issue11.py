"""Regressions of ``radau5`` from issue 11 (session 3): a tangential break-out that
chattered, hard points of a law (Herschel-Bulkley ``n < 1``), and networks drawn by the
random-network property suite (``tests/solvers/test_random_networks.py``) that used to
stop; each checks the property it broke directly."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain


@pytest.mark.parametrize("compiled", [True, False])
def test_a_tangential_break_out_does_not_chatter(compiled: bool) -> None:
    # d1 breaks out at t = 0.858 with its load crossing the yield force slowly: the slip
    # rate grows like t^2, far below the round-off of the force. The first slip step's
    # polynomial started from the mode probe's force (off by m / h_probe times its
    # round-off), which put a false guard crossing into the step: slip -> stick -> slip
    # every 3e-10 s, and the run stopped with TOO_MANY_EVENTS
    scene = bingham_chain(3)
    t_end = 0.87 if not compiled else 1.0  # (the Python loop: the interval that matters)
    sol = simulate(scene, method="radau5", t_end=t_end, rtol=1e-12, atol=1e-15,
                   compiled=compiled)
    assert sol.ok, sol.message
    d1 = [ev for ev in sol.events if ev.element == "d1"]
    assert len(d1) <= 3, d1
    # it slips from the break-out on: negative rate, force beyond the yield force
    late = sol.t > 0.8581
    assert np.all(sol.v["m1"][late] < 0.0)
    assert np.all(sol.F["d1"][late] < -1.5)
