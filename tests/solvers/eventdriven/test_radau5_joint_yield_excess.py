"""``radau5`` at ``rtol = 1e-10`` on one mass held by three yield dashpots to ground under
a constant load at or just beyond the sum of their yield forces (issue 29: the 1960th
draw of the ``LUMPED_LARGE`` tight-tolerance property, written out).

The draw's load, ``1.0606024904529736``, lies ``2.52e-15`` (``11 eps``) beyond the sum of
the yield forces, above the round-off of the mass's balance ``4 eps (|f| + sum |F|) =
1.9e-15``: the dashpots slip together, the shear-thickening one (Herschel-Bulkley ``n =
2``) taking the excess at the rate ``v* ~ gamma delta^2`` (``6e-30`` m/s). The mode probe
read them stuck, no split within their yield forces balanced the load, and the run crept
by steps of ``1e-15`` s and stopped after 12 backward-Euler bridges
(:func:`lumped.solvers.modes.force_bounds.slip_beyond_joint_bounds`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _joint_yield import ATOL, DT, GAMMA_HB2, JOINT, PERMUTATIONS, RTOL, T_END, TAUS, X0
from _joint_yield import joint_yield_scene as _scene

from lumped import simulate


def _run(load: float, order: tuple[int, ...]):
    sol = simulate(_scene(load, order), method="radau5", dt=DT, t_end=T_END, rtol=RTOL,
                   atol=ATOL, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    return sol


def _within_yield(sol, order: tuple[int, ...]) -> None:
    # every force within its yield force but for the slip's excess (at most ``delta``
    # beyond), to the forces' tolerance
    for k, i in enumerate(order):
        F = np.asarray(sol.F[f"e{k}"])
        assert np.all(F >= -TAUS[i]), (k, F.min())
        assert np.all(F <= TAUS[i] + 1e-9 + RTOL * JOINT), (k, F.max())


@pytest.mark.parametrize("order", PERMUTATIONS)
def test_a_load_eleven_eps_beyond_the_joint_yield_force_slips_without_creeping(order):
    """The draw: the run goes through in a few steps (it stopped after 12 bridges) and the
    mass stays within the exact motion's bound: the shear-thickening dashpot carries at
    most the excess ``delta``, so ``|v| <= gamma delta^2`` and ``|x - x0| <= gamma delta^2
    t``, plus what the velocity tolerance allows over the run (``atol t``)."""
    load = 1.0606024904529736
    sol = _run(load, order)
    assert sol.stats["steps"] <= 40, sol.stats
    delta = 2.53e-15  # the exact excess, 2.5222879e-15, rounded up
    bound = GAMMA_HB2 * delta**2 * T_END + ATOL * T_END
    assert np.max(np.abs(np.asarray(sol.x["m0"]) - X0)) <= bound
    _within_yield(sol, order)


@pytest.mark.parametrize("order", PERMUTATIONS)
def test_a_load_1e9_beyond_the_joint_yield_force_slips_at_its_rate(order):
    """``1e-9`` beyond (above the forces' tolerance): it slips visibly, the
    shear-thickening dashpot at ``tau + delta`` and the mass at ``v* = gamma delta^2``
    (the others' share, ``v* / gamma``, is below their forces' round-off); it read stuck
    before and crept likewise. The displacement agrees with ``bdf2`` at ``dt / 2`` within
    that run's own error (its distance to the run at ``dt``) and the velocity tolerance
    over the run."""
    load = JOINT * (1.0 + 1e-9)
    sol = _run(load, order)
    delta = load - JOINT
    hb2 = f"e{order.index(2)}"
    assert sol.F[hb2][-1] - TAUS[2] == pytest.approx(delta, rel=1e-6)
    assert sol.v["m0"][-1] == pytest.approx(GAMMA_HB2 * delta**2, rel=1e-6)
    fine, finer = (simulate(_scene(load, order), method="bdf2", dt=DT / k, t_end=T_END)
                   for k in (1, 2))
    ref = np.asarray(finer.x["m0"])[::2]
    own = np.max(np.abs(np.asarray(fine.x["m0"]) - ref))
    assert np.max(np.abs(np.asarray(sol.x["m0"]) - ref)) <= own + ATOL * T_END
    _within_yield(sol, order)


@pytest.mark.parametrize("excess", [0.0, 1.0, 4.0, -4.0])
def test_a_load_within_round_off_of_the_joint_yield_force_holds(excess):
    """Within the balance's round-off of the joint yield force (``k`` ulp of it, either
    side): the mass is held, each force on its yield force, with no step and no
    bridge."""
    load = JOINT + excess * math.ulp(JOINT)
    sol = _run(load, (0, 1, 2))
    assert np.max(np.abs(np.asarray(sol.x["m0"]) - X0)) <= 1e-30
    _within_yield(sol, (0, 1, 2))
