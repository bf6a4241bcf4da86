r"""The stage Newton's convergence test of a junction's velocity at its round-off,
compiled with numba: the twin of :mod:`lumped.solvers.radau.roundoff` (read it for the
maths), the same operations in the same order, bit for bit. The compiled stage Newton
(:func:`lumped.solvers.radau.stage_jit.stage_solve`) calls :func:`roundoff_worst_jit`
through its address, compiled for a scene with a junction only.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.jit import njit
from ..newton.criteria import ROUNDOFF

__all__ = ["linked_balances_jit", "linked_roundoff_jit", "roundoff_worst_jit"]


@njit(cache=True)
def roundoff_worst_jit(du, U, J, scale, masses, spring, f, tol, worst, h, after_impact) -> float:
    """:func:`lumped.solvers.radau.roundoff.roundoff_worst` (read it for the maths), the
    junction's velocities read from ``masses`` (``m_i = 0``), the dashpots' rows from
    ``spring``, ``f[k, i]`` the external forces: the largest ``|du_j| / scale_j`` with a
    junction velocity's tolerance floored at its round-off (its dashpot's force at the
    rounding of the junction's balance, another junction's velocity in its row at that
    velocity's own round-off), when only junction velocities fail the test."""
    if worst <= tol:
        return worst
    N = masses.shape[0]
    size = U.shape[0]
    n = size // 3
    other = 0.0
    for j in range(size):
        i = j % n
        if not (i < N and masses[i] == 0.0):
            r = abs(du[j]) / scale[j]
            if not r <= other:
                other = r
    if not other <= tol:
        return worst
    worst = other
    bals = linked_balances_jit(U, J, masses, spring, f)
    own = linked_roundoff_jit(U, J, masses, spring, bals)
    for j in range(size):
        i = j % n
        if not (i < N and masses[i] == 0.0):
            continue
        bal = bals[j]
        rho = 0.0
        for any_row in (False, True):  # the laws in the rate; else any row (springs')
            for row in range(size):
                e = row % n - N
                c = abs(J[row, j]) if (e >= 0 and not spring[e]) or any_row else 0.0
                if c > 0.0:
                    s = 0.0
                    for u in range(size):
                        if u == row:
                            s += abs(J[row, u]) * bal
                        elif u != j and own[u] < math.inf and J[row, u] != 0.0:
                            s += abs(J[row, u]) * max(abs(U[u]), own[u])
                        else:
                            s += abs(J[row, u]) * abs(U[u])
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


@njit(cache=True)
def linked_balances_jit(U, J, masses, spring, f):
    """:func:`lumped.solvers.radau.roundoff.linked_balances` (read it for the maths): per
    stage unknown, the magnitude of a junction's balance, a dashpot's force between two
    junctions at the other junction's balance."""
    N = masses.shape[0]
    size = U.shape[0]
    n = size // 3
    plain = np.zeros(size)
    for j in range(size):
        i = j % n
        if i < N and masses[i] == 0.0:
            bal = abs(f[j // n, i])  # the junction's balance: row j
            for u in range(size):
                bal += abs(J[j, u]) * abs(U[u])
            plain[j] = bal
    out = plain.copy()
    for j in range(size):
        i = j % n
        if not (i < N and masses[i] == 0.0):
            continue
        linked = False
        bal = abs(f[j // n, i])
        for u in range(size):
            w = abs(U[u])
            e = u % n - N
            if e >= 0 and not spring[e] and J[j, u] != 0.0:
                for o in range(size):
                    io = o % n
                    if (o != j and io < N and masses[io] == 0.0 and J[u, o] != 0.0
                            and plain[o] > w):
                        w = plain[o]
                        linked = True
            bal += abs(J[j, u]) * w
        if linked:
            out[j] = bal
    return out


@njit(cache=True)
def linked_roundoff_jit(U, J, masses, spring, bals):
    """:func:`lumped.solvers.radau.roundoff.linked_roundoff` (read it for the maths): per
    stage unknown, the round-off of a junction's velocity that a dashpot's row holds with
    another junction's velocity, ``inf`` elsewhere and where not known."""
    N = masses.shape[0]
    size = U.shape[0]
    n = size // 3
    own = np.full(size, math.inf)
    linked = False
    for r in range(size):
        e = r % n - N
        if e >= 0 and not spring[e]:
            count = 0
            for u in range(size):
                i = u % n
                if i < N and masses[i] == 0.0 and J[r, u] != 0.0:
                    count += 1
            if count > 1:
                linked = True
    if not linked:
        return own
    for _ in range(size):
        fell = False
        for j in range(size):
            i = j % n
            if not (i < N and masses[i] == 0.0):
                continue
            for r in range(size):
                e = r % n - N
                c = abs(J[r, j]) if e >= 0 and not spring[e] else 0.0
                if c > 0.0:
                    s = 0.0
                    for u in range(size):
                        iu = u % n
                        if u == r:
                            s += abs(J[r, u]) * bals[j]
                        elif u != j and iu < N and masses[iu] == 0.0 and J[r, u] != 0.0:
                            s += abs(J[r, u]) * max(abs(U[u]), own[u])
                        else:
                            s += abs(J[r, u]) * abs(U[u])
                    s = s / c
                    if 0.0 < s < own[j]:
                        own[j] = s
                        fell = True
        if not fell:
            break
    return own
