"""Minimum-norm Newton corrections for step matrices that are singular, or singular
up to rounding (locked elements in parallel: the motion is fixed, the split of the forces
is not).

Owns :func:`min_norm_solver` (the pseudo-inverse solve that replaces LU on a singular
Jacobian), :func:`equilibrated_min_norm` (the same after scaling rows and columns) and
:func:`null_step_removed` (the check that swaps a long LU step along a null space hidden
by rounding for the minimum-norm one), used by
:func:`lumped.solvers.newton.semismooth.newton_solve` with ``min_norm=True``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["equilibrated_min_norm", "min_norm_solver", "null_step_removed"]


def min_norm_solver(J: Sequence[Sequence[float]], rows: bool = False):
    """``solve(b)``: the minimum-norm least-squares solution of ``J y = b`` (numpy SVD).

    Singular values below ``n * eps`` times the largest count as zero, so an exactly
    rank-deficient step matrix (two locked elements in parallel) is solved on its range
    and leaves the null space (the free split of the forces) untouched. With ``rows``
    the rows are scaled to unit largest entries first (the unknowns are not: the norm
    minimised is theirs), so a row whose entries are small in its own units stays in the
    range: the consistent initial state reads a stuck
    dashpot's law at the rate ``1e-20 a`` (entries ``1e-20``); unscaled, two such rows in
    parallel fell below the cut, the masses' accelerations were left free, and the load
    was split three ways, ``m a``, ``F_1``, ``F_2`` (a mass at rest on two stuck dashpots
    loaded by 0.2 started with the forces 0.0667 and 0.0667)."""
    import numpy as np

    A = np.array(J, dtype=float)
    r = np.abs(A).max(axis=1) if rows else np.ones(len(A))
    r[~(r > 0.0)] = 1.0  # (a zero row, or a non-finite one: Newton reports it)
    pinv = np.linalg.pinv(A / r[:, None], rcond=len(A) * 2.220446049250313e-16)

    def solve(b: Sequence[float]) -> list[float]:
        # (a non-finite result is Newton's to report, NON_FINITE: no numpy warning)
        with np.errstate(invalid="ignore", over="ignore"):
            return (pinv @ (np.asarray(b, dtype=float) / r)).tolist()

    return solve


def equilibrated_min_norm(J: Sequence[Sequence[float]], G: Sequence[float]) -> list[float]:
    """The minimum-norm solution of ``J d = G`` with rows and columns scaled to unit
    largest entries first: a matrix singular only in its scales (``k h = 1e8`` beside
    ``m / h = 1``) keeps its full rank (the plain LU solution), one with rows that are
    proportional up to rounding (locks in parallel) loses their null space."""
    import numpy as np

    A = np.array(J, dtype=float)
    r = np.abs(A).max(axis=1)
    r[r == 0.0] = 1.0
    A /= r[:, None]
    c = np.abs(A).max(axis=0)
    c[c == 0.0] = 1.0
    A /= c[None, :]
    pinv = np.linalg.pinv(A, rcond=len(A) * 2.220446049250313e-16)
    return ((pinv @ (np.asarray(G, dtype=float) / r)) / c).tolist()


#: A Newton correction longer than this times ``1 + max |u|`` is checked for a step
#: along a null space that only rounding hides (:func:`null_step_removed`). The length
#: of such a step is the residual's share outside the range over the pivot of an ulp:
#: ``1e13`` while another law's residual is large (issue 11), but ``50`` to ``600`` where
#: only round-off is left outside the range (a string taut beside a stuck
#: Herschel-Bulkley dashpot, issue 29: pivot ``1.5e-20``, step ``536``); the check (an
#: SVD of the step matrix) is cheap beside the Newton iterations such a step costs.
_NULL_STEP_RATIO = 10.0


def null_step_removed(J: Sequence[Sequence[float]], G: Sequence[float], du: list[float],
                      u: Sequence[float]) -> list[float] | None:
    """The minimum-norm correction in place of the LU correction ``du`` (``J du = G``)
    where ``du`` is a long step along a null space that only rounding hides; else None.

    Locked elements in a cycle (two stuck dashpots in parallel, a string taut beside a
    stuck dashpot) make the step matrix singular, their rows proportional; but LU, when
    the ratio of those rows is not a power of two, eliminates one of them to a pivot of
    an ulp instead of zero, and while the residual is not yet small (another law still
    converging) the correction moves the free split of the forces by ``residual / ulp``
    (``1e13``), from where Newton crawls back by halving and runs out of iterations. Even
    a residual at round-off in the proportional rows moves the split by ``50`` to ``600``
    (a string taut beside a stuck Herschel-Bulkley dashpot: the split lands outside the
    dashpot's yield band and the string's force goes slack, and Newton walks back by
    halving, or leaves the stuck mode for good).
    Checked only when ``du`` exceeds :data:`_NULL_STEP_RATIO` times ``1 + max |u|``:
    the minimum-norm solution of the equilibrated matrix
    (:func:`equilibrated_min_norm`) replaces it when it is a thousand times shorter and
    solves ``J d = G`` (residual below ``1e-8`` of the terms). On a regular matrix the two
    agree to rounding, so ``du`` stays."""
    big = max(abs(d) for d in du)
    if not big > _NULL_STEP_RATIO * (1.0 + max(abs(x) for x in u)):
        return None
    d3 = equilibrated_min_norm(J, G)
    short = max(abs(d) for d in d3)
    if not (math.isfinite(short) and 1e3 * short < big):
        return None
    terms = max(max(abs(g) for g in G), max(abs(Jij) * short for row in J for Jij in row))
    for row, g in zip(J, G, strict=True):
        r = sum(Jij * dj for Jij, dj in zip(row, d3, strict=True)) - g
        if not abs(r) <= 1e-8 * terms:
            return None
    return d3
