r"""The forcing as data for compiled code: one encoding for every compiled loop.

A node's forcing is a kind and three parameters:

* :data:`FORCE_NONE` (0): no force;
* :data:`FORCE_CONSTANT` (1): ``F = p0`` (a number given as a forcing,
  :class:`lumped.scene.network.ConstantForce`);
* :data:`FORCE_SINE` (2): the sine burst ``F = p0 sin(p1 t)`` for ``t <= p2``, ``0`` after
  (:class:`lumped.scene.SineBurst`);
* :data:`FORCE_TABLE` (3): any other callable, sampled in Python on the step grid into a
  table the loop reads by step.

:func:`forcing_code` encodes one forcing, :func:`forcing_arrays` a scene's (``fkind,
fpar, ftab``), and :func:`forcing_into` evaluates them in compiled code. Positive ``F``
pushes its node towards positive ``x``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np

from ..codegen.jit import njit

if TYPE_CHECKING:
    from .network import Scene

__all__ = ["FORCE_NONE", "FORCE_CONSTANT", "FORCE_SINE", "FORCE_TABLE", "forcing_code",
           "forcing_arrays", "forcing_into"]

FORCE_NONE, FORCE_CONSTANT, FORCE_SINE, FORCE_TABLE = 0, 1, 2, 3


def forcing_code(forcing: Callable[[float], float] | None) -> tuple[int, float, float, float]:
    """``(kind, p0, p1, p2)`` of one forcing (see the module notes).

    ``None`` and :func:`lumped.scene.zero_forcing` give :data:`FORCE_NONE`; anything that
    is neither a constant nor a sine burst gives :data:`FORCE_TABLE`: the caller samples
    it on its grid.
    """
    from .forcing import SineBurst, zero_forcing
    from .network import ConstantForce

    if forcing is None or forcing is zero_forcing:
        return FORCE_NONE, 0.0, 0.0, 0.0
    if isinstance(forcing, SineBurst):
        return FORCE_SINE, float(forcing.amplitude), float(forcing.omega), float(forcing.t_off)
    if isinstance(forcing, ConstantForce):
        return FORCE_CONSTANT, float(forcing.value), 0.0, 0.0
    return FORCE_TABLE, 0.0, 0.0, 0.0


def forcing_arrays(scene: Scene, dt: float, n_steps: int):
    """``(fkind, fpar, ftab)`` of :func:`forcing_into` for the scene's nodes on the grid
    ``t_n = n dt``, ``n <= n_steps`` (``ftab`` holds the sampled forcings' values by step,
    one row when nothing is sampled)."""
    from .forcing import SineBurst

    N = len(scene.nodes)
    fkind = np.zeros(N, dtype=np.int64)
    fpar = np.zeros((N, 3))
    tabulated = [i for i, fn in enumerate(scene.forcing)
                 if fn is not None and not isinstance(fn, SineBurst) and not _constant(fn)]
    ftab = np.zeros((n_steps + 1 if tabulated else 1, N))
    for i, fn in enumerate(scene.forcing):
        if fn is None:
            continue
        if isinstance(fn, SineBurst):
            fkind[i] = FORCE_SINE
            fpar[i] = (fn.amplitude, fn.omega, fn.t_off)
        elif _constant(fn):
            fkind[i] = FORCE_CONSTANT
            fpar[i, 0] = fn.value
        else:  # any other callable, zero_forcing included: sampled on the step grid
            fkind[i] = FORCE_TABLE
            col = ftab[:, i]
            for step in range(1, n_steps + 1):
                # a non-finite value is reported by the loop when it reaches that step
                col[step] = float(fn(step * dt))
    return fkind, fpar, ftab


def _constant(fn) -> bool:
    """A constant force of :func:`lumped.scene.as_forcing` (``fn.value`` for every ``t``)."""
    from .network import ConstantForce

    return type(fn) is ConstantForce


@njit(cache=True, inline="always")
def forcing_into(step, t, fkind, fpar, ftab, f) -> int:
    """Write ``f_i(t)`` into ``f``; return the first node whose force is not finite, or -1."""
    for i in range(f.shape[0]):
        k = fkind[i]
        if k == FORCE_NONE:
            continue
        if k == FORCE_CONSTANT:
            val = fpar[i, 0]
        elif k == FORCE_SINE:
            val = 0.0 if t > fpar[i, 2] else fpar[i, 0] * math.sin(fpar[i, 1] * t)
        else:
            val = ftab[step, i]
        if not math.isfinite(val):
            f[i] = val
            return i
        f[i] = val
    return -1
