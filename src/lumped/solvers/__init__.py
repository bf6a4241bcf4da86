"""Solvers: one module per method family, a shared Newton solver and one registry.

:mod:`.status` (outcomes, :class:`Event`, :class:`RawRun`), :mod:`.newton` and
:mod:`.linalg` (semismooth Newton, small LU), :mod:`.step_system` (the discrete system of
one implicit step), :mod:`.initial_state`, :mod:`.branch_check`, :mod:`.fixed_step`
(generic BDF1/BDF2), :mod:`.closed_form` (Algorithm 1 and its BDF2 twin) and
:mod:`.registry` (name -> runner).
"""

from ..grid import steps_for
from .bdf.fixed_step import GENERIC_METHODS, RunResult, run_bdf
from .closed.closed_form import BinghamOscillator, bdf1_step, bdf2_step
from .closed.integrate import integrate
from .implicit.initial_state import consistent_initial_state
from .newton.options import NewtonCode, NewtonOptions, NewtonResult
from .newton.semismooth import newton_solve
from .registry import (
    FIXED_STEP_METHODS,
    METHOD_REGISTRY,
    RunSettings,
    closed_form_oscillator,
    register_method,
    resolve_method,
)
from .status import BranchError, Event, InconsistentInitialForce, RawRun, SolverError, Status

__all__ = [
    "FIXED_STEP_METHODS",
    "GENERIC_METHODS",
    "METHOD_REGISTRY",
    "BinghamOscillator",
    "BranchError",
    "Event",
    "InconsistentInitialForce",
    "NewtonCode",
    "NewtonOptions",
    "NewtonResult",
    "RawRun",
    "RunResult",
    "RunSettings",
    "SolverError",
    "Status",
    "bdf1_step",
    "bdf2_step",
    "closed_form_oscillator",
    "consistent_initial_state",
    "integrate",
    "newton_solve",
    "register_method",
    "resolve_method",
    "run_bdf",
    "steps_for",
]
