"""An equilibrium under a constant load held in one piece by ``radau5`` also with locks in
parallel (:func:`lumped.solvers.modes.stuck.equilibrium_hold`; issue 29): a mass on two
Bingham dashpots loaded by exactly the sum of their yield forces, where the stage forces
scattered around the bounds by the stage Newton's tolerance and every step read a crossing
of a break-out guard (about 38 loop passes an accepted step, stopped by the work budget)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.implicit.initial_state import consistent_initial_state


def _two_dashpots(load: float) -> Scene:
    # 0.1 + 0.125 = 0.225 exactly in binary
    bingham = get_law("bingham")
    return Scene([Mass("m", m=1.0)],
                 [Element("a", bingham.bind(gamma=1.0, tau=0.1), "ground", "m"),
                  Element("b", bingham.bind(gamma=1.0, tau=0.125), "ground", "m")],
                 {"m": load})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_load_at_the_summed_yield_force_keeps_the_mass_at_rest(compiled):
    sol = simulate(_two_dashpots(0.225), method="radau5", t_end=0.5, compiled=compiled,
                   max_steps=2000)
    assert sol.ok
    assert np.all(sol.x["m"] == 0.0) and np.all(sol.v["m"] == 0.0)
    # every row, the initial state's too (it split the load three ways, m a, F_a, F_b,
    # before: 0.075 each; the first landing then read 0 and 0)
    Fa, Fb = sol.F["a"], sol.F["b"]
    # each dashpot within its yield force (to round-off), together carrying the load
    assert np.all(np.abs(Fa) <= 0.1 + 4 * math.ulp(0.1))
    assert np.all(np.abs(Fb) <= 0.125 + 4 * math.ulp(0.1))
    assert np.abs(Fa + Fb - 0.225).max() <= 4 * math.ulp(0.225)
    assert sol.stats["held_intervals"] >= 1
    for method in ("bdf1", "bdf2"):  # the fixed-step methods keep it at rest too
        ref = simulate(_two_dashpots(0.225), method=method, dt=1e-2, t_end=0.5)
        assert np.abs(ref.v["m"]).max() <= 1e-12


@pytest.mark.parametrize("load", [0.2, 0.05, -0.15])
def test_the_initial_forces_of_dashpots_stuck_in_parallel_balance_the_load(load):
    # the consistent initial state's limit system reads each stuck law at the rate
    # 1e-20 a: its rows' entries are 1e-20, and the minimum-norm solve dropped them (the
    # accelerations left free) until its rows were scaled
    v, F, _ = consistent_initial_state(_two_dashpots(load), time_scale=0.5)
    assert v == [0.0]
    assert F[0] + F[1] == pytest.approx(load, abs=4 * math.ulp(0.25))
    assert abs(F[0]) <= 0.1 + 4 * math.ulp(0.1) and abs(F[1]) <= 0.125 + 4 * math.ulp(0.1)
    sol = simulate(_two_dashpots(load), method="radau5", t_end=0.5)
    assert np.all(sol.v["m"] == 0.0)
    # every row balances, the first (the initial state) to round-off, the steps' rows to
    # their stage Newton's tolerance
    total = sol.F["a"] + sol.F["b"]
    assert abs(total[0] - load) <= 4 * math.ulp(0.25)
    assert np.abs(total - load).max() <= 1e-9


def test_a_load_beyond_the_summed_yield_force_is_not_held():
    # load 0.225 + d: both slip, m v' = d - 2 v (gamma = 1): v = d (1 - exp(-2 t)) / 2
    d = 0.025
    sol = simulate(_two_dashpots(0.225 + d), method="radau5", t_end=0.5, rtol=1e-9,
                   atol=1e-12)
    assert sol.ok
    t = sol.t
    assert np.abs(sol.v["m"] - 0.5 * d * (1.0 - np.exp(-2.0 * t))).max() <= 1e-8
    x_exact = 0.5 * d * (t - 0.5 * (1.0 - np.exp(-2.0 * t)))
    assert np.abs(sol.x["m"] - x_exact).max() <= 1e-8
