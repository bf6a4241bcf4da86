"""Types of the semismooth Newton: its options, its result and its return codes.

Owns :class:`NewtonOptions` (tolerances and budgets), :class:`NewtonResult` (the iterate,
its residual and Jacobian, the cost counters), :class:`NewtonCode` (how a solve ended) and
the ``Evaluate`` callback type of :func:`lumped.solvers.newton.semismooth.newton_solve`.
The compiled Newton (:mod:`lumped.solvers.newton.semismooth_jit`) returns the values of
:class:`NewtonCode` as integers (its ``CODE_NAMES``).
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass

__all__ = ["Evaluate", "NewtonCode", "NewtonOptions", "NewtonResult"]


Evaluate = Callable[[list[float]], tuple[list[float], list[list[float]], list[float]]]


class NewtonCode(enum.Enum):
    """How a Newton solve ended."""

    SUCCESS = "success"
    MAX_ITERS = "max_iters"  #: the iteration budget ran out
    DIVERGED = "diverged"  #: the line search found no decrease of the residual
    SINGULAR = "singular"  #: a zero pivot in the LU factorisation
    NON_FINITE = "non_finite"  #: NaN or infinity in the residual, Jacobian or step


@dataclass(frozen=True)
class NewtonOptions:
    """Tolerances and budgets of :func:`~lumped.solvers.newton.semismooth.newton_solve`.

    Attributes
    ----------
    rtol, atol : float
        Relative and absolute tolerances of both convergence tests.
    max_iters : int
        Newton iterations (factorisations) allowed per solve.
    max_backtracks : int
        Halvings of the step allowed in the line search of one iteration.
    free_steps : int
        The first ``free_steps`` iterations take the full Newton step whenever it is
        finite, even if the residual grows (a watchdog: on a piecewise-linear law the
        full step from a wrong piece lands on the right one, where the next step is
        exact, while a line search would creep along the wrong piece).
    """

    rtol: float = 1e-10
    atol: float = 1e-12
    max_iters: int = 50
    max_backtracks: int = 40
    free_steps: int = 2

    def __post_init__(self) -> None:
        from ..._validate import as_int_at_least, as_positive

        as_positive("rtol", self.rtol)
        as_positive("atol", self.atol)
        as_int_at_least("max_iters", self.max_iters, 1)
        as_int_at_least("max_backtracks", self.max_backtracks, 0)
        as_int_at_least("free_steps", self.free_steps, 0)


@dataclass
class NewtonResult:
    """Outcome of :func:`~lumped.solvers.newton.semismooth.newton_solve`.

    Attributes
    ----------
    u : list of float
        The last iterate (the solution when ``code`` is ``SUCCESS``).
    code : NewtonCode
    iterations, residual_evals, jacobian_evals, factorizations : int
        Cost counters of this solve.
    residual : list of float
        ``G(u)`` at the returned iterate.
    worst_row : int
        Index of the row with the largest ``|G_i| / (rtol S_i + atol)``.
    jacobian : list of list of float
        ``J(u)`` at the returned iterate (callers read element derivatives from it).
    singular : bool
        A singular Jacobian was met (and, with ``min_norm=True``, stepped over by a
        minimum-norm correction).
    """

    u: list[float]
    code: NewtonCode
    iterations: int
    residual_evals: int
    jacobian_evals: int
    factorizations: int
    residual: list[float]
    worst_row: int
    jacobian: list[list[float]]
    singular: bool = False
