"""Code generation: sympy residuals -> plain scalar Python kernels.

:mod:`.rewrite` prepares an expression (kinks -> ``Piecewise``, branch-wise derivatives,
magnitude of the terms); :mod:`.emit` prints, compiles and caches the kernels;
:mod:`.branches` splits a law into its smooth branches (selector, per-branch kernels,
guard functions, locking branches) for the event model.
"""

from .branches import BranchInfo, LawBranches, law_branches
from .emit import Kernel, compile_function, compile_kernel
from .rewrite import check_supported, diff_branchwise, magnitude_expression, prepare, rewrite_kinks

__all__ = [
    "BranchInfo",
    "LawBranches",
    "law_branches",
    "Kernel",
    "check_supported",
    "compile_function",
    "compile_kernel",
    "diff_branchwise",
    "magnitude_expression",
    "prepare",
    "rewrite_kinks",
]
