r"""The forcing as data for compiled code: one encoding for every compiled loop.

A node's forcing is a kind and three parameters:

* :data:`FORCE_NONE` (0): no force;
* :data:`FORCE_CONSTANT` (1): ``F = p0`` (a number given as a forcing,
  :class:`lumped.scene.forcing_spec.ConstantForce`);
* :data:`FORCE_SINE` (2): the sine burst ``F = p0 sin(p1 t)`` for ``t <= p2``, ``0`` after
  (:class:`lumped.scene.SineBurst`);
* :data:`FORCE_TABLE` (3): any other callable, sampled in Python on the step grid into a
  table the loop reads by step;
* :data:`FORCE_LINEAR` (4, only where :func:`forcing_arrays` is asked ``linear=True``: an
  adaptive method's loop, which evaluates the forcing at any time): a linearly
  interpolated table, a :class:`lumped.io.Table` of a force or the inertial force
  ``-m a_g(t)`` of a ground acceleration read from a record
  (:class:`lumped.scene.GroundMotion`), evaluated by :func:`linear_value` with the
  Python callable's own arithmetic (the same numbers bit for bit). Its row of ``fpar``
  holds ``n, mode, scale, before, after``, an added constant or sine burst (``kind, p0,
  p1, p2``: the other part of a sum such as an applied force beside a ground record,
  kind 0 where there is none), the times and two arrays of values (see
  :func:`linear_row`), so ``fpar`` is as wide as the longest table needs.

:func:`forcing_code` encodes one forcing, :func:`forcing_arrays` a scene's (``fkind,
fpar, ftab``), :func:`forcing_into` evaluates them in compiled code and :func:`loads_at`
at many times with numpy (nothing compiled: the Python loop's dense output). Positive
``F`` pushes its node towards positive ``x``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..codegen.jit import njit
from .forcing import SineBurst, zero_forcing
from .forcing_spec import ConstantForce

if TYPE_CHECKING:
    from .network import Scene

__all__ = ["FORCE_NONE", "FORCE_CONSTANT", "FORCE_SINE", "FORCE_TABLE", "FORCE_LINEAR",
           "forcing_code", "forcing_arrays", "forcing_into", "linear_row", "linear_value",
           "loads_at"]

FORCE_NONE, FORCE_CONSTANT, FORCE_SINE, FORCE_TABLE, FORCE_LINEAR = 0, 1, 2, 3, 4
#: The two interpolants of :data:`FORCE_LINEAR`: :class:`lumped.io.Table`'s (``y_k +
#: (t - t_k) / (t_{k+1} - t_k) (y_{k+1} - y_k)``, ``before``/``after`` outside, ``y_{n-1}``
#: at ``t_{n-1}``), and the ground motion's acceleration (``a_k + s_k (t - t_k)`` on the
#: segment of ``min(bisect_right(t) - 1, n - 2)``, ``before``/``after`` beyond the ends).
LINEAR_TABLE, LINEAR_MOTION = 0, 1
#: ``fpar`` columns before a :data:`FORCE_LINEAR` table's times: ``n, mode, scale, before,
#: after`` and the added part's ``kind, p0, p1, p2`` (from :data:`LINEAR_ADD` on).
LINEAR_HEAD = 9
LINEAR_ADD = 5


def linear_row(forcing) -> np.ndarray | None:
    """The :data:`FORCE_LINEAR` row of ``forcing``, or ``None`` for a forcing that is not
    a linearly interpolated table, or the sum of one and a constant or a sine burst.

    A table describes itself by ``interpolant()`` (:meth:`lumped.io.Table.interpolant`);
    a forcing without one, or whose ``interpolant()`` gives ``None``, is not a table. The
    row is ``n, mode, scale, before, after``, the added part ``kind, p0, p1, p2``
    (:func:`forcing_code` of the sum's other part; kind 0 for a table alone), then the
    ``n`` times, then ``p`` and ``r``: ``p = r = y`` for a table (``mode``
    :data:`LINEAR_TABLE`), the segments' start values ``a`` and slopes ``s`` for a ground
    motion (:data:`LINEAR_MOTION`); ``scale`` multiplies the value (the ``-m`` of an
    inertial force, else 1). A sum of two parts (:func:`lumped.scene.combine_forcing`:
    an applied force and the inertial force of a ground motion) adds them as the Python
    sum does: ``f = g(t) + table(t)``, one addition, the same double."""
    from .inertial import SumForcing

    added: tuple[int, float, float, float] = (FORCE_NONE, 0.0, 0.0, 0.0)
    if isinstance(forcing, SumForcing):
        if len(forcing.parts) != 2:
            return None
        codes = [forcing_code(fn) for fn in forcing.parts]
        simple = [k for k, code in enumerate(codes) if code[0] in (FORCE_CONSTANT, FORCE_SINE)]
        if len(simple) != 1:
            return None
        added = codes[simple[0]]
        forcing = forcing.parts[1 - simple[0]]
    get = getattr(forcing, "interpolant", None)
    parts = get() if callable(get) else None
    if parts is None:
        return None
    kind, t, p, r, before, after, scale = parts
    mode = {"table": LINEAR_TABLE, "motion": LINEAR_MOTION}[kind]
    return np.array([float(len(t)), float(mode), scale, before, after, float(added[0]),
                     *added[1:], *t, *p, *r])


@njit(cache=True, inline="always")
def _segment(i, t, fpar, n) -> int:
    """The last ``k < n - 1`` with ``t_k <= t`` of node ``i``'s table (``bisect_right - 1``
    for ``t_0 <= t < t_{n-1}``)."""
    lo, hi = 0, n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if fpar[i, LINEAR_HEAD + mid] <= t:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True, inline="always")
def linear_value(i, t, fpar) -> float:
    """Node ``i``'s :data:`FORCE_LINEAR` forcing at ``t``: the arithmetic of the Python
    callable (:func:`linear_row`), so the same double."""
    value = _table_value(i, t, fpar)
    k = fpar[i, LINEAR_ADD]
    if k == FORCE_NONE:
        return value
    if k == FORCE_CONSTANT:
        return fpar[i, LINEAR_ADD + 1] + value
    added = (0.0 if t > fpar[i, LINEAR_ADD + 3]
             else fpar[i, LINEAR_ADD + 1] * math.sin(fpar[i, LINEAR_ADD + 2] * t))
    return added + value


@njit(cache=True, inline="always")
def _table_value(i, t, fpar) -> float:
    """The table part of node ``i``'s :data:`FORCE_LINEAR` row at ``t``."""
    n = int(fpar[i, 0])
    h = LINEAR_HEAD
    t0 = fpar[i, h]
    tl = fpar[i, h + n - 1]
    scale = fpar[i, 2]
    if fpar[i, 1] == LINEAR_TABLE:
        if not (t0 <= t and t < tl):
            if t == tl:
                return scale * fpar[i, h + 2 * n - 1]
            return scale * (fpar[i, 3] if t < t0 else fpar[i, 4])
        lo = _segment(i, t, fpar, n)
        tk = fpar[i, h + lo]
        yk = fpar[i, h + n + lo]
        if t == tk:
            return scale * yk
        return scale * (yk + (t - tk) / (fpar[i, h + lo + 1] - tk)
                        * (fpar[i, h + n + lo + 1] - yk))
    if t < t0:
        return scale * fpar[i, 3]
    if t > tl:
        return scale * fpar[i, 4]
    k = min(_segment(i, t, fpar, n), n - 2) if t < tl else n - 2
    return scale * (fpar[i, h + n + k] + fpar[i, h + 2 * n - 1 + k] * (t - fpar[i, h + k]))


