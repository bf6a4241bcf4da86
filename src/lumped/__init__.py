"""lumped: vibrating lumped-parameter systems with implicit constitutive laws.

Elements are declared by implicit residuals ``alpha(x, F_s) = 0`` (springs) or
``beta(v, F_d) = 0`` (dashpots); a scene of masses and elements is a semi-explicit
DAE, advanced by BDF1/BDF2.  For one mass with a linear spring and a Bingham dashpot
the step has a closed form (the paper's Algorithm 1), available here as the fast path.
"""

from .bingham import BinghamOscillator, bdf1_step, bdf2_step, integrate
from .forcing import SineBurst, paper_F1, paper_F2, zero_forcing
from .trajectory import StickSummary, Trajectory, summarize

__version__ = "0.1.0"

__all__ = [
    "BinghamOscillator",
    "SineBurst",
    "StickSummary",
    "Trajectory",
    "__version__",
    "bdf1_step",
    "bdf2_step",
    "integrate",
    "paper_F1",
    "paper_F2",
    "summarize",
    "zero_forcing",
]
