"""Regressions of ``radau5`` from issue 11 (session 3): a tangential break-out that
chattered, hard points of a law (Herschel-Bulkley ``n < 1``), and networks drawn by the
random-network property suite (``tests/solvers/test_random_networks.py``) that used to
stop; each checks the property it broke directly."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.scene.forcing import SineBurst


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


def _hb_stop_exact(t: np.ndarray, tau: float, v0: float) -> tuple[np.ndarray, np.ndarray]:
    """A unit mass on a Herschel-Bulkley dashpot (gamma = 1, n = 1/2) to ground, sliding
    at ``v0 > 0``: ``F = tau + v^2``, so ``v' = -(tau + v^2)`` and, with ``a = sqrt(tau)``,
    ``phi = atan(v0 / a)``: ``v = a tan(phi - a t)``, ``x = log(cos(phi - a t) / cos(phi))``
    until ``v = 0`` at ``t* = phi / a``; then it sticks (no load: ``|F| = 0 <= tau``)."""
    a = np.sqrt(tau)
    phi = np.arctan(v0 / a)
    s = np.minimum(t, phi / a)
    return np.log(np.cos(phi - a * s) / np.cos(phi)), a * np.tan(phi - a * s)


@pytest.mark.parametrize("compiled", [True, False])
def test_herschel_bulkley_below_one_against_its_exact_stop(compiled: bool) -> None:
    # n < 1: dq/dF is infinite at the yield force, where the slip ends. radau5 used to
    # refuse the scene; the slip branch is now solved in its inverse form F = tau + (q /
    # gamma)^(1/n), read from the law's expression (BranchInfo.stage)
    tau, v0 = 0.25, 1.0
    scene = Scene([Mass("m", m=1.0, v0=v0)],
                  [Element("d", get_law("herschel_bulkley").bind(gamma=1.0, tau=tau, n=0.5),
                           "ground", "m")])
    sol = simulate(scene, method="radau5", t_end=3.0, rtol=1e-8, atol=1e-11,
                   compiled=compiled)
    assert sol.ok, sol.message
    x, v = _hb_stop_exact(sol.t, tau, v0)
    assert np.abs(sol.x["m"] - x).max() <= 1e-6
    assert np.abs(sol.v["m"] - v).max() <= 1e-6
    (stop,) = [ev for ev in sol.events if ev.element == "d"]
    assert abs(stop.t - np.arctan(v0 / np.sqrt(tau)) / np.sqrt(tau)) <= 1e-8
    assert np.all(sol.v["m"][sol.t > stop.t] == 0.0)  # stuck exactly


@pytest.mark.parametrize("n", [0.3, 0.8])
def test_herschel_bulkley_below_one_loops_agree(n: float) -> None:
    # the compiled loop takes the inverse form from the generated module: the same numbers
    scene = Scene([Mass("m", m=1.0, x0=0.2, v0=1.0)],
                  [Element("d", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.5, n=n),
                           "ground", "m"),
                   Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m")],
                  {"m": SineBurst(3.0, 2 * math.pi, 3.0)})
    ours = simulate(scene, method="radau5", t_end=2.0, rtol=1e-7, compiled=False)
    compiled = simulate(scene, method="radau5", t_end=2.0, rtol=1e-7, compiled=True)
    assert ours.ok and compiled.ok
    assert compiled.stats.pop("loop") == "compiled"
    ours.stats.pop("loop")
    assert np.array_equal(compiled.data, ours.data) and compiled.stats == ours.stats
    assert len(ours.events) >= 3
