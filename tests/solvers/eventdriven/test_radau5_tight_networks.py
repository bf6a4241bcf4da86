"""``radau5`` at ``rtol = 1e-10`` on loaded random networks that it used to bridge or stop
on (issue 29), each scene written out from the random-network strategy
(``benchmarks/tight_hunt.py`` draws seed ``s``); each runs through with no backward-Euler
bridge, as at ``rtol = 1e-6``."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene


def _string_beside_a_flat_herschel_bulkley_link() -> Scene:
    # seed 274: a loaded mass m0 tied to m1 by a string (e3) beside a shear-thickening
    # Herschel-Bulkley link (e1, n = 2)
    hb = get_law("herschel_bulkley")
    return Scene(
        [Mass("m0", m=1.0, x0=-0.37624293996242686, v0=-1.77269902465682),
         Mass("m1", m=0.9999999999999686, x0=0.3280626156988069, v0=1.1860400812457152e-233)],
        [Element("e0", get_law("implicit_spring").bind(k=1.0, L0=0.46991011312735004,
                                                       F0=2.4975923322238236), "ground", "m0"),
         Element("e1", hb.bind(gamma=0.26969640567091646, tau=0.10816107742637955, n=2.0),
                 "m0", "m1"),
         Element("e2", hb.bind(gamma=0.6471675365679924, tau=0.9906610524904494, n=1.5),
                 "m1", "ground"),
         Element("e3", get_law("string_spring").bind(k=3.6150856881332056,
                                                     L=0.8043055556612337), "m0", "m1")],
        {"m0": 1.638745886928079})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_string_that_impacts_beside_a_flat_yielding_link_goes_slack_at_once(compiled):
    """At ``t = 0.0729808183`` the string e3 reaches its length while its ends separate: a
    plastic impact. After it the load and the springs pull the ends together (the balance
    of accelerations wants ``0.14`` of the string, below its ``k L = 2.9``), so the string
    goes slack at once and e1, at rest relative to its ends, slips from its yield force
    (``F = -tau - sqrt(-q / gamma)``). The mode choice's probe read the string taut from
    round-off and a stage solve found e1's mirror root beyond its yield force: the modes
    alternated with steps of ``1e-12`` s until the run stopped at its step floor and
    backward Euler bridged it (a strict expected failure before)."""
    scene = _string_beside_a_flat_herschel_bulkley_link()
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    impacts = [ev for ev in sol.events if ev.kind == "impact"]
    assert [ev.element for ev in impacts] == ["e3"]
    assert impacts[0].t == pytest.approx(0.0729808183, abs=1e-9)
    assert impacts[0].impulse > 0.0  # a string pulls
    # after the impact: the string slack (q < L, its spring's force) and e1 slipping
    # backwards beyond its yield force, at every output point
    k, L = 3.6150856881332056, 0.8043055556612337
    tau = 0.10816107742637955
    after = np.asarray(sol.t) > impacts[0].t
    q = np.asarray(sol.x["m1"])[after] - np.asarray(sol.x["m0"])[after]
    assert after.sum() >= 60 and np.all(q < L)
    np.testing.assert_allclose(np.asarray(sol.F["e3"])[after], k * q, rtol=1e-9)
    assert np.all(np.asarray(sol.F["e1"])[after] < -tau)


def test_the_tight_run_agrees_with_a_loose_one():
    # the same trajectory at rtol 1e-6 (no event there is in doubt): within its error
    scene = _string_beside_a_flat_herschel_bulkley_link()
    tight = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10,
                     atol=1e-13, compiled=False)
    loose = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-6, atol=1e-9)
    for m in ("m0", "m1"):
        np.testing.assert_allclose(tight.x[m], loose.x[m], rtol=0.0, atol=1e-7)
