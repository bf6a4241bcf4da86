r"""The linear solves of the Radau IIA stage Newton (:mod:`lumped.solvers.radau.stage`).

Owns :func:`linear_solver` (the LU with pivoting, or the minimum-norm solution when the
stage Jacobian is singular), :func:`cone_solver` (the force split among locked elements
in parallel: of all the solutions of a singular stage system, the one whose forces sit
nearest the centres of the intervals their locks admit) and :func:`solves` with
:func:`row_scale` (whether a residual is a root to the convergence test, which tells a
split the locks can carry from a least-squares point).
"""

from __future__ import annotations

import math
from collections.abc import Callable

from ..newton.linalg import lu_factor, lu_solve
from ..newton.min_norm import min_norm_solver

__all__ = ["cone_solver", "linear_solver", "row_scale", "solves"]


def linear_solver(J: list[list[float]]) -> Callable[[list[float]], list[float]]:
    """``solve(b)`` for ``J y = b``: the LU with pivoting, or the minimum-norm least-squares
    solution when ``J`` is singular (:func:`lumped.solvers.newton.semismooth.min_norm_solver`)."""
    fac = lu_factor(J)
    if fac is not None:
        return lambda b: lu_solve(fac, b)
    if not all(math.isfinite(a) for row in J for a in row):  # a law undefined here
        return lambda b: [math.nan] * len(b)
    return min_norm_solver(J)


def row_scale(row: list[float], scale: list[float]) -> float:
    """``sum_j |J_ij| scale_j``: how much row ``i`` of the stage system changes when every
    unknown moves by its tolerance ``scale_j``."""
    return sum(abs(a) * sc for a, sc in zip(row, scale, strict=True))


def solves(G: list[float], J: list[list[float]], scale: list[float], tol: float) -> bool:
    """Whether the residual ``G`` is one a Newton correction within the convergence test
    removes: ``|G_i| <= 10 tol sum_j |J_ij| scale_j`` on every row (a row that no
    unknown enters must be zero to round-off)."""
    for g, row in zip(G, J, strict=True):
        if not abs(g) <= 10.0 * tol * row_scale(row, scale) + 1e-300:
            return False
    return True


def cone_solver(J: list[list[float]], U: list[float], cones: dict[int, tuple[float, ...]],
                N: int, n: int, held: dict[int, float] | None = None
                ) -> Callable[[list[float]], list[float]]:
    """``solve(b)`` for a singular ``J`` whose free directions split the force among locked
    elements in parallel: of all the solutions, the one whose new forces minimise
    ``sum (F_e - c_e)^2 / w_e`` over the elements of ``cones`` (``e -> (c_e, w_e, lo_e,
    hi_e)``, the centre and half-width of the force interval ``[lo_e, hi_e]`` the
    element's lock admits, :func:`lumped.solvers.modes.lock_events.lock_cones`) and the
    correction's norm over the other unknowns. Two stuck dashpots in parallel share a load
    ``S`` in proportion to their capacities (each within its cone whenever ``|S|`` is within
    the sum), a rigid lock (``w_e`` huge) takes what the others do not.

    With ``du = D z + o`` (``D = sqrt(w_e)``, ``o = c_e - U_j`` on those forces; ``o = 0``
    elsewhere; ``U`` the iterate, read at every call): ``z`` is the minimum-norm solution
    of ``J D z = b - J o``, rows equilibrated. The scales are set so that the split is
    solved to round-off at every step size (issue 29): a row with one entry (a stuck
    dashpot to ground: ``V = 0``) fixes its unknown by one division, exactly, as the LU's
    singleton pivots do, and that column is taken out of the other rows before the SVD;
    a mass's velocity, ``m / h`` in its momentum rows beside the forces' ``1``, is scaled
    by ``D = 1 / max_i |J_ij|`` (its correction is unique: its weight in the norm changes
    nothing but the rounding); every other unknown has ``D = 1``. In one SVD of the raw
    rows the split came out to its round-off, ``eps m / h``: ``5e-5`` of a yield force
    on a step of ``1e-12`` s, where the load lay ``1e-9`` within the joint yield force.
    ``held`` (stage column -> force): forces held at a bound of their interval (centre
    moved there, weight ``1e-12 w_e``), see :meth:`lumped.solvers.radau.stage.StageSystem.solve`."""
    import numpy as np

    size = len(U)
    held = held or {}
    A = np.array(J, dtype=float)
    single = [(i, int(nz[0]), float(A[i, nz[0]])) for i in range(size)
              for nz in [np.flatnonzero(A[i])] if len(nz) == 1]
    pinned = sorted({j for _, j, _ in single})
    cols = {k * n + N + e: (c, w) for k in range(3) for e, (c, w, *_) in cones.items()
            if k * n + N + e not in pinned}  # (a force its own law fixes is no share)
    D = np.ones(size)
    for j, (_, w) in cols.items():
        D[j] = math.sqrt(w * 1e-12 if j in held else w)
    for k in range(3):
        for i in range(N):
            j = k * n + i
            if any(A[kk * n + i, j] != 0.0 for kk in range(3)):  # (a mass's momentum rows)
                D[j] = 1.0 / np.abs(A[:, j]).max()
    A_pin = A[:, pinned]
    AD = A * D
    AD[:, pinned] = 0.0
    # rows equilibrated (the same solutions; a junction's row through a flat law, dq/dF
    # ~ 1e-7, is not cut off as round-off beside the momentum rows)
    r = np.abs(AD).max(axis=1)
    r[r == 0.0] = 1.0
    pinv = np.linalg.pinv(AD / r[:, None], rcond=size * 2.220446049250313e-16) / r

    def solve(b: list[float]) -> list[float]:
        o = np.zeros(size)
        for j, (c, _) in cols.items():  # ``U`` is the caller's iterate, updated in place
            o[j] = held.get(j, c) - U[j]
        fixed = np.zeros(size)
        for i, j, a in single:
            fixed[j] = b[i] / a
        z = pinv @ (np.asarray(b, dtype=float) - A @ o - A_pin @ fixed[pinned])
        du = D * z + o
        du[pinned] = fixed[pinned]
        return du.tolist()

    return solve
