"""``radau5`` at ``rtol = 1e-10`` on one mass held by three yield dashpots to ground
(the scene of ``test_radau5_joint_yield_excess.py``) under a sine burst whose peak lies
``1e-12`` to ``1e-7`` (relative) beyond the sum of their yield forces, switched off at
that peak (issue 29).

The exact motion: stuck until the peak, a slip of ``v ~ gamma delta^2`` (at most
``1e-14`` m/s) at the peak, and at ``t_off`` the load falls inside the joint yield force
(to ``0``, or to a constant offset), where the mass stops at once and stays stuck. The
mode chosen at ``t_off`` read the load at ``t_off`` itself, the peak, and sent the group
(read stuck by the probe under the load after the jump) to slip on: every step failed and
the run stopped on its work budget, in every law order
(:func:`lumped.solvers.modes.force_bounds.slip_beyond_joint_bounds`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _joint_yield import ATOL, GAMMA_HB2, JOINT, PERMUTATIONS, RTOL, TAUS, M, joint_yield_laws

from lumped import simulate
from lumped.scene import Element, Mass, Scene, SineBurst

OMEGA = 4.0 * math.pi
T_OFF = 0.125  # (the burst's peak: sin(OMEGA T_OFF) = 1)
T_END = 0.3
DT = T_END / 48


class _PeakThenOffset:
    """``c + a sin(OMEGA t)`` up to its peak ``c + a`` at ``T_OFF``, then ``c - a`` (a
    burst on a constant offset, switched off at its peak)."""

    def __init__(self, peak: float, a: float) -> None:
        self.peak, self.a = peak, a

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        return [T_OFF] if t0 < T_OFF < t1 else []

    def __call__(self, t: float) -> float:
        if t <= T_OFF:
            return self.peak - self.a + self.a * math.sin(OMEGA * t)
        return self.peak - 2.0 * self.a


def _run(forcing, order: tuple[int, ...]):
    laws = joint_yield_laws()
    elements = [Element(f"e{k}", laws[i], "ground", "m0") for k, i in enumerate(order)]
    scene = Scene([Mass("m0", m=M)], elements, {"m0": forcing})
    sol = simulate(scene, method="radau5", dt=DT, t_end=T_END, rtol=RTOL, atol=ATOL,
                   compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) <= 1, sol.message
    assert sol.stats["steps"] <= 120, sol.stats
    return sol


def _stuck_after_the_burst(sol, order: tuple[int, ...], beyond: float, after: float) -> None:
    """The mass moved at most what the slip at the peak and the velocity tolerance allow;
    after ``T_OFF`` it is at rest, every force within its yield band (to the forces'
    tolerance) and their sum the load ``after`` (to the same)."""
    delta = beyond * JOINT
    t = np.asarray(sol.t)
    assert np.max(np.abs(np.asarray(sol.x["m0"]))) <= GAMMA_HB2 * delta**2 * T_END + ATOL * T_END
    late = t > T_OFF + 1e-9
    assert np.all(np.abs(np.asarray(sol.v["m0"])[late]) <= ATOL)
    total = np.zeros(int(late.sum()))
    for k, i in enumerate(order):
        F = np.asarray(sol.F[f"e{k}"])[late]
        assert np.all(np.abs(F) <= TAUS[i] + RTOL * JOINT), (k, np.abs(F).max() - TAUS[i])
        total += F
    assert np.all(np.abs(total - after) <= RTOL * JOINT)


@pytest.mark.parametrize("order", PERMUTATIONS)
def test_a_burst_switched_off_just_beyond_the_joint_yield_force(order):
    """A sine burst whose peak is ``1e-12`` beyond the joint yield force, switched off
    there: the group sticks again under the load ``0`` (each order stopped on its work
    budget near ``t = 0.126``, or took a bridge)."""
    sol = _run(SineBurst(JOINT * (1.0 + 1e-12), OMEGA, T_OFF), order)
    _stuck_after_the_burst(sol, order, 1e-12, 0.0)


@pytest.mark.parametrize("beyond", [1e-9, 1e-7])
def test_a_burst_switched_off_further_beyond(beyond):
    """Peaks ``1e-9`` and ``1e-7`` beyond: the slip at the peak is visible in ``x``
    (``~1e-24`` and ``1e-19`` m) and the mass sticks at ``t_off``."""
    sol = _run(SineBurst(JOINT * (1.0 + beyond), OMEGA, T_OFF), (0, 1, 2))
    _stuck_after_the_burst(sol, (0, 1, 2), beyond, 0.0)


def test_a_burst_on_an_offset_switched_off_beyond():
    """A burst on a constant offset (a callable the static hold does not take) peaking
    ``1e-9`` beyond the joint yield force, then the offset ``0.2`` of it below its peak:
    stuck on."""
    a = 0.1 * JOINT
    peak = JOINT * (1.0 + 1e-9)
    sol = _run(_PeakThenOffset(peak, a), (0, 1, 2))
    _stuck_after_the_burst(sol, (0, 1, 2), 1e-9, peak - 2.0 * a)
