r"""The laws in the form that stays conditioned: steep branches solved for their force.

A branch of a law is *steep* (:attr:`lumped.codegen.branches.BranchInfo.steep`, read from
the law's expression and numbers, never its name) where ``dR/dF`` is large against
``dR/dq``: the forward form ``R(q, F)`` then fixes the force only to its rounding, and a
rate ``q`` may have no floating-point force at all. Herschel-Bulkley with ``n < 1``,

.. math::

    q = \gamma\, \mathrm{sgn}(F)\, (|F| - \tau)^n \quad (|F| > \tau), \qquad
    q = 0 \quad (|F| \le \tau),

gives a rate ``0 < |q| < gamma ulp(tau)^n`` no force: between ``F = -tau`` (the stuck
branch, residual ``q``) and its neighbour ``-tau - ulp(tau)`` (the slip branch, residual
``q + gamma ulp(tau)^n``) the residual jumps over zero, and Newton's iterates cycle
between the two. The inverse form of the slip branch,

.. math::

    R^{\mathrm{inv}}(q, F) = F - \mathrm{sgn}(q) \left(\tau + (|q|/\gamma)^{1/n}\right),
    \qquad \partial R^{\mathrm{inv}}/\partial F = 1,

has the same zeros on the branch and gives the force to its rounding
(:meth:`~lumped.codegen.branches.LawBranches.stage_law_for`). Near the yield force that
force rounds to ``-tau`` itself, where the law reads its stuck branch: the *conditioned
law* of :func:`conditioned_kernels` reads there the steep branch whose inverse form holds
to the rounding of its terms (and whose stage guards, signs of ``q``, admit the point),
as :func:`lumped.solvers.modes.choice.select_modes` reads the branch of its probe.

The fixed-step methods solve a step in these forms where the laws' own forms fail
(:meth:`lumped.solvers.bdf.step_loop.StepLoop.conditioned_solve`), so that ``radau5``'s
backward-Euler bridge (:mod:`lumped.solvers.eventdriven.bridge`) follows a break-away
from rest on such a dashpot.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Callable

from ...scene import Scene

__all__ = ["ROUNDOFF_HOLDS", "conditioned_kernels", "conditioned_law"]

#: A branch's residual holds at round-off where ``|R| <= ROUNDOFF_HOLDS M``, ``M`` the
#: magnitude of its terms (as the branch read of the mode choice: ``8 eps``).
ROUNDOFF_HOLDS = 8.0 * sys.float_info.epsilon


def conditioned_law(lb, law_kernel: Callable) -> Callable | None:
    """``kernel(q, F) -> (R, dR/dq, dR/dF)`` of a law with branches ``lb``
    (:class:`~lumped.codegen.branches.LawBranches` or its shifted view), its steep
    branches in their inverse form, the others by ``law_kernel``; ``None`` when no
    branch has an inverse form.

    The branch is the law's own (``lb.branch``), except where that branch has no
    inverse form and its residual does not hold at round-off while a steep branch's
    inverse form does, with every stage guard of that branch ``>= 0``: the point sits on
    the boundary in ``F`` of the steep branch (the force of the rate ``q`` rounds to the
    yield force). Has ``.magnitude(q, F)`` (the terms' scale of the branch read)."""
    form = lb.stage_law_for(law_kernel)
    if form is None:
        return None
    steep = [(lb.stage_kernel_for(j), lb.stage_guards_for(j))
             for j, info in enumerate(lb.info) if info.stage is not None]
    plain = [info.stage is None for info in lb.info]
    branch = lb.branch
    law_mag = getattr(form, "magnitude", None)

    def read(q: float, F: float) -> Callable | None:
        """The steep branch's inverse form that holds at ``(q, F)`` where the law's own
        branch (without one) does not, else ``None``."""
        if law_mag is None or not plain[branch(q, F)]:
            return None
        R = form(q, F)[0]
        if abs(R) <= ROUNDOFF_HOLDS * law_mag(q, F):
            return None
        for k, guards in steep:
            if (abs(k(q, F)[0]) <= ROUNDOFF_HOLDS * k.magnitude(q, F)
                    and all(g >= 0.0 for g in guards(q, F))):
                return k
        return None

    def kernel(q: float, F: float) -> tuple[float, float, float]:
        k = read(q, F)
        return form(q, F) if k is None else k(q, F)

    def magnitude(q: float, F: float) -> float:
        k = read(q, F)
        if k is not None:
            return k.magnitude(q, F)
        return math.inf if law_mag is None else law_mag(q, F)

    kernel.magnitude = magnitude  # type: ignore[attr-defined]
    return kernel


def conditioned_kernels(scene: Scene) -> list[Callable] | None:
    """Every element's :func:`conditioned_law` (its own kernel where it has no steep
    branch with an inverse form, or where its branches cannot be read: a hand-written
    kernel), or ``None`` when no element has such a branch."""
    from ...scene.shifted_laws import branches_of

    kernels, any_steep = [], False
    for el in scene.elements:
        try:
            form = conditioned_law(branches_of(el.law), el.law.kernel)
        except (AttributeError, TypeError, ValueError):  # no expression to read
            form = None
        any_steep = any_steep or form is not None
        kernels.append(el.law.kernel if form is None else form)
    return kernels if any_steep else None
