"""A string going taut on a stuck junction under a large load (issue 29).

A draw of the tight property (seed 22070 of the ``long`` profile, after 303 passing
draws, shrunk). At ``t = 0.06694`` the string ``e4`` from the mass goes taut on junction
``j1``, which a Herschel-Bulkley ``n = 0.3`` dashpot held at rest: the plastic impact
(an impulse of ``9e-17``: the junction has no mass) gives ``j1`` the mass's velocity and
the dashpot breaks out. Two things stopped ``radau5`` there, at its step floor, with
backward Euler finding the locks inconsistent:

* the mode after the impact read the moving dashpot at rest, from the balance's force
  alone (:func:`lumped.solvers.modes.after_impact.hold_impacted_locks`), though its
  rate was ``-0.78``;
* the junction took the mode probe's velocity at ``t + h_p`` (``-0.7866``) beside its
  mass's ``-0.7768`` at ``t``, off the taut string's lock: the first step's dense output
  was off the lock by a defect of 561 at every step size
  (:func:`lumped.solvers.modes.lock_events.hold_strung_junctions` now ties it).
"""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene


def _string_taut_at_a_stuck_junction() -> Scene:
    # the tight property's draw at seed 22070 of the ``long`` profile (LUMPED_LARGE=500,
    # after 303 passing draws, shrunk): m0 under a load of -23.3 on a spring, hung by a
    # string e4 on junction j1, which a Herschel-Bulkley n = 0.3 dashpot and a slack
    # string hold to ground; j2 on two Bingham dashpots to ground
    def law(name, **values):
        return get_law(name).bind(**values)

    return Scene(
        [Mass("m0", m=1.0700286251985376, x0=-0.667977907151645, v0=0.6249346388717103),
         Junction("j1", x0=-0.43660996317795575), Junction("j2", x0=0.47707958158500374)],
        [Element("e0", law("linear_spring", k=1.0), "ground", "m0"),
         Element("e1", law("herschel_bulkley", gamma=1.0, tau=1.0, n=0.3), "ground", "j1"),
         Element("e2", law("bingham", gamma=1.0, tau=1.0), "ground", "j2"),
         Element("e3", law("string_spring", k=0.28667895983107616, L=1.0), "ground", "j1"),
         Element("e4", law("string_spring", k=1.0000000000000004, L=0.2364548141364892),
                 "m0", "j1"),
         Element("e5", law("bingham", gamma=0.28667895983107616, tau=1.0), "ground", "j2")],
        {"m0": -23.29505727481599})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_string_going_taut_on_a_stuck_junction_under_a_large_load_runs_through(compiled):
    scene = _string_taut_at_a_stuck_junction()
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled, max_steps=5000)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0 and sol.stats["steps"] <= 600  # (278)
    impact = [ev for ev in sol.events if ev.kind == "impact"]
    assert [ev.element for ev in impact] == ["e4"] and 0.0669 < impact[0].t < 0.067
    after = sol.t > 0.068  # the junction dragged along: e1 slips with the mass
    assert np.all(np.abs(sol.v["j1"][after] - sol.v["m0"][after]) <= 1e-8)
    ref = simulate(scene, method="bdf2", dt=0.025 / 64, t_end=0.5)
    assert np.abs(sol.x["m0"] - ref.x["m0"][::16]).max() <= 1e-4  # (2.4e-6)
