"""The first guard crossing's root on one attempt of ``radau5``'s compiled loop, compiled
apart from :func:`lumped.solvers.eventdriven.loop_jit.advance` (only when a process lands
on events often; the Python loop's own crossing test before)."""

from __future__ import annotations

from ...codegen.function_types import function_at, guards_type
from ...codegen.jit import numba_enabled
from ..modes.crossing_root import first_root
from ..modes.on_demand import compiled_once
from .loop_jit import A_HIT, A_J, A_ROOT, A_W, H

__all__ = ["attempt_root", "compiled_attempt_root"]


def attempt_root(guards_addr, lawc, ea, eb, spring, modes, watched, A, x, v, F, fst, ist, ws,
                 wm) -> None:
    """After an attempt (``ist[SINGLE] = 1``, solved, ``ist[A_OK] = 1``): the first
    crossing's root on the attempt's step into ``fst[A_ROOT]`` (``-1.0`` if none), on guard
    ``ist[A_J]`` of watched element ``ist[A_W]``, and ``ist[A_HIT]``
    (:func:`lumped.solvers.modes.crossing_root.first_root`, the Python loop's algorithm).
    Apart from :func:`~lumped.solvers.eventdriven.loop_jit.advance`
    (:func:`compiled_attempt_root`): compiled only when a process lands often, the Python
    loop's own crossing test before."""
    N = x.shape[0]
    n = N + ea.shape[0]
    nw = max(watched.shape[0], 1)
    fst[A_ROOT] = first_root(_guards_at(guards_addr), lawc, ea, eb, spring, modes, watched, A,
                             fst[H], x, v, F, ws[0, :3 * n], N, n, wm[5, :nw, :4],
                             wm[6, :nw, :4], ws[8], ist[A_W:A_J + 1])
    ist[A_HIT] = fst[A_ROOT] >= 0.0


if numba_enabled():
    _guards_at = function_at(guards_type())

_ROOT: list = []


def compiled_attempt_root(compile: bool = True):
    """:func:`attempt_root` compiled once for every scene (numba's disk cache after the
    first time on a machine), or ``None`` without numba; ``compile=False``: only if numba's
    disk cache holds it (:func:`lumped.solvers.modes.on_demand.compiled_once`)."""
    return compiled_once(_ROOT, attempt_root, _root_signature, compile)


def _root_signature():
    from numba import types as T_

    f8, i8 = T_.float64, T_.int64
    v, m, m3, iv = f8[::1], f8[:, ::1], f8[:, :, ::1], i8[::1]
    return T_.none(i8, v, iv, iv, T_.boolean[::1], iv, iv, m, v, v, v, v, iv, m, m3)
