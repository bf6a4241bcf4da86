r"""Outcomes of a run, shared by every method: :class:`Status`, the errors, :class:`Event`
and :class:`RawRun` (what every method runner returns, see :mod:`lumped.solvers.registry`).
"""

from __future__ import annotations

import enum
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

__all__ = [
    "Status",
    "SolverError",
    "BranchError",
    "InconsistentInitialForce",
    "Event",
    "RawRun",
]


class Status(enum.Enum):
    """Outcome of a run."""

    SUCCESS = "success"
    MAX_ITERS = "max_iters"  #: Newton's iteration budget ran out
    DIVERGED = "diverged"  #: Newton's line search found no decrease
    SINGULAR = "singular"  #: singular step Jacobian
    NON_FINITE = "non_finite"  #: NaN or infinity met
    BRANCH_LOST = "branch_lost"  #: a non-monotone law would have jumped between branches
    TOO_MANY_EVENTS = "too_many_events"  #: event accumulation (Zeno, chattering): a clear stop
    STEP_TOO_SMALL = "step_too_small"  #: the adaptive step size fell below its floor
    INCONSISTENT = "inconsistent"  #: no motion satisfies all the laws


class SolverError(RuntimeError):
    """A step failed. Attributes: ``status``, ``t``, ``where`` (element or node), ``residual``."""

    def __init__(self, message: str, *, status: Status, t: float, where: str,
                 residual: float) -> None:
        super().__init__(message)
        self.status, self.t, self.where, self.residual = status, t, where, residual


class BranchError(SolverError):
    """A non-monotone law reached a fold: no solution continuous with the past."""


class InconsistentInitialForce(ValueError):
    """A user-supplied initial force breaks its element's law (or a junction balance)."""


@dataclass(frozen=True)
class Event:
    """One switching event, impact or time event.

    Attributes
    ----------
    t : float
        Time of the event.
    element : str
        Element name (``""`` for a time event of the forcing).
    kind : str
        ``"switch"`` (a law changes branch), ``"impact"`` (a velocity jump) or ``"time"``.
    from_branch, to_branch : int
        Index of the active ``Piecewise`` branch before and after (``-1`` if n/a).
    impulse : float
        Impacts: the impulse carried by the element (N s).
    energy_lost : float
        Impacts: kinetic energy lost (J), ``>= 0``.
    """

    t: float
    element: str
    kind: str
    from_branch: int
    to_branch: int
    impulse: float = 0.0
    energy_lost: float = 0.0


@dataclass
class RawRun:
    """What every method runner returns (wrapped into :class:`lumped.result.Solution`).

    Attributes
    ----------
    data : numpy.ndarray
        ``(n_samples, len(scene.columns()))``: ``t``, ``x_i, v_i`` per node, ``F_e`` per
        element.
    stats : dict
        scipy-like counters: ``steps``, ``newton_iterations``, ``residual_evals``, ...
    status : Status
    message : str
        Empty on success; otherwise what failed, when and where.
    events : list of Event
    dense : callable, optional
        ``t -> (len(t), n_cols)`` rows laid out like ``data``.
    indeterminate : dict
        Element name -> intervals ``(t0, t1)`` on which its force is not unique.
    """

    data: np.ndarray
    stats: dict
    status: Status = Status.SUCCESS
    message: str = ""
    events: list[Event] = field(default_factory=list)
    dense: Callable[[np.ndarray], np.ndarray] | None = None
    indeterminate: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
