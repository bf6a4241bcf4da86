r"""The force on one node at one time, for the generated fast loops of ``jit-bdf1``/``jit-bdf2``.

:func:`force_at` is the arithmetic of :func:`lumped.scene.forcing_jit.forcing_into` for
one node. It is compiled once per machine (numba's disk cache beside the package) and
called by every structure's generated loop (:mod:`lumped.solvers.bdf.fast_codegen`);
LLVM inlines it there. Generated into each structure's module it cost a compilation per
new structure (about 0.1 s of CPU).
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.jit import njit
from ...scene.forcing_jit import FORCE_CONSTANT, FORCE_SINE, FORCE_TABLE

__all__ = ["force_at"]


@njit(cache=True)
def force_at(fk: int, fa: float, fw: float, ft: float, t: float, ftab: np.ndarray,
             step: int, i: int) -> float:
    """Node ``i``'s force at ``t`` (step ``step``) for forcing kind ``fk`` with parameters
    ``fa, fw, ft`` (:mod:`lumped.scene.forcing_jit`): the sine burst ``fa sin(fw t)`` for
    ``t <= ft``, the constant ``fa``, the tabulated ``ftab[step, i]``; else 0."""
    if fk == FORCE_SINE:
        return 0.0 if t > ft else fa * math.sin(fw * t)
    if fk == FORCE_CONSTANT:
        return fa
    if fk == FORCE_TABLE:
        return ftab[step, i]
    return 0.0
