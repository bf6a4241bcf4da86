"""The stage Newton's test of a junction's velocity at the round-off of its laws
(:mod:`lumped.solvers.radau.roundoff`), and its compiled twin, bit for bit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped.solvers.newton.criteria import ROUNDOFF
from lumped.solvers.radau.roundoff import (
    junction_columns,
    linked_balances,
    linked_roundoff,
    rate_rows,
    roundoff_worst,
)
from lumped.solvers.radau.roundoff_jit import roundoff_worst_jit

# a mass (node 0) and a junction (node 1) on one element (n = 3 unknowns a stage, 9 in
# all): the junction's balance row at each stage holds the element's force, the
# element's row the junction's velocity with the small coefficient of a law flat in it
# (an inverse form F - tau - (q / gamma)^(1/n) near its stop: dG/dq = 1e-3) and its
# force with 1
MASSES = [1.0, 0.0]
SPRING = [False]
N_UNK = 3
TOL = 1e-3


def _system():
    size = 3 * N_UNK
    J = np.eye(size)
    for k in range(3):
        J[k * N_UNK + 1, k * N_UNK + 1] = 0.0
        J[k * N_UNK + 1, k * N_UNK + 2] = 1.0
        J[k * N_UNK + 2, k * N_UNK + 1] = -1e-3
    U = np.array([0.5, 0.04, 0.03] * 3)
    scale = np.array([1e-13 + 1e-10 * 0.5, 1e-13 + 1e-10 * 0.04, 1e-10 * 0.03] * 3)
    return J, U, scale


def _both(du, J, U, scale, spring=SPRING, masses=MASSES, f=None, after_impact=False, h=1.0):
    worst = float(np.max(np.abs(du) / scale))  # (the plain test, as the Newton finds it)
    n = len(U) // 3
    f = np.zeros((3, len(masses))) if f is None else f
    py = roundoff_worst(list(du), list(U), J.tolist(), list(scale),
                        junction_columns(masses, n), rate_rows(len(masses), spring), f.tolist(),
                        TOL, worst, h, after_impact)
    jit = roundoff_worst_jit(du, U, J, scale, np.array(masses), np.array(spring), f, TOL,
                             worst, h, after_impact)
    assert py == jit
    return py


def test_the_junction_columns_are_the_massless_nodes_velocities():
    assert junction_columns(MASSES, N_UNK) == [False, True, False] * 3
    assert rate_rows(2, SPRING) == [False, False, True] * 3
    assert rate_rows(2, [True]) == [False] * 9


def test_a_junction_velocity_correction_at_its_laws_round_off_is_converged():
    J, U, scale = _system()
    # the junction's velocity read from its law's row: ROUNDOFF (|F| + 1e-3 |v|) / 1e-3
    rho = ROUNDOFF * (0.03 + 1e-3 * 0.04) / 1e-3
    du = np.zeros(9)
    du[1 + N_UNK] = 0.5 * rho  # (1.3e-14: 3 times the plain test's 4e-15)
    assert abs(du[1 + N_UNK]) / scale[1 + N_UNK] > TOL
    assert _both(du, J, U, scale) == pytest.approx(0.5 * TOL, rel=1e-12)
    # ... beyond it, not
    du[1 + N_UNK] = 2.0 * rho
    assert _both(du, J, U, scale) > TOL


def test_a_springs_row_sets_the_floor_where_no_dashpots_row_holds_the_velocity():
    # a junction on springs alone (its Coulomb element slipping, a row flat in q): the
    # spring's row, F - F_n - h a k V, holds the velocity to its forces' rounding over
    # h a k; the same correction as a dashpot's row lets through is converged (issue 29)
    J, U, scale = _system()
    du = np.zeros(9)
    du[1 + N_UNK] = 0.5 * ROUNDOFF * (0.03 + 1e-3 * 0.04) / 1e-3
    assert abs(du[1 + N_UNK]) / scale[1 + N_UNK] > TOL
    assert _both(du, J, U, scale, spring=[True]) == pytest.approx(0.5 * TOL, rel=1e-12)
    # ... on the first step after an impact, also where so short that the springs'
    # rounding (ulp / (h a k)) is within the velocity's own tolerance
    assert _both(du, J, U, scale, spring=[True], after_impact=True) == pytest.approx(
        0.5 * TOL, rel=1e-12)


def test_a_springs_floor_beyond_the_velocitys_tolerance_holds_but_after_an_event():
    # a step so short that the springs' rounding (ulp / (h a k)) exceeds the velocity's
    # own tolerance: converged at that rounding (the velocity of an index-2 junction, read
    # on the positions it moves), except on the first step after an impact, where the
    # junction may still be jumping within the step (following an impact): not there
    J, U, scale = _system()
    for k in range(3):
        J[k * N_UNK + 2, k * N_UNK + 1] = -1e-9
    du = np.zeros(9)
    du[1 + N_UNK] = 0.5 * ROUNDOFF * (0.03 + 1e-9 * 0.04) / 1e-9
    assert ROUNDOFF * 0.03 / 1e-9 > scale[1 + N_UNK]
    worst = abs(du[1 + N_UNK]) / scale[1 + N_UNK]
    assert _both(du, J, U, scale, spring=[True], after_impact=True) == worst > TOL
    assert _both(du, J, U, scale, spring=[True]) == pytest.approx(0.5 * TOL, rel=1e-12)
    # ... and a correction beyond that rounding fails on any step (of size 1 here)
    du[1 + N_UNK] = 2.0 * ROUNDOFF * (0.03 + 1e-9 * 0.04) / 1e-9
    assert _both(du, J, U, scale, spring=[True]) > TOL


def test_a_velocity_held_by_springs_alone_is_read_on_the_positions_it_moves():
    # an index-2 velocity (springs' rows alone): its tolerance is scale / h on a step h < 1
    # (the positions it moves, h times it), beyond the springs' rounding, except on the
    # first step after an impact; a velocity a dashpot's row holds keeps its own
    J, U, scale = _system()
    du = np.zeros(9)
    du[1 + N_UNK] = 0.5 * TOL * scale[1 + N_UNK] / 1e-5
    # (beyond the springs' rounding, which the test lets through on any step)
    assert abs(du[1 + N_UNK]) > ROUNDOFF * (0.03 + 1e-3 * 0.04) / 1e-3 / TOL
    assert _both(du, J, U, scale, spring=[True], h=1e-5) == pytest.approx(0.5 * TOL,
                                                                          rel=1e-12)
    floor = ROUNDOFF * (0.03 + 1e-3 * 0.04) / 1e-3 / TOL  # (the row's rounding)
    floored = abs(du[1 + N_UNK]) / floor
    assert _both(du, J, U, scale, spring=[True], h=1e-5, after_impact=True) == pytest.approx(
        floored, rel=1e-12)
    assert floored > TOL
    assert _both(du, J, U, scale, spring=[False], h=1e-5) == pytest.approx(floored,
                                                                           rel=1e-12)
    # (no loosening on a step h > 1)
    assert _both(du, J, U, scale, spring=[True], h=2.0) == pytest.approx(floored, rel=1e-12)


def test_a_springs_row_sets_no_floor_beside_a_dashpots_row():
    # a spring's row holds the velocity through h A V: its rounding is the positions'
    # over h, which on a short step after an impact passes a junction velocity still
    # jumping: where a dashpot's row (dG/dq = 1e-3) holds the velocity too, it alone sets
    # the floor, not the spring's (dG/dq = 1, a floor 600 times lower)
    masses, spring, n = [1.0, 0.0], [False, True], 4
    J = np.eye(3 * n)
    U = np.zeros(3 * n)
    for k in range(3):
        b, r = k * n + 1, k * n + 2  # j's balance row (its velocity's column), e0's row
        J[b, b] = 0.0
        J[b, r], J[b, r + 1] = 1.0, 1.0
        J[r, b], J[r + 1, b] = -1e-3, -1.0
        U[k * n:(k + 1) * n] = [0.5, 0.04, 0.03, -0.03]
    scale = 1e-13 + 1e-10 * np.abs(U)
    rho = ROUNDOFF * (0.06 + 1e-3 * 0.04) / 1e-3  # (the balance's terms: 0.03 + 0.03)
    du = np.zeros(3 * n)
    du[n + 1] = 0.5 * rho
    assert _both(du, J, U, scale, spring, masses) == pytest.approx(0.5 * TOL, rel=1e-12)
    du[n + 1] = 2.0 * rho
    assert _both(du, J, U, scale, spring, masses) > TOL


def test_the_floor_is_the_junctions_alone():
    J, U, scale = _system()
    du = np.zeros(9)
    du[0] = 2.0 * TOL * scale[0]  # a mass's velocity: no floor
    assert _both(du, J, U, scale) == pytest.approx(2.0 * TOL, rel=1e-12)
    # ... and while another unknown fails, a junction's velocity keeps its plain test
    du[1] = 1e-14
    assert _both(du, J, U, scale) == pytest.approx(1e-14 / scale[1], rel=1e-12)


def test_a_dashpots_force_at_a_junction_carries_the_rounding_of_the_balance():
    # a mass (node 0) and a junction (node 1); e0 a Newtonian dashpot ground -> j (c =
    # 0.05), e1 a spring m -> j, e2 a spring j -> ground (n = 5 a stage): the springs'
    # forces 0.6 and 1.2 and a load 0.6 on the junction cancel at it to the dashpot's
    # F_e0 ~ 0 (0 = f + F_e0 + F_e1 - F_e2). Its velocity F_e0 / c carries ulp(1.2) / c,
    # not the rounding of the dashpot's row alone (|F_e0| + c |v| ~ 0): a correction of
    # 1e-15 is converged (issue 29: two strings at a junction on a dashpot)
    masses, spring, n, c = [1.0, 0.0], [False, True, True], 5, 0.05
    J = np.eye(3 * n)
    U = np.zeros(3 * n)
    f = np.zeros((3, 2))
    for k in range(3):
        b, r = k * n + 1, k * n + 2  # j's balance row (its velocity's column), e0's row
        J[b, b] = 0.0
        J[b, r], J[b, r + 1], J[b, r + 2] = 1.0, 1.0, -1.0
        J[r, b] = -c  # F - c v
        U[k * n:(k + 1) * n] = [0.3, 2e-17, 1e-18, 0.6, 1.2]
        f[k, 1] = 0.6
    scale = 1e-13 + 1e-10 * np.abs(U)
    du = np.zeros(3 * n)
    du[n + 1] = 1e-15
    # the plain test fails, and so would a floor read from the dashpot's row alone
    assert du[n + 1] / scale[n + 1] > TOL
    assert du[n + 1] > ROUNDOFF * (1e-18 + c * 2e-17) / c
    bal = 0.6 + 1e-18 + 0.6 + 1.2  # |f| + the forces at the junction
    rho = ROUNDOFF * (bal + c * 2e-17) / c
    assert _both(du, J, U, scale, spring, masses, f) == pytest.approx(1e-15 / (rho / TOL),
                                                                      rel=1e-12)
    # ... the load's share counted: without it (f = 0) the floor is lower
    without = _both(du, J, U, scale, spring, masses)
    assert without == pytest.approx(1e-15 / (ROUNDOFF * (bal - 0.6 + c * 2e-17) / c / TOL),
                                    rel=1e-12)
    # ... and a correction beyond the balance's rounding still fails
    du[n + 1] = 2.0 * rho
    assert _both(du, J, U, scale, spring, masses, f) > TOL


def _locked_junctions(gamma=4.36):
    # junctions j0, j1 (nodes 0, 1; n = 5 a stage): e0 a Bingham dashpot ground -> j0
    # slipping backwards (R = q - gamma (F + tau)), e1 stuck between them (R = q =
    # V_j1 - V_j0: no force term), e2 a spring j1 -> ground holding j1's velocity through
    # h A V (here 1e-3); their balances 0 = F_e1 - F_e0 (j0) and 0 = F_e2 - F_e1 (j1)
    masses, spring, n = [0.0, 0.0], [False, False, True], 5
    J = np.eye(3 * n)
    U = np.zeros(3 * n)
    for k in range(3):
        j0, j1, r0, r1, r2 = (k * n + i for i in range(5))
        J[j0, j0] = J[j1, j1] = 0.0
        J[j0, r0], J[j0, r1] = 1.0, -1.0
        J[j1, r1], J[j1, r2] = 1.0, -1.0
        J[r0, j0], J[r0, r0] = 1.0, -gamma
        J[r1, j1], J[r1, j0], J[r1, r1] = 1.0, -1.0, 0.0
        J[r2, j1] = 1e-3
        U[k * n:(k + 1) * n] = [-2e-6, -2e-6, -0.0343, -0.845, 0.8]
    scale = 1e-13 + 1e-10 * np.abs(U)
    return masses, spring, n, J, U, scale


def test_a_junction_locked_to_another_carries_that_ones_round_off():
    # issue 29, seed 22044: j0's velocity is set by e0's row to e0's rounding, gamma times
    # the balance's (gamma (|F_e0| + B_j1): e1's force is j1's balance); e1's row only
    # ties j1 to j0, and read alone (|V_j1| + |V_j0| = 4e-6) it floored both velocities
    # at 1e-21: corrections of 7e-16 cycled above the plain test (1e-16) on every step
    # after e0's break-out
    gamma = 4.36
    masses, spring, n, J, U, scale = _locked_junctions(gamma)
    # e1's force is j1's balance with the spring's (F_e1 = F_e2): it carries that
    # balance's rounding into j0's (linked_balances)
    bals = linked_balances(list(U), J.tolist(), junction_columns(masses, n),
                           rate_rows(2, spring), np.zeros((3, 2)).tolist())
    assert bals[n] == 0.0343 + (0.845 + 0.8)
    assert bals[n + 1] == (0.0343 + 0.845) + 0.8 and bals[n + 2] == 0.0  # (and back)
    rho0 = gamma * (0.0343 + 0.845 + 0.8) + 2e-6  # (e0's row: the balance's terms, V_j0)
    rho1 = 2e-6 + rho0  # (e1's row: V_j1, and V_j0 at its round-off)
    own = linked_roundoff(list(U), J.tolist(), junction_columns(masses, n),
                          rate_rows(2, spring), bals)
    assert own[n] == pytest.approx(rho0, rel=1e-12)
    assert own[n + 1] == pytest.approx(rho1, rel=1e-12)
    assert own[n + 2] == math.inf  # (no junction's velocity)
    du = np.zeros(3 * n)
    du[n], du[n + 1] = 0.5 * ROUNDOFF * rho0, -0.5 * ROUNDOFF * rho0  # (7e-16)
    assert abs(du[n + 1]) / scale[n + 1] > TOL
    assert _both(du, J, U, scale, spring, masses) == pytest.approx(0.5 * TOL, rel=1e-9)
    # ... beyond that rounding, not
    du[n + 1] = 2.0 * ROUNDOFF * rho1
    assert _both(du, J, U, scale, spring, masses) > TOL


def test_junctions_locked_together_on_springs_alone_keep_their_rows_as_they_are():
    # no row of a law in the rate sets either velocity alone (e0 a spring now): nothing
    # is known to carry along e1's row, which is read as before, |V_j1| + |V_j0|
    masses, spring, n, J, U, scale = _locked_junctions()
    spring = [True, False, True]
    own = linked_roundoff(list(U), J.tolist(), junction_columns(masses, n),
                          rate_rows(2, spring), [1.0] * (3 * n))
    assert own == [math.inf] * (3 * n)
    du = np.zeros(3 * n)
    du[n + 1] = 2.0 * TOL * scale[n + 1]
    assert _both(du, J, U, scale, spring, masses) == pytest.approx(2.0 * TOL, rel=1e-12)


def test_a_dashpot_between_junctions_carries_the_other_balances_rounding():
    # issue 29, the tight property's draw of seed 22131: j0 on a Newtonian dashpot to
    # ground (e0, c0 = 0.0225) tied by another (e1, c2 = 0.0103) to j2, which two springs
    # (e2, e3: the string's and an implicit spring's rows, holding V_j2 through h a)
    # hold at 0.075 and 0.0785; their difference is e1's force, so j2's balance rounds
    # it, and j0's velocity carries that over c0. Read from |F_e1| alone, V_j0's
    # corrections cycled at 3.1e-16 above its floor and the run stopped after 12 bridges
    c0, c2 = 0.0225, 0.0103
    masses, spring, n = [0.0, 0.0], [False, False, True, True], 6
    J = np.zeros((3 * n, 3 * n))
    U = np.zeros(3 * n)
    for k in range(3):
        j0, j2, r0, r1, r2, r3 = (k * n + i for i in range(n))
        J[j0, r0], J[j0, r1] = 1.0, -1.0  # 0 = F_e0 - F_e1
        J[j2, r1], J[j2, r2], J[j2, r3] = 1.0, -1.0, -1.0  # 0 = F_e1 - F_e2 - F_e3
        J[r0, j0], J[r0, r0] = -c0, 1.0
        J[r1, j2], J[r1, j0], J[r1, r1] = -c2, c2, 1.0
        J[r2, j2], J[r2, r2] = 1e-3, -1.0
        J[r3, j2], J[r3, r3] = 1e-3, -1.0
        U[k * n:(k + 1) * n] = [-1.88e-3, -0.347, -4.24e-5, -3.55e-3, -0.075, 0.0785]
    scale = 1e-13 + 1e-10 * np.abs(U)
    junction = junction_columns(masses, n)
    bals = linked_balances(list(U), J.tolist(), junction, rate_rows(2, spring),
                           np.zeros((3, 2)).tolist())
    B2 = 3.55e-3 + 0.075 + 0.0785
    assert bals[1] == pytest.approx(B2 + 4.24e-5, rel=1e-15)  # (and back: j0's)
    assert bals[0] == pytest.approx(4.24e-5 + B2, rel=1e-15)  # (not 4.24e-5 + 3.55e-3)
    assert [b for b, c in zip(bals, junction, strict=True) if not c] == [0.0] * 12
    du = np.zeros(3 * n)
    du[n] = 3.1e-16  # (the cycle: 1.07e-3 of the plain test)
    assert abs(du[n]) / scale[n] > TOL
    # j0's floor from e0's row: ROUNDOFF (B_j0 + c0 |V_j0|) / c0 (6.2e-12 over TOL)
    floor = ROUNDOFF * ((4.24e-5 + B2) / c0 + 1.88e-3) / TOL
    assert _both(du, J, U, scale, spring, masses) == pytest.approx(3.1e-16 / floor,
                                                                   rel=1e-9)
    # ... beyond that rounding, not
    du[n] = 2.0 * floor * TOL
    assert _both(du, J, U, scale, spring, masses) > TOL
