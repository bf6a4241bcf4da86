"""The stop of a junction's dashpot taken within the tolerances
(:func:`lumped.solvers.modes.finite_stop.stop_within_tolerance`), on its own: a junction
``j1`` between a Herschel-Bulkley ``n = 0.8`` dashpot to ground and a linear spring to
ground, a force ``delta`` short of the yield force (``F = -k x_j``, yield at ``x_j = tau /
k``)."""

from __future__ import annotations

import math

import pytest

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven.setup import scene_plan
from lumped.solvers.modes.finite_stop import stop_within_tolerance

K, TAU = 10.0, 0.1
SLIP, STUCK = 1, 2  # the Herschel-Bulkley law's negative slip branch and its stuck one
_EPS = 2.220446049250313e-16


def _scene(beside: str | None = None) -> Scene:
    elements = [Element("e0", get_law("linear_spring").bind(k=1.0), "ground", "m0"),
                Element("e1", get_law("herschel_bulkley").bind(gamma=10.0, tau=TAU, n=0.8),
                        "ground", "j1"),
                Element("e2", get_law("linear_spring").bind(k=K), "j1", "ground")]
    if beside:
        elements.append(Element("e3", get_law(beside).bind(c=1.0), "j1", "ground"))
    return Scene([Mass("m0", m=1.0), Junction("j1", x0=0.0)], elements)


def _state(scene: Scene, delta: float):
    """``(x, v, F, modes)``: the junction ``delta / k`` past its stop, at rest, slipping."""
    xj = (TAU + delta) / K
    F = [0.0, -K * xj, -K * xj] + [0.0] * (len(scene.elements) - 3)
    modes = [0, SLIP, 0] + [0] * (len(scene.elements) - 3)
    return [0.0, xj], [0.0, 0.0], F, modes


def _try(scene: Scene, delta: float, tol_F: float = 1e-6, tol_x: float = 1e-6):
    x, v, F, modes = _state(scene, delta)
    branches = scene_plan(scene).branches
    taken = stop_within_tolerance(scene, branches, modes, 1, 0.0, x, v, F, 1e-9, tol_F, tol_x)
    return taken, x, v, F, modes


@pytest.mark.parametrize("delta", [6e-13, 1e-9, 1e-7])
def test_the_stop_is_taken_within_the_tolerances(delta: float) -> None:
    """The junction moves to ``tau / k`` (to round-off), the dashpot's force is its yield
    force, the spring's its law's there, and the dashpot is held stuck."""
    taken, x, v, F, modes = _try(_scene(), delta)
    assert taken
    assert modes[1] == STUCK
    assert F[1] == -TAU
    assert math.isclose(x[1], TAU / K, rel_tol=8 * _EPS)
    assert math.isclose(F[2], -K * x[1], rel_tol=8 * _EPS)
    assert abs(F[1] - F[2]) <= 8 * _EPS * TAU  # the junction's balance
    assert v[1] == 0.0


@pytest.mark.parametrize("case", ["force beyond tol_F", "move beyond tol_x", "a dashpot beside"])
def test_no_stop_outside_its_premises(case: str) -> None:
    """Nothing is changed when the force is further from the yield force than ``tol_F``,
    the junction would move by more than ``tol_x``, or another dashpot at the junction
    takes part of its balance (its force is not the springs')."""
    scene = _scene("newtonian" if case == "a dashpot beside" else None)
    delta = 1e-7
    before = _state(scene, delta)
    taken, x, v, F, modes = _try(scene, delta, tol_F=1e-8 if case == "force beyond tol_F"
                                 else 1e-6, tol_x=1e-9 if case == "move beyond tol_x"
                                 else 1e-6)
    assert not taken
    assert (x, v, F, modes) == before
