"""``radau5`` at ``rtol = 1e-10`` on one mass held by three yield dashpots to ground under
a constant load just *within* the sum of their yield forces (issue 29, the converse of
``test_radau5_joint_yield_excess.py``, whose scene this is).

The exact motion for every load within the joint yield force: the mass never moves and
every force stays within its yield band (the split among them is not unique). The steps
did not keep a split there before it was solved to round-off (``eps m / h`` before,
:func:`lumped.solvers.radau.cone_split.cone_solver`): a force landed past its yield
force, the stage's active set held it ``1e-6`` of its half-width inside, and the others
could not carry the rest; loads ``1e-12`` and ``1e-9``
(of the joint yield force) inside crept and stopped after 12 backward-Euler bridges
(:func:`lumped.solvers.modes.force_bounds.split_near_joint_bounds`)."""

from __future__ import annotations

import numpy as np
import pytest
from _joint_yield import (
    ATOL,
    DT,
    JOINT,
    PERMUTATIONS,
    RTOL,
    T_END,
    TAUS,
    X0,
    M,
    joint_yield_laws,
    joint_yield_scene,
)

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene


def _assert_held(sol, order: tuple[int, ...], x0: float) -> None:
    """``ok``, no bridge, a bounded step count, the mass within what the velocity
    tolerance allows over the run (``atol t_end``), every force within its yield band to
    the forces' tolerance (``rtol`` of the joint yield force)."""
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.stats["steps"] <= 40, sol.stats
    assert np.max(np.abs(np.asarray(sol.x["m0"]) - x0)) <= ATOL * T_END
    for k, i in enumerate(order):
        F = np.asarray(sol.F[f"e{k}"])
        assert np.all(np.abs(F) <= TAUS[i] + RTOL * JOINT), (k, np.abs(F).max() - TAUS[i])


@pytest.mark.parametrize("order", PERMUTATIONS)
@pytest.mark.parametrize("inside", [1e-12, 1e-10, 1e-9])
def test_a_load_just_within_the_joint_yield_force_holds_without_creeping(inside, order):
    """Loads ``1e-12``, ``1e-10`` and ``1e-9`` of the joint yield force inside it, each law
    order: held (``1e-12`` and ``1e-9`` crept and stopped after 12 bridges, ``1e-10`` took
    10 bridges), and the forces carry the load (the mass's balance) to ``rtol``."""
    load = JOINT * (1.0 - inside)
    sol = simulate(joint_yield_scene(load, order), method="radau5", dt=DT, t_end=T_END, rtol=RTOL,
                   atol=ATOL, compiled=False)
    _assert_held(sol, order, X0)
    # (the row at t = 0 is the consistent initial state's, to its Newton's tolerance)
    total = sum(np.asarray(sol.F[f"e{k}"]) for k in range(3))
    assert abs(total[0] - load) <= 10.0 * RTOL * JOINT
    assert np.all(np.abs(total[1:] - load) <= RTOL * JOINT)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_load_just_within_beside_a_stretched_spring_holds(sign):
    """The group beside a spring to the node that carries part of the load (``k x0``),
    the rest ``1e-9`` within the joint yield force either way; the compiled driver too
    (it runs the Python loop for locks in parallel)."""
    k, x0 = 10.0, 0.01
    load = sign * JOINT * (1.0 - 1e-9) + k * x0
    scene = joint_yield_scene(load, spring=k, x0=x0)
    sol = simulate(scene, method="radau5", dt=DT, t_end=T_END, rtol=RTOL, atol=ATOL,
                   compiled=True)
    _assert_held(sol, (0, 1, 2), x0)


@pytest.mark.parametrize("inside", [1e-12, 1e-9])
def test_the_group_between_two_masses_holds(inside):
    """The three dashpots between two masses, the first held to ground by a spring
    stretched to carry the load on the second, ``inside`` within the joint yield force:
    nothing moves (``1e-12`` crept and stopped after 12 bridges at ``t = 0.006``)."""
    k, load = 100.0, JOINT * (1.0 - inside)
    elements = [Element(f"e{i}", law, "mA", "m0") for i, law in enumerate(joint_yield_laws())]
    elements.append(Element("s", get_law("linear_spring").bind(k=k), "ground", "mA"))
    scene = Scene([Mass("mA", m=1.0, x0=load / k), Mass("m0", m=M, x0=load / k)],
                  elements, {"m0": load})
    sol = simulate(scene, method="radau5", dt=DT, t_end=T_END, rtol=RTOL, atol=ATOL,
                   compiled=False)
    _assert_held(sol, (0, 1, 2), load / k)
    assert np.max(np.abs(np.asarray(sol.x["mA"]) - load / k)) <= ATOL * T_END
