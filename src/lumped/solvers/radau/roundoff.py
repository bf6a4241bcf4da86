r"""The stage Newton's convergence test of a junction's velocity at its round-off.

A junction (a massless node) has no inertia: its stage velocity ``V_k,i`` is set by the
laws of the elements at it through the junction's force balance, and so carries the
round-off of their forces magnified by ``dq/dF``. A junction held by two
Herschel-Bulkley ``n = 0.3`` dashpots slowing to a stop in finite time (the spring
pulling it falls to the sum of their yield forces) has ``q = gamma (F - tau)^n``, so
``dq/dF = n q / (F - tau)`` grows without bound: at ``q = 0.04``, ``F - tau = 6e-6``,
``dq/dF = 2000``, and one ulp of the forces (``7e-18``) moves the velocity by ``1.4e-14``
(measured: the corrections cycled at ``1e-14 .. 4e-14``), above the test's ``tol
(atol + rtol |v|) = 5e-15`` at ``rtol = 1e-10``. Every stage solve then failed, the
step fell to its floor and backward Euler bridged the stop (issue 29).

The round-off of an unknown ``u_j`` read from a row ``r`` of the stage system is
``ROUNDOFF (sum_u |J_ru| |U_u|) / |J_rj|``: the rounding of the row's terms over the
row's sensitivity to ``u_j`` (a law in its inverse form ``F - tau - (q/gamma)^(1/n)``:
``ROUNDOFF (|F| + |dG/dq| |q|) / |dG/dq| = ROUNDOFF (|q| + |F| dq/dF)``). The best row
of a law in the rate (a dashpot's: the least round-off) sets it. :func:`roundoff_worst`
floors the tolerance of each junction velocity at that level when only junction
velocities fail the test: a correction at the round-off of the laws is converged.

The dashpot's force ``F_e`` in that row is itself read from the junction's balance
``0 = f_i + sum_{a_e = i} F_e - sum_{b_e = i} F_e``: it carries the rounding of the
balance's terms, ``ROUNDOFF B_i``, ``B_i = |f_i| + sum_e |F_e|`` over the elements at
the junction, not of ``|F_e|`` alone. So the row's term of its own force is taken at
``|J_rr| B_i`` (``B_i >= |F_e|``; equal for a junction on one element). Two strings
meeting at a junction held by a Newtonian dashpot (``c = 0.048``) while its velocity
crosses zero: the strings' forces ``0.59`` and ``0.13`` and a spring's ``0.46`` cancel
to the dashpot's ``F_e ~ 0``, whose own terms ``|F_e| + c |v|`` set a round-off of
``1e-18``, but one ulp of the balance (``1.1e-16``) moves the velocity by ``ulp / c =
2.3e-15``: the corrections cycled at ``1.16e-15``, above the test's ``tol (atol + rtol
|v|) = 6.6e-16`` at ``rtol = 1e-10``, and backward Euler bridged 12 times before the run
stopped at its step floor (issue 29). With the balance's terms the floor is ``ROUNDOFF
B_i / c = 2.2e-14``.

A spring's row is read only where no law in the rate holds the junction's velocity: it
holds the velocity through ``h sum_l a_kl V_l``, and the velocity it fixes carries the
positions' rounding over ``h`` (``ulp(x) / h``, ``1e-7`` at ``h = 1e-10``), which on a
short step after an impact would pass a junction velocity still jumping within the step
(a string taut between a junction and a mass whose velocity the impact changed: the
junction follows at once, held by its dashpot's row); such a step fails as before, and
the event is taken at its start. But a junction held by a slipping Coulomb element
(its row ``F + tau``: ``dR/dq = 0``) and springs has its velocity from the springs' rows
alone, ``F_k = F_n + h sum_l a_kl k (V_m - V_j)_l``, to one ulp of their forces over ``h
a_kl k``: a junction between two unit springs, ``h = 6e-3``, moved by ``1e-13``, above
the test's ``tol (atol + rtol |v|) = 7e-14`` at ``rtol = 1e-10``, and more so on every
shorter step: the run crept, backward Euler bridged twice and the work budget stopped it
after 15 000 rejected steps (issue 29). There the best of the springs' rows sets the
floor (``ROUNDOFF B_i / (h a_kl k)``, ``4e-13``), as long as it is within the velocity's
own tolerance ``atol + rtol |v|`` (not on the short steps of an impact, where it would
pass the jump above: a Coulomb element at a junction then stuck 1.2e-7 beyond its yield
force). That limit stays on the first step after an impact only (``after_impact``: the
junction may jump within it). On any other step such a velocity is an index-2 variable
of the DAE (no law fixes it, the springs' rows fix its position), and its tolerance is
read on the positions it moves, ``scale_j / h`` for ``h < 1`` (Hairer and Wanner's
scaling of index-2 components in RADAU5), floored at the springs' rounding as before.
Two equal Coulomb elements in series through a junction, both slipping, springs across
each, leave the junction's velocity to the springs' rows (``k_2 x_j = k_4 (x_m -
x_j)``): at ``rtol = 1e-10`` one ulp of their forces over ``h a_kl k`` was ``1e-12`` at
``h = 1.8e-2`` against the velocity's ``7e-13``, every stage solve failed down to ``h =
4e-15`` and the run stopped after 12 bridges (a tight-run draw, issue 29; 25 steps now).
The springs' rounding is also short of the positions' own where a spring's ends sit far
from its force (``k (|x_a| + |x_b|) >> |F|``: a junction on a spring of ``k = 5.7``, its
ends at 0.035 and 0.038, carrying 0.015): its velocity cycled at 1.3 times that floor
while an HB ``n = 0.8`` dashpot at another junction stopped, and the run crawled through
bridges for 30 minutes (another draw; 3.5 s now, no bridge: its last bridge followed a
switch at another junction, whose first step needs no plain tolerance, as it has no
impact).

A row may hold two junctions' velocities: a dashpot between them, stuck (``V_b - V_a =
0``) or slipping. It ties them and fixes neither, so the rounding of its own terms is no
floor for them: the other junction's velocity enters it at that velocity's own round-off
(:func:`linked_roundoff`), where a row that holds no other junction velocity (its
dashpot to ground, say) sets it. Two junctions locked by a stuck dashpot, the one on a
Bingham dashpot to ground that had just broken out: read alone, the lock's row floored
both velocities at ``1e-21`` against their rounding ``7e-16``, and backward Euler bridged
5 times before the work budget stopped the run (issue 29). The compiled twin is
:func:`lumped.solvers.radau.roundoff_jit.roundoff_worst_jit` (the same operations in the
same order, bit for bit).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ..newton.criteria import ROUNDOFF

__all__ = ["junction_columns", "linked_balances", "linked_roundoff", "rate_rows", "roundoff_worst"]


def junction_columns(masses: Sequence[float], n: int) -> list[bool]:
    """Per stage unknown (``3 n`` of them, see :mod:`lumped.solvers.radau.stage`): whether it
    is a junction's velocity (``m_i = 0``)."""
    N = len(masses)
    return [j % n < N and masses[j % n] == 0.0 for j in range(3 * n)]


