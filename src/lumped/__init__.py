"""lumped: vibrating lumped-parameter systems with implicit constitutive laws.

Elements are declared by implicit residuals ``alpha(x, F_s) = 0`` (springs) or
``beta(v, F_d) = 0`` (dashpots); a scene of masses and elements is a semi-explicit
DAE, advanced by BDF1/BDF2 with a semismooth Newton solver (:func:`simulate`).  For one
mass with a linear spring and a Bingham dashpot the step has a closed form (the paper's
Algorithm 1, :func:`integrate`), and :mod:`lumped.reference` gives the exact solution.
"""

from .bingham import BinghamOscillator, bdf1_step, bdf2_step, integrate
from .compare import compare
from .forcing import SineBurst, paper_F1, paper_F2, zero_forcing
from .laws import BUILTIN_LAWS, BoundLaw, ElementLaw, get_law
from .scene import GROUND, Element, Junction, Mass, Scene
from .scenefile import load_scene
from .simulate import (
    METHODS,
    BranchError,
    InconsistentInitialForce,
    Solution,
    SolverError,
    Status,
    simulate,
)
from .trajectory import StickSummary, Trajectory, summarize

__version__ = "0.1.0"

#: Names served lazily: the exact reference pulls in scipy.optimize, which only it needs.
_LAZY = {name: "reference" for name in
         ("ExactSolution", "ReferenceNotApplicable", "exact_solution", "reference_for_grid")}


def __getattr__(name: str):
    if name in _LAZY:
        import importlib

        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module 'lumped' has no attribute {name!r}")

__all__ = [
    "BUILTIN_LAWS",
    "GROUND",
    "METHODS",
    "BinghamOscillator",
    "BoundLaw",
    "BranchError",
    "Element",
    "ElementLaw",
    "ExactSolution",
    "InconsistentInitialForce",
    "Junction",
    "Mass",
    "ReferenceNotApplicable",
    "Scene",
    "SineBurst",
    "Solution",
    "SolverError",
    "Status",
    "StickSummary",
    "Trajectory",
    "__version__",
    "bdf1_step",
    "bdf2_step",
    "compare",
    "exact_solution",
    "get_law",
    "integrate",
    "load_scene",
    "paper_F1",
    "paper_F2",
    "reference_for_grid",
    "simulate",
    "summarize",
    "zero_forcing",
]
