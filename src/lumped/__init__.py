"""lumped: vibrating lumped-parameter systems with implicit constitutive laws.

Elements are declared by implicit residuals ``alpha(x, F_s) = 0`` (springs) or
``beta(v, F_d) = 0`` (dashpots); a scene of masses and elements is a semi-explicit
DAE, advanced by BDF1/BDF2 with a semismooth Newton solver (:func:`simulate`).  For one
mass with a linear spring and a Bingham dashpot the step has a closed form (the paper's
Algorithm 1, :func:`lumped.solvers.closed.integrate.integrate`), and :mod:`lumped.reference`
gives the exact solution.

The top level holds only the everyday names; everything else lives in its sub-package
(``lumped.laws``, ``lumped.scene``, ``lumped.codegen``, ``lumped.solvers``,
``lumped.reference``, ``lumped.bench``, ``lumped.io``, ``lumped.cli``; see
docs/architecture.md).  Names that used to be exported here are still served, with a
``DeprecationWarning`` naming their new home, for one release.
"""

from .io.scenefile import load_scene
from .laws import ElementLaw, get_law
from .result import Solution
from .scene import GROUND, Element, Junction, Mass, Scene
from .simulate import simulate
from .solvers.status import BranchError, InconsistentInitialForce, SolverError, Status

__version__ = "0.1.0"

#: Former top-level names -> the module that now holds them (served with a warning).
_MOVED = {
    "BinghamOscillator": "lumped.solvers.closed.closed_form",
    "bdf1_step": "lumped.solvers.closed.closed_form",
    "bdf2_step": "lumped.solvers.closed.closed_form",
    "integrate": "lumped.solvers.closed.closed_form",
    "compare": "lumped.compare",
    "SineBurst": "lumped.scene",
    "paper_F1": "lumped.scene",
    "paper_F2": "lumped.scene",
    "zero_forcing": "lumped.scene",
    "BUILTIN_LAWS": "lumped.laws",
    "BoundLaw": "lumped.laws",
    "METHODS": "lumped.solvers.registry",
    "StickSummary": "lumped.trajectory",
    "Trajectory": "lumped.trajectory",
    "summarize": "lumped.trajectory",
    "ExactSolution": "lumped.reference",
    "ReferenceNotApplicable": "lumped.reference",
    "exact_solution": "lumped.reference",
    "reference_for_grid": "lumped.reference",
}


#: The old single-mass front door: what to use instead (the warning says so).
_SUPERSEDED = {
    "integrate": "lumped.simulate(lumped.scene.bingham_oscillator(m, k, gamma, tau, x0=..., "
                 "v0=..., forcing=...), method='closed-bdf1' or 'closed-bdf2', dt=..., "
                 "t_end=...), which returns a lumped.Solution",
    "BinghamOscillator": "lumped.scene.bingham_oscillator(m, k, gamma, tau, ...), a Scene "
                         "to pass to lumped.simulate",
    "Trajectory": "lumped.Solution, what lumped.simulate returns (x, v, F by name)",
    "summarize": "lumped.Solution.stick_intervals() of the result of lumped.simulate",
    "StickSummary": "lumped.Solution.stick_intervals() of the result of lumped.simulate",
}


def __getattr__(name: str):
    home = _MOVED.get(name)
    if home is None:
        raise AttributeError(f"module 'lumped' has no attribute {name!r}")
    import importlib
    import warnings

    advice = (f"use {_SUPERSEDED[name]} (or import it from `{home}`)"
              if name in _SUPERSEDED else f"import it from `{home}` instead")
    warnings.warn(
        f"`lumped.{name}` is deprecated and will be removed in the next release; {advice}",
        DeprecationWarning,
        stacklevel=2,
    )
    return getattr(importlib.import_module(home), name)


__all__ = [
    "GROUND",
    "BranchError",
    "Element",
    "ElementLaw",
    "InconsistentInitialForce",
    "Junction",
    "Mass",
    "Scene",
    "Solution",
    "SolverError",
    "Status",
    "__version__",
    "get_law",
    "load_scene",
    "simulate",
]