def rate_rows(N: int, spring: Sequence[bool]) -> list[bool]:
    """Per stage row (``3 n``): whether it is the law of an element in the rate (a
    dashpot: ``spring[e]`` false)."""
    n = N + len(spring)
    return [r % n >= N and not spring[r % n - N] for r in range(3 * n)]


def roundoff_worst(du: Sequence[float], U: Sequence[float], J: Sequence[Sequence[float]],
                   scale: Sequence[float], junction: Sequence[bool], rate: Sequence[bool],
                   f: Sequence[Sequence[float]], tol: float, worst: float,
                   h: float = 1.0, after_impact: bool = False) -> float:
    r"""The largest ``|du_j| / scale_j`` of a Newton correction ``du`` (``worst``, as the
    caller found it), with the tolerance of a junction's velocity floored at its
    round-off: ``max(scale_j, rho_j / tol)``, ``rho_j = ROUNDOFF min_r (|J_rr| B_j +
    sum_{u != r} |J_ru| W_u) / |J_rj|`` over the rows ``r`` of laws in the rate
    (``rate[r]``, :func:`rate_rows`) that hold ``u_j`` (when none does: over every row
    that holds it, the springs': then at least ``scale_j / h`` for a step ``h < 1``, and
    with ``after_impact``, the first step after an impact, not that but only ``rho_j`` if
    ``rho_j <= scale_j``), ``r`` also the column of that law's force, and ``B_j = |f_k,i|
    + sum_u |J_ju| |U_u|`` the terms of the junction's balance (row ``j = k n + i``,
    ``f[k][i]`` the external force on it at stage ``k``; see the module notes), at the
    iterate ``U`` and its Jacobian ``J``; no floor where no row holds ``u_j``. A term
    ``W_u`` is ``|U_u|``, but another junction's velocity in the row enters at its own
    round-off, ``max(|U_u|, rho_u)`` (:func:`linked_roundoff`; a dashpot between two
    junctions, stuck or slipping).

    ``worst`` is returned as it is when it is within ``tol`` or when another unknown fails
    the test (only a junction's velocity at its round-off is let through).
    """
    if worst <= tol:
        return worst
    other = 0.0
    for j in range(len(du)):
        if not junction[j]:
            r = abs(du[j]) / scale[j]
            if not r <= other:
                other = r
    if not other <= tol:
        return worst
    worst = other
    size = len(U)
    bals = linked_balances(U, J, junction, rate, f)
    own = linked_roundoff(U, J, junction, rate, bals)
    for j in range(size):
        if not junction[j]:
            continue
        bal = bals[j]
        rho = 0.0
        for any_row in (False, True):  # the laws in the rate; else any row (springs')
            for r, row in enumerate(J):
                c = abs(row[j]) if rate[r] or any_row else 0.0
                if c > 0.0:
                    s = 0.0
                    for u in range(size):
                        if u == r:
                            s += abs(row[u]) * bal
                        elif u != j and own[u] < math.inf and row[u] != 0.0:
                            s += abs(row[u]) * max(abs(U[u]), own[u])
                        else:
                            s += abs(row[u]) * abs(U[u])
                    s = s / c
                    if rho == 0.0 or s < rho:
                        rho = s
            if rho > 0.0:
                break
        tol_j = max(scale[j], ROUNDOFF * rho / tol)
        if rho > 0.0 and any_row:  # (springs' rows alone: an index-2 velocity)
            if after_impact:
                if ROUNDOFF * rho > scale[j]:
                    tol_j = scale[j]  # (their rounding beyond the velocity's own tolerance)
            elif h < 1.0:
                tol_j = max(tol_j, scale[j] / h)
        r = abs(du[j]) / tol_j
        if not r <= worst:
            worst = r
    return worst


