"""Coulomb elements and Bingham dashpots on a cycle through junctions (draws of
``tests/solvers/test_random_networks.py`` at ``LUMPED_LARGE=1000``).

Two Coulomb elements in series through a junction (:func:`series_scene`):
Once both Coulomb elements slip, the junction between them carries equal forces at their
common bound and its velocity is left free by the laws (any split of the slip between
the two): the stage Jacobian is singular. The Python loop solves it by the minimum-norm
correction; ``compiled=True`` must hand such an attempt to that same solve and give the
same run, bit for bit (it failed the step instead and took another mode).

A stuck cycle (:func:`stuck_cycle_scene`): everything moves as one and the load through
``j0`` splits between the Coulomb ``e1`` and the path ``e2``-``e3``, a split the laws
leave free; the stage rule gives ``e1`` two thirds of it until it meets its bound
``tau = 1`` inside a step, and holds it there. The collocation cubic through that kink
overshot the bound on the dense output (``|F_e1| = 1.000335`` at ``t = 0.1375``, above
the ``rtol`` of the random networks' test); the dense output now keeps the locks' forces
in their intervals along the cycle, every node's balance kept.
"""

from __future__ import annotations

import numpy as np
import pytest
from _yield_check import check_yield

from lumped import Element, Junction, Mass, Scene, get_law, simulate

#: the grid of the draw (``grid`` of the random networks at its middle level)
DT, T_END = 0.0125, 0.5
LOAD = 12.649110640673518


def _bingham(gamma: float):
    return get_law("bingham").bind(gamma=gamma, tau=1.0)


def _coulomb(r: float):
    return get_law("coulomb").bind(tau=1.0, r=r)


def _cycle(*links) -> Scene:
    """``e0`` (Bingham, ground -> j0), then ``e1, e2, ...`` of ``links`` ``(law, a, b)``."""
    nodes = [Junction("j0", x0=0.0), Mass("m1", m=1.0, x0=1.0, v0=1.375),
             Junction("j2", x0=1.0)]
    return Scene(nodes, [Element("e0", _bingham(5.623413251903491), "ground", "j0")] + [
        Element(f"e{k + 1}", law, a, b) for k, (law, a, b) in enumerate(links)], {"m1": LOAD})


def series_scene() -> Scene:
    """e2, e3: Coulomb in series through j2, in parallel with the Bingham e1."""
    return _cycle((_bingham(1.0), "j0", "m1"), (_coulomb(1.0), "j0", "j2"),
                  (_coulomb(10.0), "j2", "m1"))


def _run(scene: Scene, compiled: bool):
    return simulate(scene, method="radau5", t_end=T_END, dt=DT, rtol=DT**2, atol=DT**3,
                    compiled=compiled, throw=False)


def test_a_junction_between_slipping_coulomb_elements_gives_one_run_in_both_loops():
    """``compiled=True`` takes the compiled stage Newton (run as Python where numba is
    off: the same code), which has no minimum-norm solve; at the singular stage Jacobian
    of a free junction it must hand the attempt to Python's, as the compiled loop does."""
    scene = series_scene()
    a, b = _run(scene, False), _run(scene, True)
    assert a.success and b.success
    assert a.stats["steps"] == b.stats["steps"]
    assert np.array_equal(a.data, b.data)
    assert [(e.t, e.element, e.kind) for e in a.events] == \
        [(e.t, e.element, e.kind) for e in b.events]


def test_the_free_junction_stays_between_its_neighbours_while_both_slip():
    """Whatever split of the slip the run picks, ``e2`` and ``e3`` carry one force at
    their bound and neither runs backwards: ``v_j0 <= v_j2 <= v_m1`` to the tolerance."""
    s = _run(series_scene(), False)
    assert s.success
    tol = 10 * DT**2 * max(1.0, float(np.abs(s.data).max()))
    late = s.t > 0.39  # (after the yield near t = 0.3854)
    assert late.any()
    F2, F3 = s.F["e2"][late], s.F["e3"][late]
    assert np.all(np.abs(F2 - F3) <= tol) and np.all(np.abs(np.abs(F2) - 1.0) <= tol)
    v0, v1, v2 = s.v["j0"][late], s.v["m1"][late], s.v["j2"][late]
    assert np.all(v0 - tol <= v2) and np.all(v2 <= v1 + tol)


def stuck_cycle_scene() -> Scene:
    """e1: Coulomb j0 -> m1, in parallel with the stuck path e2 (Bingham), e3 (Coulomb)."""
    return _cycle((_coulomb(1.0), "j0", "m1"), (_bingham(1.0), "j0", "j2"),
                  (_coulomb(10.0), "m1", "j2"))


@pytest.mark.parametrize("compiled", [False, True])
def test_a_stuck_cycle_keeps_its_coulomb_force_within_the_bound_on_the_dense_output(compiled):
    scene = stuck_cycle_scene()
    s = _run(scene, compiled)
    assert s.success
    # the random networks' test: Coulomb forces within rtol of the forces' scale
    v_max = float(np.abs(s.data[:, 2:1 + 2 * len(scene.nodes):2]).max())
    check_yield(scene, s, min(1e-3, 100.0 * DT**2), DT**3 + DT**2 * v_max, DT**2)
    # (the draw: 1.000335 at t = 0.1375; held in [-1, 1] now, also between nodes)
    assert np.abs(s.F["e1"]).max() <= 1.0 + 1e-12
    # the balance of the massless junctions, which the correction keeps
    scale = 1.0 + float(np.abs(s.F["e0"]).max())
    F = s.F
    assert np.allclose(F["e1"] + F["e2"], F["e0"], rtol=0.0, atol=DT**2 * scale)
    assert np.allclose(F["e2"], -F["e3"], rtol=0.0, atol=DT**2 * scale)
