"""The yield check of the property suite (``tests/_yield_check.py``) at a rate of exactly
zero, where a parallel stuck dashpot holds it (a free split; issue 29). An adaptive run: a
Herschel-Bulkley ``n = 2`` dashpot slipping at that rate carries its yield force only to
the rounding of the velocities (seed 23009 of the tight run: ``8.1e-9`` above ``tau`` at
``rtol = 1e-10``). A fixed-step run: its law's residual is within Newton's tolerance,
whose scale for a rate holds the velocities it is the difference of (seed 24004 of
``bdf1``'s property). A stuck dashpot well above ``tau`` still fails the check."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest
from _yield_check import check_yield

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

GAMMA, TAU = 0.9046886471689398, 0.03723684534337339
V = -1.046363828223289  # both ends' velocity: the rate is exactly zero


def _scene() -> Scene:
    hb = get_law("herschel_bulkley").bind(gamma=GAMMA, tau=TAU, n=2.0)
    bingham = get_law("bingham").bind(gamma=0.3, tau=0.15)
    return Scene([Junction("j2"), Mass("m1", m=1.0, v0=V)],
                 [Element("e5", bingham, "j2", "m1"), Element("e6", hb, "j2", "m1"),
                  Element("e0", get_law("linear_spring").bind(k=1.0), "ground", "j2")])


def _solution(F6: float) -> SimpleNamespace:
    """One sample: ``e6`` at ``F6``, the rate ``v_m1 - v_j2`` exactly zero."""
    F = {"e5": np.array([-0.0433]), "e6": np.array([F6]), "e0": np.array([-0.2823])}
    v = {"j2": np.array([V]), "m1": np.array([V])}
    return SimpleNamespace(v=v, F=F, forces=np.array([[F["e5"][0], F6, F["e0"][0]]]))


def test_a_force_within_the_rounding_of_a_zero_rate_passes():
    """``8.1e-9`` above ``tau``: the rate it gives, ``gamma (8.1e-9)^2 = 6e-17``, is below
    the rounding of the velocities (``4 eps 2|v| = 1.9e-15``)."""
    check_yield(_scene(), _solution(TAU + 8.097835679787835e-09), 1e-8, 1e-13 + 1e-10, 1e-10)


@pytest.mark.parametrize("excess", [1e-6, 1e-4])
def test_a_stuck_dashpot_above_its_yield_force_fails(excess):
    """``1e-6`` above ``tau`` gives a rate of ``9e-13``, far above that rounding."""
    with pytest.raises(AssertionError, match="e6 stuck above its yield force"):
        check_yield(_scene(), _solution(TAU + excess), 1e-8, 1e-13 + 1e-10, 1e-10)


def _free_split(F1: float) -> tuple[Scene, SimpleNamespace]:
    """Seed 24004 of ``bdf1``'s property at its event (``t = 0.068``): a Herschel-Bulkley
    ``n = 1.5`` dashpot ``e1`` beside a stuck Bingham dashpot ``e5`` between two masses
    moving together at ``1.85``, ``e1`` at ``F1``."""
    hb = get_law("herschel_bulkley").bind(gamma=1.0, tau=0.1, n=1.5)
    bingham = get_law("bingham").bind(gamma=0.1, tau=1.0)
    scene = Scene([Mass("m0", m=1.0, v0=2.0), Mass("m1", m=1.0, v0=2.0)],
                  [Element("e1", hb, "m0", "m1"), Element("e5", bingham, "m0", "m1")])
    F = {"e1": np.array([F1]), "e5": np.array([0.1037])}
    v = {"m0": np.array([1.85]), "m1": np.array([1.85])}
    return scene, SimpleNamespace(v=v, F=F, forces=np.array([[F1, 0.1037]]))


def test_a_fixed_step_residual_within_newtons_tolerance_passes():
    """Newton's row scale for a rate holds the velocities it is the difference of
    (``|v_a| + |v_b| = 3.7``): ``1.75e-7`` above ``tau`` is a residual of ``7.3e-11``,
    within its tolerance ``1e-10 * 3.7 + 1e-12``."""
    check_yield(*_free_split(0.1 + 1.7474048192e-07))


def test_a_fixed_step_residual_beyond_newtons_tolerance_fails():
    """``1e-5`` above ``tau``: a residual of ``3.2e-8``, 40 times that tolerance."""
    with pytest.raises(AssertionError, match="e1 stuck above its yield force"):
        check_yield(*_free_split(0.1 + 1e-5))
