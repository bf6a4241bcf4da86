"""Regressions of ``radau5`` on networks drawn by the random-network property suite
(``tests/solvers/test_random_networks.py``, issue 11), continued from
``test_radau5_networks.py``: each scene is one that used to stop or give a wrong answer,
written out, with the property it broke checked directly."""

from __future__ import annotations

import numpy as np

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene


def _hb(gamma: float, tau: float, n: float):
    return get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=n)


def test_two_stuck_dashpots_in_parallel_break_out_when_the_load_passes_their_yield_forces():
    # e2 (HB n = 0.5) and e4 (HB n = 1.5) hold m2 to ground together; the load reaches
    # tau2 + tau4 at t = 0.0173 and keeps growing. The probe read e4 as slipping at a rate
    # of 1.5e-16 (the slow start of a flat n > 1 branch), below the round-off bound of
    # lock_parallel_rates, which put it back on its lock: the mode was kept and both
    # forces went on to three times their yield forces until t = 0.0349 (silently wrong)
    tau2, tau4 = 0.029477001298478342, 0.1867349663521619
    scene = Scene([
        Mass("m0", m=0.21176362935750243, x0=0.5605838121725837, v0=1.9354279485485817),
        Junction("j1", x0=-5.304654586045421e-255),
        Mass("m2", m=0.5874616616318252, x0=4.402370476406039e-141, v0=1e-10),
        Mass("m3", m=1.0, x0=-0.012605843484027046, v0=1.305730954185381),
    ], [
        Element("e0", get_law("coulomb").bind(tau=0.9896066924246762, r=21.32539635249065),
                "ground", "m0"),
        Element("e1", get_law("bingham").bind(gamma=7.958838559652756,
                                              tau=0.2562052842791847), "ground", "j1"),
        Element("e2", _hb(1.0, tau2, 0.5), "ground", "m2"),
        Element("e3", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "m3"),
        Element("e4", _hb(0.6197601385164463, tau4, 1.5), "ground", "m2"),
        Element("e5", get_law("implicit_spring").bind(k=24.179226385803606, L0=0.1,
                                                      F0=22.610186812838755), "m2", "m3"),
        Element("e6", get_law("string_spring").bind(k=99.99999999999994,
                                                    L=0.005175453888400537), "m0", "ground"),
    ])
    dt = 0.008259071131380965
    sol = simulate(scene, method="radau5", dt=dt, t_end=40 * dt, rtol=dt**2, atol=dt**3,
                   compiled=False)
    assert sol.ok, sol.message
    breaks = [ev.t for ev in sol.events if ev.element == "e4" and ev.from_branch == 2
              and ev.t > 0.01]
    assert breaks and abs(breaks[0] - 0.017337) < 1e-5, sol.events
    stuck = (sol.v["m2"] == 0.0) & (sol.t > 0.01)
    assert stuck.any()
    assert np.all(np.abs(sol.F["e2"][stuck]) <= tau2 * (1 + 1e-9))
    assert np.all(np.abs(sol.F["e4"][stuck]) <= tau4 * (1 + 1e-9))

