r"""The external forces of ``radau5``'s compiled loop, the table's code compiled only where a
scene has a table.

:func:`forces` evaluates the forcing of :func:`lumped.scene.forcing_jit.forcing_into` at
any time ``t`` for the kinds an adaptive step meets (:data:`FORCE_NONE`,
:data:`FORCE_CONSTANT`, :data:`FORCE_SINE`, :data:`FORCE_LINEAR`), with the same
arithmetic and order (the same doubles; a non-finite value is written and ends the
evaluation, later nodes keep 0). A linearly interpolated table (its bisection, its two
interpolants and an added constant or sine burst) is most of that code; it is reached
through an address, :func:`table_forcing`, the function :func:`table_value` compiled
apart, so that the shared loop (:mod:`lumped.solvers.eventdriven.loop_jit`), compiled once
per machine, holds none of it: a machine whose first scene has no table never compiles
it (about a second of CPU of a first run, and the loop's optimiser and code emission on
it), and a scene with a table compiles this one function once (numba's disk cache after
that).
"""

from __future__ import annotations

import math

from ...codegen.function_types import compiled_address, function_at
from ...codegen.jit import njit, numba_enabled
from ...scene.forcing_jit import FORCE_CONSTANT, FORCE_LINEAR, FORCE_SINE, linear_value

__all__ = ["forces", "table_value", "table_forcing", "TABLE_TYPE"]


@njit(cache=True)
def forces(t, fkind, fpar, table, f) -> None:
    """``f_i(t)`` per node (``scene.external_forces``): 0 where there is no forcing.

    ``fkind, fpar``: :func:`lumped.scene.forcing_jit.forcing_arrays` with ``linear=True``
    (no sampled kind); ``table``: the address of :func:`table_value` compiled
    (:func:`table_forcing`) if some ``fkind`` is :data:`FORCE_LINEAR`, else unused (0)."""
    for i in range(f.shape[0]):
        f[i] = 0.0
    for i in range(f.shape[0]):
        k = fkind[i]
        if k == FORCE_LINEAR:
            val = _table_at(table)(i, t, fpar)
        elif k == FORCE_SINE:
            val = 0.0 if t > fpar[i, 2] else fpar[i, 0] * math.sin(fpar[i, 1] * t)
        else:  # FORCE_CONSTANT or FORCE_NONE (0.0 again)
            val = fpar[i, 0] if k == FORCE_CONSTANT else 0.0
        f[i] = val
        if not math.isfinite(val):
            return


def table_value(i, t, fpar) -> float:
    """Node ``i``'s linearly interpolated table at ``t``
    (:func:`lumped.scene.forcing_jit.linear_value`, the Python callable's arithmetic)."""
    return linear_value(i, t, fpar)


if numba_enabled():
    from numba import types as _T

    #: The numba function type of :func:`table_value`.
    TABLE_TYPE = _T.FunctionType(_T.float64(_T.int64, _T.float64, _T.float64[:, ::1]))
    _table_at = function_at(TABLE_TYPE)
else:  # pragma: no cover - without numba
    TABLE_TYPE = None
_TABLE: list = []


def table_forcing() -> int:
    """The address of :func:`table_value` compiled (once per process; numba's disk cache
    after the first time on a machine), for a scene with a table forcing."""
    return compiled_address(_TABLE, table_value, TABLE_TYPE)
