r"""Convergence tests and merit of the semismooth Newton, on Python floats.

Owns the tests that :func:`lumped.solvers.newton.semismooth.newton_solve` (and the
solvers built on it) apply to an iterate:

* :func:`residual_ok`: ``|G_i| <= rtol * S_i + atol`` for every row ``i``;
* :func:`update_ok`: ``|delta_j| <= rtol * |u_j| + atol`` for every unknown ``j``;
* :func:`update_ok_scaled`: the update test against the scale of the terms each unknown
  enters;
* :func:`at_roundoff`: the residual at the rounding of its terms, ``|G_i| <= ROUNDOFF
  S_i`` (``ROUNDOFF = 4 eps``), the first test of a correction that is noise;

the line search's merit :func:`merit` (the largest residual relative to the row scales)
and :func:`hair`, the probe a hair along a Newton step that reads the Jacobian of the
piece the step points into. Their compiled twins are in
:mod:`lumped.solvers.newton.criteria_jit`.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence

__all__ = ["ROUNDOFF", "at_roundoff", "hair", "merit", "residual_ok", "update_ok",
           "update_ok_scaled"]

#: The round-off level of a row relative to its scale ``S_i`` (the sum of the magnitudes
#: of its terms): ``4 eps``, a few roundings of its terms.
ROUNDOFF = 4.0 * sys.float_info.epsilon


def hair(u: float, d: float) -> float:
    """``u - 1e-8 d``, but at least one ulp away from ``u`` (towards ``-d``) when ``d != 0``.

    The probe of the directional Jacobian must leave ``u`` for real: when the Newton
    correction is below ``1e8`` ulps of ``u`` (e.g. ``F = tau`` exactly with the true
    root ``1e-35`` beyond it), ``u - 1e-8 d`` rounds back to ``u`` and the probe would
    read the very piece it is meant to look past.
    """
    p = u - 1e-8 * d
    if p == u and d != 0.0:
        p = math.nextafter(u, -math.inf if d > 0.0 else math.inf)
    return p


def merit(G: Sequence[float], S: Sequence[float], floor: float) -> float:
    """Largest relative residual ``|G_i| / (S_i + atol / rtol)`` (unit-free per row)."""
    m = 0.0
    for g, s in zip(G, S, strict=True):
        r = abs(g) / (s + floor)
        if r > m:
            m = r
    return m


def residual_ok(G: Sequence[float], S: Sequence[float], rtol: float, atol: float) -> bool:
    """The residual test: ``|G_i| <= rtol * S_i + atol`` for every row ``i``."""
    for g, s in zip(G, S, strict=True):
        if not abs(g) <= rtol * s + atol:
            return False
    return True


def at_roundoff(G: Sequence[float], S: Sequence[float]) -> bool:
    r"""Every row at the rounding of its terms: ``|G_i| <= ROUNDOFF * S_i``.

    The first of Newton's two tests for a correction that is noise
    (:func:`lumped.solvers.newton.semismooth.newton_solve`; the second: the full
    correction does not reduce the row). A scale ``S_i`` that counts terms
    which cancel exactly (``gamma (F - tau)`` read as ``gamma |F|``) is above the row's
    true rounding, so this test alone does not make a solution. Example: a taut string
    (``q - L = 0``) holding a mass at rest on a stuck junction, ``q = x_m - x_j`` on a
    lattice of spacing ``ulp(x_m)`` that misses ``L`` by a fraction of it: the lock row
    asks the mass's velocity for ``(q - L) / h``, which moves ``x_m = x_hat + h v`` by
    less than an ulp, and the momentum balance asks the forces for ``m (q - L) / h^2``
    (``3e-9`` at ``h = 1e-4``), beyond ``rtol |F|``. The scale ``S_i`` of a law row
    must then count the terms ``q`` is computed from
    (:func:`lumped.solvers.implicit.step_system.law_scale`).
    """
    for g, s in zip(G, S, strict=True):
        if not abs(g) <= ROUNDOFF * s:
            return False
    return True


def update_ok(du: Sequence[float], u: Sequence[float], rtol: float, atol: float) -> bool:
    """The update test: ``|du_j| <= rtol * |u_j| + atol`` for every unknown ``j``."""
    for d, x in zip(du, u, strict=True):
        if not abs(d) <= rtol * abs(x) + atol:
            return False
    return True


def update_ok_scaled(du: Sequence[float], u: Sequence[float], J: Sequence[Sequence[float]],
                     S: Sequence[float], rtol: float, atol: float) -> bool:
    r"""The update test with the scale of the terms each unknown enters.

    ``|du_j| <= rtol * max(|u_j|, T_j) + atol`` with ``T_j = min_i S_i / |J_ij|`` over
    the rows ``i`` that contain ``u_j``: a correction that changes no equation by more
    than ``rtol`` times the size of that equation's terms is negligible, whatever the
    size of ``u_j`` itself (e.g. ``0``, where ``rtol |u_j|`` vanishes and ``atol`` in
    the unknown's units may be far below its round-off). Used after the plain test.
    """
    for j, (d, x) in enumerate(zip(du, u, strict=True)):
        a = abs(d)
        if a <= rtol * abs(x) + atol:
            continue
        T = math.inf
        for row, s in zip(J, S, strict=True):
            c = abs(row[j])
            if c > 0.0 and s / c < T:
                T = s / c
        if not a <= rtol * T + atol:  # T = inf (an empty column) fails too
            return False
    return True
