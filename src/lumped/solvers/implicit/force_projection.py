r"""Nonlinear elimination of the forces for the step's Newton solve: every element's force
from its own law at the elongation (rate) an iterate's velocities give.

:func:`force_projector` makes the ``project`` of
:func:`~lumped.solvers.newton.semismooth.newton_solve`: every trial iterate gets each
element's force from its own law, solved by a safeguarded scalar root in a bracket.
Newton then acts on the reduced system ``balance(v, F(q(v))) = 0``, which stays well
conditioned where a law's graph is steep in ``F``: Herschel-Bulkley with ``n < 1`` has
``dq/dF -> infinity`` at its yield force, while its inverse ``F = tau + (q / gamma)^(1/n)``
is smooth there. Any user law with such a point gets the same help. The projector also
reads a dashpot whose rate is below the rounding of its ends' velocities as stuck, lists
the elements whose law admits no force at their ``q`` (a string past its length), and
gives each law row's round-off floor (``ulp_scales``).

Used by the globalised step solve (:mod:`lumped.solvers.implicit.globalize`) and its
balance sweeps (:mod:`lumped.solvers.implicit.balance_sweeps`).
"""

from __future__ import annotations

import math

from ...scene import Scene
from ..newton.scalar_root import scalar_root
from .branch_check import known_monotone

__all__ = ["force_projector"]


def _no_force_at(kernel, q: float, F0: float) -> bool:
    """True when a law monotone in ``F`` admits no force at ``q``: ``R`` has one sign at
    ``F0`` and at ``+-1e300`` (a taut string's law past its length, ``q > L``). Three
    kernel calls, where :func:`~lumped.solvers.newton.scalar_root.scalar_root` would double its
    bracket some 2000 times before it gives up (most of the time of a globalised step
    with a string an ulp past its length)."""
    R0 = kernel(q, F0)[0]
    if R0 == 0.0 or R0 != R0:
        return False
    lo, hi = kernel(q, -1e300)[0], kernel(q, 1e300)[0]
    if R0 > 0.0:
        return lo > 0.0 and hi > 0.0
    return lo < 0.0 and hi < 0.0


#: A dashpot's rate within this many ulps of its ends' velocities is rest to
#: :func:`force_projector` (with ``admit=True``) where its law admits the force at rest.
_REST_ULPS = 4.0


def _at_rest(kernel, u: list[float], a: int, b: int, q: float, F: float) -> bool:
    """True when the rate ``q = u_b - u_a`` of a dashpot is below the rounding of its
    ends' velocities (:data:`_REST_ULPS` ulps of the larger) and its law admits ``F`` at
    rest on a piece flat in ``F`` (``R(0, F) = 0``, ``dR/dF = 0``: stuck)."""
    ends = max(abs(u[a]) if a >= 0 else 0.0, abs(u[b]) if b >= 0 else 0.0)
    if not abs(q) <= _REST_ULPS * math.ulp(ends):
        return False
    R, _, RF = kernel(0.0, F)
    return R == 0.0 and RF == 0.0


def force_projector(scene: Scene, h: float, x_hat: list[float], *, admit: bool = False):
    """``u -> u'``: every element's force replaced by the root of its own law at the
    elongation (rate) that ``u``'s velocities give, where the law fixes the force there
    (a stuck dashpot's force is left as is; with ``admit=True`` only if its law admits
    it, else moved to a force it admits; a dashpot whose rate is below the rounding of
    its ends' velocities reads as stuck where its law admits its force at rest,
    :func:`_at_rest`). See ``project`` of
    :func:`~lumped.solvers.newton.semismooth.newton_solve`. After each call ``project.missing``
    lists the rows of the elements whose law admits no force at their ``q`` (their
    force is left as it was)."""
    N = len(scene.nodes)
    items = [(N + e, scene.elem_a[e], scene.elem_b[e], el.kind == "spring", el.law.kernel)
             for e, el in enumerate(scene.elements)]
    # springs whose law may admit no force at some q (a string past its length), tested
    # first by _no_force_at; only laws known to be monotone in F (no folds)
    may_miss = {N + e for e, el in enumerate(scene.elements)
                if el.kind == "spring" and known_monotone(el.law)}

    def elongation(u: list[float], a: int, b: int, is_spring: bool) -> float:
        if is_spring:
            qb = x_hat[b] + h * u[b] if b >= 0 else 0.0
            qa = x_hat[a] + h * u[a] if a >= 0 else 0.0
        else:
            qb = u[b] if b >= 0 else 0.0
            qa = u[a] if a >= 0 else 0.0
        return qb - qa

    def project(u: list[float], free: list[tuple[int, float]] | None = None) -> list[float]:
        out = list(u)
        missing = project.missing = []
        for k, a, b, is_spring, kernel in items:
            q = elongation(u, a, b, is_spring)
            if admit and not is_spring and q != 0.0 and _at_rest(kernel, u, a, b, q, u[k]):
                # a rate below the rounding of its ends' velocities (a junction moving
                # with a stuck neighbour, solved an ulp or two off it), at a force the
                # law admits at rest: stuck, its force left to Newton. Read as slipping
                # it would jump to its yield force, and its node's balance with it
                if free is not None:
                    free.append((k, 0.0))
                continue
            try:
                if k in may_miss and _no_force_at(kernel, q, u[k]):
                    raise ValueError  # a string past its length: no root to search for
                F, fixed = scalar_root(kernel, q, u[k])
            except ValueError:  # no force at this q: leave it to Newton
                missing.append(k)
                continue
            if math.isfinite(F) and (fixed or (admit and kernel(q, u[k])[0] != 0.0)):
                # a force the law fixes; or, where the law leaves it free (a stuck
                # dashpot), one it admits if the iterate's is not
                out[k] = F
            if not fixed and free is not None:
                free.append((k, q))
        return out

    def ulp_scales(u: list[float]) -> list[tuple[int, float]]:
        """``(row, rho / eps)`` per law row: ``rho`` the largest change of ``R`` when ``F``
        moves to a floating-point neighbour, the round-off floor of the row at ``u``
        (where the law is steep in ``F`` no float may give a smaller residual)."""
        out = []
        for k, a, b, is_spring, kernel in items:
            q = elongation(u, a, b, is_spring)
            R = kernel(q, u[k])[0]
            rho = max(abs(kernel(q, math.nextafter(u[k], d))[0] - R)
                      for d in (-math.inf, math.inf))
            out.append((k, rho / 2.220446049250313e-16))
        return out

    project.ulp_scales = ulp_scales
    return project
