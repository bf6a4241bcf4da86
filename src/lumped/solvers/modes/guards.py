r"""The branch guards of a held mode along a step of the adaptive method: how far below
zero a guard may sit from round-off (:func:`guard_tolerance`) and whether a law crosses a
fold between the nodes of the step's polynomial (:func:`fold_crossed`).

A *mode* holds every element's law on one smooth branch (:func:`lumped.codegen.branches.
law_branches`); the branch's guards ``g(q, F) >= 0`` say where it is admissible. The guards
are sampled along the step's collocation polynomial at
:data:`lumped.solvers.radau.tableau.SAMPLES`, and the first point where one turns negative
is located by :mod:`lumped.solvers.modes.crossing_root`.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from ..implicit.branch_check import left_branch

__all__ = ["fold_crossed", "guard_tolerance"]


def fold_crossed(kernel: Callable, q: Sequence[float], F: Sequence[float]) -> bool:
    """Whether the law crosses a fold along a step: ``dR/dq`` or ``dR/dF`` changes sign
    strictly between consecutive nodes ``(q[k], F[k])`` of the step's polynomial (the test
    of the fixed-step methods, :mod:`lumped.solvers.implicit.branch_check`)."""
    d = [kernel(qk, Fk) for qk, Fk in zip(q, F, strict=True)]
    for k in range(len(q) - 1):
        if left_branch(kernel, q[k], F[k], d[k][1], d[k][2], q[k + 1], F[k + 1],
                        d[k + 1][1], d[k + 1][2]):
            return True
    return False


def guard_tolerance(q: float, F: float) -> float:
    """How far below zero a guard may sit from round-off alone at ``(q, F)``."""
    return 64.0 * 2.220446049250313e-16 * (1.0 + abs(q) + abs(F))
