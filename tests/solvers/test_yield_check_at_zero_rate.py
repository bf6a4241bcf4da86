"""The yield check of the property suite (``tests/_yield_check.py``) at a rate of exactly
zero: a Herschel-Bulkley ``n = 2`` dashpot that slips at a rate a parallel lock holds at
zero carries its yield force only to the rounding of the velocities (seed 23009 of the
tight run, issue 29: ``8.1e-9`` above ``tau`` at ``rtol = 1e-10``), while a stuck
dashpot well above ``tau`` still fails the check."""

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
