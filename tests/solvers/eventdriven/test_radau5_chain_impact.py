"""``radau5``: two masses tied by a taut string, stopped together when the first reaches
its own string's length (issue 29; a draw of the tight random-network property, seed 22045
of the ``long`` profile, after 2617 passing).

m0 (``v0 = 1.5``) goes taut on e0 (a string to ground) at once; the load of ``221`` on m1
pulls m1 up until e1 (a string from m0) goes taut at ``t = 0.0637``, and the two move up
together at ``8.05`` until m0 reaches e0's length again at ``t = 0.07665``: a plastic
impact stops both, and the load keeps both strings taut from then on (the exact motion:
m0 and m1 at rest at ``L_0`` and ``L_0 + L_1``, e1 carrying the load). The mode choice
after the impact read e1 slack (its probe moves the string's ends by ``2e-18``, below their
positions' rounding, and e0's snap onto its length had moved e1 ``1.3e-13`` off its own),
and the run went on from there with both strings slack: it bounced back at ``-6.3``.
"""

from __future__ import annotations

import numpy as np
import pytest
from _lock_scenes import two_strings_stopped_together

from lumped import simulate

L0, L1, LOAD = 0.6720605383456154, 0.03205626107396782, 221.02329860463186


@pytest.mark.parametrize("compiled", [False, True])
def test_masses_stopped_together_by_a_string_stay_on_both_strings(compiled):
    sol = simulate(two_strings_stopped_together(), method="radau5", t_end=0.5, rtol=1e-10,
                   atol=1e-13, compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    stop = [ev.t for ev in sol.events if ev.element == "e0" and ev.kind == "impact"]
    assert len(stop) >= 2 and stop[1] == pytest.approx(0.07665, abs=1e-5), sol.events
    # no string goes slack after the stop
    assert not [ev for ev in sol.events if ev.t > stop[1] and ev.kind == "switch"
                and ev.element in ("e0", "e1")], sol.events
    ts = np.linspace(stop[1] + 1e-3, 0.5, 60)
    y, col = sol.sol(ts), sol.columns.index
    np.testing.assert_allclose(y[:, col("v_m0")], 0.0, atol=1e-9)
    np.testing.assert_allclose(y[:, col("v_m1")], 0.0, atol=1e-9)
    np.testing.assert_allclose(y[:, col("x_m0")], L0, rtol=1e-12)
    np.testing.assert_allclose(y[:, col("x_m1")], L0 + L1, rtol=1e-12)
    np.testing.assert_allclose(y[:, col("F_e1")], LOAD, rtol=1e-9)
    # bdf2 agrees (it stops both at its step's impact)
    ref = simulate(two_strings_stopped_together(), method="bdf2", t_end=0.5, dt=1.6e-4)
    yr = ref.sol(ts)
    for name in ("x_m0", "x_m1", "x_m2"):
        np.testing.assert_allclose(y[:, col(name)], yr[:, col(name)], atol=1e-5)
