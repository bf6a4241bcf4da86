"""The split of the stage solve among stuck dashpots in parallel
(:func:`lumped.solvers.radau.cone_split.cone_solver`) under a load ``1e-9`` (relative)
within their joint yield force: the rule's split, in proportion to the half-widths, puts
each force ``1e-9`` of its yield force inside its bound, and the solve must keep it there
at every step size (issue 29). The momentum rows carry ``m / h`` on the velocities beside
``1`` on the forces: left in one SVD, the split came out to its round-off, ``eps m / h``,
up to ``5e-5`` of a yield force on short steps."""

from __future__ import annotations

import pytest
from _joint_yield import JOINT, TAUS, M

from lumped.solvers.radau.stage import StageSystem

LOAD = JOINT * (1.0 - 1e-9)
#: Each force's distance from the rule's split allowed, as a fraction of its yield force:
#: 1 % of the load's margin (the solve's round-off is ``1e-15``).
SPLIT_TOL = 1e-11
CONES = {e: (0.0, tau, -tau, tau) for e, tau in enumerate(TAUS)}


def _stuck(q: float, F: float) -> tuple[float, float, float]:
    """The stuck branch of a yield dashpot: ``R = q``."""
    return q, 1.0, 0.0


def _assert_rule_split(U: list[float], first: int, n: int) -> None:
    for k in range(3):
        for e, tau in enumerate(TAUS):
            share = U[k * n + first + e] / tau
            assert abs(share - LOAD / JOINT) <= SPLIT_TOL, (k, e, share - LOAD / JOINT)


@pytest.mark.parametrize("h", [1e-6, 1e-9, 1e-12])
def test_a_mass_at_rest_on_stuck_dashpots_to_ground_is_split_by_the_rule(h):
    """A stuck dashpot to ground pins the velocity (``V = 0``, a row of one entry): its
    column is taken out of the momentum rows before the split (at ``h = 1e-12`` the split
    was ``5e-5`` of the Bingham dashpot's yield force off, each short step read a guard
    crossed at once)."""
    rtol, atol = 1e-10, 1e-13
    system = StageSystem([M], [-1] * 3, [0] * 3, [False] * 3)
    f_ref = max(LOAD, M * atol / rtol / h)  # (the run's force scale, Radau5Run.attempt)
    scale = ([atol] + [rtol * f_ref] * 3) * 3
    U = ([0.0] + list(TAUS)) * 3  # (from every force on its bound, as after a probe)
    got, _, _ = system.solve(U, h, [0.0], [0.0], [[LOAD]] * 3, [_stuck] * 3, scale,
                             cones=CONES)
    assert got is not None
    _assert_rule_split(U, 1, 4)


@pytest.mark.parametrize("h", [1e-6, 1e-8, 1e-10])
def test_a_group_between_two_moving_masses_is_split_by_the_rule(h):
    """Between two free masses moving together (``v = 3.6e-5``) the velocities are the
    masses' own unknowns: their columns are scaled to the forces' before the split (the
    split was up to ``1e-5`` of a yield force off at ``h = 1e-10``)."""
    rtol, atol, v = 1e-6, 1e-9, 3.6e-5
    f = LOAD * (1.0 + M)  # (on the second mass; the group carries f m_A / (m_A + m))
    system = StageSystem([1.0, M], [0] * 3, [1] * 3, [False] * 3)
    f_ref = max(f, M * (v + atol / rtol) / h)
    scale = ([atol + rtol * v] * 2 + [rtol * f_ref] * 3) * 3
    U = ([v, v] + list(TAUS)) * 3
    got, _, _ = system.solve(U, h, [0.0, 0.0], [v, v], [[0.0, f]] * 3, [_stuck] * 3, scale,
                             cones=CONES)
    assert got is not None
    _assert_rule_split(U, 2, 5)