def forcing_code(forcing: Callable[[float], float] | None) -> tuple[int, float, float, float]:
    """``(kind, p0, p1, p2)`` of one forcing (see the module notes).

    ``None`` and :func:`lumped.scene.zero_forcing` give :data:`FORCE_NONE`; anything that
    is neither a constant nor a sine burst gives :data:`FORCE_TABLE`: the caller samples
    it on its grid.
    """

    if forcing is None or forcing is zero_forcing:
        return FORCE_NONE, 0.0, 0.0, 0.0
    if isinstance(forcing, SineBurst):
        return FORCE_SINE, float(forcing.amplitude), float(forcing.omega), float(forcing.t_off)
    if isinstance(forcing, ConstantForce):
        return FORCE_CONSTANT, float(forcing.value), 0.0, 0.0
    return FORCE_TABLE, 0.0, 0.0, 0.0


def forcing_arrays(scene: Scene, dt: float, n_steps: int, *, linear: bool = False):
    """``(fkind, fpar, ftab)`` of :func:`forcing_into` for the scene's nodes on the grid
    ``t_n = n dt``, ``n <= n_steps`` (``ftab`` holds the sampled forcings' values by step,
    one row when nothing is sampled). With ``linear``, a linearly interpolated table
    (:func:`linear_row`) is :data:`FORCE_LINEAR` instead of sampled."""
    N = len(scene.nodes)
    fkind = np.zeros(N, dtype=np.int64)
    rows = {i: linear_row(fn) for i, fn in enumerate(scene.forcing)} if linear else {}
    rows = {i: row for i, row in rows.items() if row is not None}
    fpar = np.zeros((N, max([3] + [len(row) for row in rows.values()])))
    for i, row in rows.items():
        fkind[i] = FORCE_LINEAR
        fpar[i, :len(row)] = row
    tabulated = [i for i, fn in enumerate(scene.forcing)
                 if fn is not None and not isinstance(fn, SineBurst) and not _constant(fn)
                 and i not in rows]
    ftab = np.zeros((n_steps + 1 if tabulated else 1, N))
    for i, fn in enumerate(scene.forcing):
        if fn is None or i in rows:
            continue
        if isinstance(fn, SineBurst):
            fkind[i] = FORCE_SINE
            fpar[i, :3] = (fn.amplitude, fn.omega, fn.t_off)
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
        elif k == FORCE_LINEAR:
            val = linear_value(i, t, fpar)
        else:
            val = ftab[step, i]
        if not math.isfinite(val):
            f[i] = val
            return i
        f[i] = val
    return -1