def linked_balances(U: Sequence[float], J: Sequence[Sequence[float]],
                    junction: Sequence[bool], rate: Sequence[bool],
                    f: Sequence[Sequence[float]]) -> list[float]:
    r"""Per stage unknown: the magnitude ``B_j`` of the terms of a junction's balance (row
    ``j``, ``f[k][i]`` its external force at stage ``k``), 0 for every other unknown.

    ``B_j = |f_k,i| + sum_u |J_ju| W_u`` with ``W_u = |U_u|``, except for the force of a
    dashpot whose row also holds another junction's velocity ``j'`` (a dashpot between
    two junctions): ``W_u = max(|U_u|, B_j')`` with ``B_j'`` the plain sum at ``j'``.
    That force is fixed by ``j'``'s balance where no other law in the rate holds ``j'``
    (``F_u = f_j' + ...``, its other elements springs), and so carries that balance's
    rounding into ``j``'s. A junction ``j0`` on a Newtonian dashpot to ground (``c0 =
    0.023``, carrying ``4e-5``) and a spring, tied by a dashpot (``c2 = 0.010``,
    ``3.5e-3``) to a junction ``j2`` between two springs carrying ``0.078`` each: read
    from ``|F_u|``, ``j0``'s balance was ``0.007`` and its velocity's round-off
    ``ROUNDOFF 0.007 / c0 = 2.8e-16``, but ``j2``'s balance rounds ``F_u`` by ``ROUNDOFF
    0.16``, and the stage corrections of ``V_j0`` cycled at ``3.1e-16`` (that rounding
    over ``c0 + c2``); every stage solve failed down to the step floor, and
    backward Euler bridged 12 times before the run stopped (the tight property, issue
    29). Where no row of a law in the rate holds two junctions, ``B_j`` is the plain sum,
    operation for operation.
    """
    n = len(U) // 3
    size = len(U)
    plain = [0.0] * size
    for j in range(size):
        if junction[j]:
            bal = abs(f[j // n][j % n])  # the junction's balance: row j
            for u in range(size):
                bal += abs(J[j][u]) * abs(U[u])
            plain[j] = bal
    out = list(plain)
    for j in range(size):
        if not junction[j]:
            continue
        linked = False
        bal = abs(f[j // n][j % n])
        for u in range(size):
            w = abs(U[u])
            if rate[u] and J[j][u] != 0.0:
                for o in range(size):
                    if o != j and junction[o] and J[u][o] != 0.0 and plain[o] > w:
                        w = plain[o]
                        linked = True
            bal += abs(J[j][u]) * w
        if linked:
            out[j] = bal
    return out


def linked_roundoff(U: Sequence[float], J: Sequence[Sequence[float]],
                    junction: Sequence[bool], rate: Sequence[bool],
                    bals: Sequence[float]) -> list[float]:
    r"""Per stage unknown: the round-off ``rho_u`` (over ``ROUNDOFF``) of a junction's
    velocity that a row of a law in the rate holds with another junction's velocity (a
    dashpot between two junctions), ``inf`` for every other unknown and where it is not
    known.

    Such a row ties the two velocities; it fixes neither: a dashpot stuck between the
    junctions ``j0`` and ``j1`` (``V_j1 - V_j0 = 0``, no force term) holds ``j1`` at
    ``j0``'s velocity, which ``j0``'s own dashpot to ground sets, with its rounding
    (``ROUNDOFF gamma B_j0``, ``6.5e-15``). Read as ``ROUNDOFF (|V_j0| + |V_j1|)`` the row
    floored both velocities at ``1e-21`` just after ``j0``'s dashpot broke out: the
    corrections cycled at ``7e-16``, above the test's ``tol (atol + rtol |v|) = 1e-16``
    at ``rtol = 1e-10``, every stage solve failed down to the step floor, and backward
    Euler bridged 5 times before the work budget stopped the run (issue 29). So another
    junction's velocity in a row enters at its own round-off, known once a row that holds
    no other junction velocity (or one whose velocity is known) sets it: ``rho_j = min_r
    (|J_rr| B_j + sum_{u != r} |J_ru| W_u) / |J_rj|`` over such rows, ``W_u = max(|U_u|,
    rho_u)`` for another junction's velocity, ``|U_u|`` otherwise, swept until no value
    falls (``bals[j]`` is ``B_j``, see :func:`roundoff_worst`). Without such a row
    (nothing ties two junctions) every value is ``inf`` at once, and
    :func:`roundoff_worst` reads its rows as before.
    """
    size = len(U)
    own = [math.inf] * size
    linked = False
    for r in range(size):
        if rate[r]:
            count = 0
            for u in range(size):
                if junction[u] and J[r][u] != 0.0:
                    count += 1
            if count > 1:
                linked = True
    if not linked:
        return own
    for _ in range(size):
        fell = False
        for j in range(size):
            if not junction[j]:
                continue
            for r in range(size):
                row = J[r]
                c = abs(row[j]) if rate[r] else 0.0
                if c > 0.0:
                    s = 0.0
                    for u in range(size):
                        if u == r:
                            s += abs(row[u]) * bals[j]
                        elif u != j and junction[u] and row[u] != 0.0:
                            s += abs(row[u]) * max(abs(U[u]), own[u])
                        else:
                            s += abs(row[u]) * abs(U[u])
                    s = s / c
                    if 0.0 < s < own[j]:
                        own[j] = s
                        fell = True
        if not fell:
            break
    return own
