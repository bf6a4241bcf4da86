r"""The runner contract and the outcomes of a run, shared by every method: a runner is
``runner(scene, settings: RunSettings) -> RawRun`` (see :mod:`lumped.solvers.registry`);
:class:`Status`, the errors and :class:`Event` say how it went, and
:func:`fixed_step_grid` checks a fixed-step method's settings.
"""

from __future__ import annotations

import enum
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import TYPE_CHECKING, Any

import numpy as np

from ..grid import steps_for

if TYPE_CHECKING:
    from ..scene import Scene
    from .newton.options import NewtonOptions

__all__ = [
    "Status",
    "SolverError",
    "BranchError",
    "InconsistentInitialForce",
    "Event",
    "RawRun",
    "RunSettings",
    "Runner",
    "fixed_step_grid",
]


class Status(enum.Enum):
    """Outcome of a run."""

    SUCCESS = "success"
    MAX_ITERS = "max_iters"  #: Newton's iteration budget, or radau5's work budget, ran out
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


@dataclass(frozen=True)
class RunSettings:
    """What :func:`lumped.simulate` passes to a runner (validated there).

    Attributes
    ----------
    t_end : float
        Final time.
    dt : float, optional
        Step size of the fixed-step methods (required there).
    rtol, atol : float, optional
        Tolerances of the adaptive methods.
    throw : bool
        Raise :class:`~lumped.solvers.status.SolverError` on a failed step, or return the
        run up to the last good step with its status and message.
    options : NewtonOptions, optional
        Newton tolerances and budgets.
    extra : Mapping
        Method-specific keywords.
    """

    t_end: float
    dt: float | None = None
    rtol: float | None = None
    atol: float | None = None
    throw: bool = True
    options: NewtonOptions | None = None
    extra: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))


#: ``runner(scene, settings) -> RawRun``.
Runner = Callable[["Scene", RunSettings], RawRun]


def fixed_step_grid(method: str, settings: RunSettings,
                     allowed: tuple[str, ...] = ()) -> tuple[float, int]:
    """``(dt, n_steps)`` of a fixed-step method; refuses what it does not take (extra
    keywords other than ``allowed``)."""
    if settings.dt is None:
        raise ValueError(f"`dt` is required for the fixed-step method {method!r}, got None")
    for name in ("rtol", "atol"):
        if getattr(settings, name) is not None:
            raise ValueError(f"`{name}` applies to adaptive methods only; {method!r} is a "
                             f"fixed-step method (give `dt`), got {name}="
                             f"{getattr(settings, name)!r}")
    unknown = sorted(k for k in settings.extra if k not in allowed)
    if unknown:
        raise TypeError(f"method {method!r} takes no keyword argument(s) "
                        f"{', '.join(map(repr, unknown))}")
    return settings.dt, steps_for(settings.dt, settings.t_end)
