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
docs/architecture.md).  The names that 0.1 still served here with a
``DeprecationWarning`` (``integrate``, ``BinghamOscillator``, ``Trajectory``, ...) are
gone since 0.2: import them from their sub-packages (see the CHANGELOG).
"""

from .io.scenefile import load_scene
from .laws import ElementLaw, get_law
from .result import Solution
from .scene import GROUND, Element, Junction, Mass, Scene
from .simulate import simulate
from .solvers.status import BranchError, InconsistentInitialForce, SolverError, Status

__version__ = "0.2.0"

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