def loads_at(fkind: np.ndarray, fpar: np.ndarray, ts: np.ndarray,
             forcing: Sequence[Callable[[float], float] | None] = ()) -> np.ndarray:
    r"""``f_i(t)`` per node at the times ``ts``, ``(len(ts), N)``, by the kind codes
    (:func:`forcing_arrays`) with numpy, nothing compiled.

    :data:`FORCE_CONSTANT` is ``p0``; :data:`FORCE_SINE` is ``p0 sin(p1 t)`` for ``t <=
    p2``, ``0`` after (numpy's ``sin``); :data:`FORCE_LINEAR` is :func:`linear_value`'s
    arithmetic, operation by operation, on arrays (the same doubles); only
    :data:`FORCE_TABLE`, a callable without a kind code, is called once per time,
    ``forcing[i](t)`` (:func:`lumped.scene.zero_forcing`, sampled by
    :func:`forcing_arrays`, is ``0`` here without a call).
    """
    out = np.zeros((len(ts), len(fkind)))
    for i, kind in enumerate(fkind.tolist()):
        if kind == FORCE_LINEAR:
            out[:, i] = _linear_at(fpar[i], ts)
        elif kind == FORCE_TABLE:
            fn = forcing[i]
            if fn is not None and fn is not zero_forcing:
                out[:, i] = [float(fn(float(t))) for t in ts]
        elif kind != FORCE_NONE:
            out[:, i] = _simple_at(kind, fpar[i], ts)
    return out


def _simple_at(kind: int, p: np.ndarray, ts: np.ndarray) -> np.ndarray | float:
    """A :data:`FORCE_CONSTANT` or :data:`FORCE_SINE` forcing ``p = (p0, p1, p2, ...)`` at
    the times ``ts`` (``p0`` for a constant)."""
    if kind == FORCE_SINE:
        return np.where(ts > p[2], 0.0, p[0] * np.sin(p[1] * ts))
    return p[0]


def _linear_at(row: np.ndarray, ts: np.ndarray) -> np.ndarray:
    """:func:`linear_value` of the :data:`FORCE_LINEAR` ``row`` at the times ``ts``."""
    n, h = int(row[0]), LINEAR_HEAD
    tt = row[h:h + n]
    t0, tl = tt[0], tt[-1]
    k = np.searchsorted(tt[1:n - 1], ts, side="right")  # (_segment's, 0 before t_0)
    tk = tt[k]
    if row[1] == LINEAR_TABLE:
        y = row[h + n:h + 2 * n]
        yk = y[k]
        value = np.where(ts == tk, yk, yk + (ts - tk) / (tt[k + 1] - tk) * (y[k + 1] - yk))
        inside = (t0 <= ts) & (ts < tl)
        if not inside.all():
            value = np.where(inside, value, np.where(
                ts == tl, y[-1], np.where(ts < t0, row[3], row[4])))
    else:  # LINEAR_MOTION: the segments' start values and slopes
        value = row[h + n + k] + row[h + 2 * n - 1 + k] * (ts - tk)
        if not ((t0 <= ts) & (ts <= tl)).all():
            value = np.where(ts < t0, row[3], np.where(ts > tl, row[4], value))
    value = row[2] * value  # (the scale)
    added = int(row[LINEAR_ADD])
    if added == FORCE_NONE:
        return value
    return _simple_at(added, row[LINEAR_ADD + 1:], ts) + value
