"""Solvers: the method families over a shared Newton, along the data flow.

The sub-packages are layers, each importing only those below it (an import-linter
contract in ``pyproject.toml``)::

    registry -> eventdriven -> modes -> {closed, bdf, radau} -> implicit -> nonsmooth
             -> newton -> status

:mod:`.status` (outcomes, :class:`Event`, the runner contract :class:`RunSettings` ->
:class:`RawRun`), :mod:`.newton`, :mod:`.nonsmooth`, :mod:`.implicit`, the families
:mod:`.closed`, :mod:`.bdf` and :mod:`.radau`, :mod:`.modes`, :mod:`.eventdriven`
(``radau5``) and :mod:`.registry` (name -> runner). See ``docs/architecture.md``.
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
