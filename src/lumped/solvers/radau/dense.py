r"""The dense output of the adaptive method's accepted steps: the collocation polynomial of
each step (:class:`DenseOutput`, :func:`position_weights`), evaluated by numpy or in one
compiled pass, the static balance of the stuck intervals held without steps, and on the
steps of a mode that holds nodes at rest the forces of their locks put onto their balance
(:mod:`lumped.solvers.radau.locked_forces`).

The row layout of ``data`` and the rows of a run are in :mod:`lumped.solvers.radau.rows`.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.jit import njit, numba_enabled
from .locked_forces import LockedForces
from .tableau import C, dense_weights

__all__ = ["DenseOutput", "LockedForces", "position_weights"]


def position_weights(s):
    r"""``L_k(s) = int_0^s l_k``, ``k = 1..3``: the integrals of the Lagrange weights of
    :func:`~lumped.solvers.radau.tableau.dense_weights` (``s`` a float or an array).

    The dense output of a position integrates the collocation cubic of its velocity,
    ``x(t_n + s h) = x_n + h (s v_n + sum_k L_k(s) (V_k - v_n))``: a quartic whose error
    is ``h`` times that of the velocity's cubic, ``O(h^5)`` per step, where the cubic
    through ``x_n`` and the stage positions ``X_k`` is ``O(h^4)``. It meets the step's
    ends: ``L_k(1) = b_k = a_3k`` (the 3-point Radau quadrature integrates the cubic of
    the node ``0`` to zero), so ``x(t_n + h) = X_3``, and its slope is ``v`` at both ends;
    a held position (``V_k = v_n = 0``) stays exact.
    """
    ss = s * s
    return tuple((ss * (3.0 * ss - 4.0 * (ca + cb) * s + 6.0 * ca * cb)) / (12.0 * d)
                 for ca, cb, d in _L_NODES)


class DenseOutput:
    """The collocation polynomials of the accepted steps: ``t -> rows like data``.

    Steps come one at a time (:meth:`add`, the Python loop) or as blocks of arrays
    (:meth:`extend`; the compiled loop writes its steps in place, :meth:`block` and
    :meth:`commit`); all keep the order of the steps. They are held in arrays that grow
    by doubling, so a run's steps are never concatenated.

    With ``locked`` (:class:`~lumped.solvers.radau.locked_forces.LockedForces`), each step
    carries the group of its held mode's locks (:meth:`group`; ``-1``: none), and the
    forces of the locks between nodes at rest are put onto their balance at the output
    times."""

    def __init__(self, N: int, E: int, locked: LockedForces | None = None) -> None:
        self.N, self.E = N, E
        ny = 2 * N + E
        self.locked = locked
        self._T0 = self._H = np.empty(0)
        self._G = np.empty(0, dtype=np.int64)
        self._Y0 = self._D = None  # made with the first step (a stuck run takes none)
        self._shapes = ((), (), (ny,), (3, ny))
        self._count = 0
        self._static: list[tuple[float, float, object]] = []
        self._table: tuple | None = None

    def __len__(self) -> int:
        return self._count + len(self._static)

    def add_static(self, t0: float, t1: float, hold) -> None:
        """A stuck interval ``[t0, t1]`` without steps: ``hold.y0`` (``x, v, F`` at ``t0``)
        and ``hold.forces_many(ts)``, the forces of the static balance
        (:class:`lumped.solvers.modes.stuck.StaticHold`)."""
        self._static.append((t0, t1, hold))

    def _reserve(self, k: int) -> None:
        """Room for ``k`` more steps."""
        need = self._count + k
        cap = self._T0.shape[0]
        if need > cap:
            new = max(need, 2 * cap, 64)
            n = self._count
            for name, shape in zip(("_T0", "_H", "_Y0", "_D", "_G"), self._shapes + ((),),
                                   strict=True):
                grown = np.empty((new, *shape), dtype=np.int64 if name == "_G" else float)
                if n:
                    grown[:n] = getattr(self, name)[:n]
                setattr(self, name, grown)

    def group(self, branches, modes: list[int], cones: dict) -> int:
        """The group of a held mode's locks for :meth:`add` and :meth:`commit`
        (:meth:`LockedForces.group`; ``-1`` without ``locked``)."""
        return -1 if self.locked is None else self.locked.group(branches, modes, cones)

    def add(self, t: float, h: float, y0: list[float], Y: list[list[float]],
            group: int = -1) -> None:
        """One step: its start ``t``, size ``h``, ``y_n``, the stage values ``Y_k`` and the
        group of its mode's locks (:meth:`group`)."""
        self._reserve(1)
        i = self._count
        self._T0[i], self._H[i], self._G[i] = t, h, group
        self._Y0[i] = y0
        np.subtract(Y, self._Y0[i], out=self._D[i])
        self._count += 1

    def extend(self, t0: np.ndarray, h: np.ndarray, y0: np.ndarray, D: np.ndarray) -> None:
        """A block of steps: starts, sizes, ``y_n`` rows and ``Y_k - y_n`` (copied)."""
        k = len(t0)
        if k:
            T0, H, Y0, D_ = self.block(k)
            T0[:], H[:], Y0[:], D_[:] = t0, h, y0, D
            self.commit(k)

    def block(self, k: int) -> tuple[np.ndarray, ...]:
        """Views ``(T0, H, Y0, D)`` of room for the next ``k`` steps, to be written in
        place (by the compiled loop) and kept with :meth:`commit`."""
        self._reserve(k)
        a, b = self._count, self._count + k
        return self._T0[a:b], self._H[a:b], self._Y0[a:b], self._D[a:b]

    def commit(self, k: int, group: int = -1) -> None:
        """Keep the first ``k`` steps written into the last :meth:`block`, all of one mode
        (the group of its locks: :meth:`group`)."""
        self._G[self._count:self._count + k] = group
        self._count += k

    def _arrays(self) -> tuple[np.ndarray, ...]:
        n = self._count
        return self._T0[:n], self._H[:n], self._Y0[:n], self._D[:n]

    def span(self) -> tuple[float, float]:
        """``(t_lo, t_hi)``: the interval the steps and the held (stuck) segments cover
        (``(inf, -inf)`` when empty)."""
        t_lo, t_hi = math.inf, -math.inf
        if self._count:
            T0, H = self._arrays()[:2]
            t_lo, t_hi = T0[0], T0[-1] + H[-1]
        for s0, s1, _ in self._static:
            t_lo, t_hi = min(t_lo, s0), max(t_hi, s1)
        return t_lo, t_hi

    def __call__(self, t) -> np.ndarray:
        """Rows ``(t, x_i, v_i per node, F_e)`` at the times ``t`` (vectorised). At a step
        boundary the later step is used (right limits: the forces after an event)."""
        ts = np.atleast_1d(np.asarray(t, dtype=float))
        N = self.N
        if not len(self):
            raise ValueError("no step was taken: the dense output is empty")
        t_lo, t_hi = self.span()
        if self._count:
            T0, H, Y0, D = self._arrays()
        out = np.empty((len(ts), 1 + 2 * N + self.E))
        if numba_enabled():  # the same numbers, in one compiled pass per part
            self._compiled(ts, t_lo, t_hi, out)
            self._locked(ts, t_hi, out)
            return out
        bad = ~((ts >= t_lo) & (ts <= t_hi))
        if bad.any():
            raise ValueError(f"`t` = {ts[bad][0]!r} is outside the solved interval "
                             f"[{t_lo!r}, {t_hi!r}]")
        if self._count:
            self._polynomials(ts, out)
        for s0, s1, hold in self._static:
            # [s0, s1): a step that starts at s1 owns s1 (right limits); the end is closed
            # when nothing follows
            closed = s1 == t_hi and not (self._count and bool(np.isin(s1, T0)))
            inside = (ts >= s0) & ((ts < s1) | ((ts == s1) & closed))
            if inside.any():
                sel = ts[inside]
                y0 = hold.y0
                rows = np.empty((len(sel), out.shape[1]))
                rows[:, 0] = sel
                rows[:, 1:1 + 2 * N:2] = y0[:N]
                rows[:, 2:2 + 2 * N:2] = y0[N:2 * N]
                rows[:, 1 + 2 * N:] = hold.forces_many(sel)
                out[inside] = rows
        self._locked(ts, t_hi, out)
        return out

    def _locked(self, ts: np.ndarray, t_hi: float, out: np.ndarray) -> None:
        """The forces of the locks between nodes at rest onto their balance, on the rows
        of steps (:meth:`LockedForces.correct`; not those of the stuck intervals)."""
        if self.locked is None or not self._count or not (self._G[:self._count] >= 0).any():
            return
        skip = np.zeros(len(ts), dtype=bool)
        if self._static:
            for s0, s1, closed in zip(*self._static_table(t_hi), strict=True):
                skip |= (ts >= s0) & ((ts < s1) | ((ts == s1) & closed))
        T0, H, Y0, D = self._arrays()
        self.locked.correct(ts, out, T0, H, Y0, D, self._G[:self._count], skip)

    def _compiled(self, ts: np.ndarray, t_lo: float, t_hi: float, out: np.ndarray) -> None:
        """:meth:`__call__` compiled: the numpy path's rows, each evaluated once (a row in a
        stuck interval by the static balance only; with sorted times the steps are walked
        and each stuck interval fills only its own range of rows)."""
        bad, ordered = _scan_times(ts, t_lo, t_hi)
        if bad >= 0:
            raise ValueError(f"`t` = {ts[bad]!r} is outside the solved interval "
                             f"[{t_lo!r}, {t_hi!r}]")
        if self._count:
            S0, S1, closed = self._static_table(t_hi)
            _evaluate(*self._arrays(), ts, self.N, out, S0, S1, closed, ordered)
        else:  # held segments only: each is closed at the end of the solved interval
            closed = [s1 == t_hi for _, s1, _ in self._static]
        for k, (s0, s1, hold) in enumerate(self._static):
            if ordered:  # the rows this interval can own: [s0, s1] in sorted times
                lo, hi = int(np.searchsorted(ts, s0, "left")), int(np.searchsorted(ts, s1,
                                                                                  "right"))
            else:
                lo, hi = 0, len(ts)
            if lo < hi:
                _static_fill(ts[lo:hi], s0, s1, bool(closed[k]), *hold.arrays(), self.N,
                             out[lo:hi])

    def _static_table(self, t_hi: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(S0, S1, closed)`` of the stuck intervals (cached): ``[s0, s1)``, closed at
        ``s1`` when it ends the solved interval and no step starts there."""
        key = (self._count, len(self._static), t_hi)
        if self._table is None or self._table[0] != key:
            T0 = self._arrays()[0] if self._count else np.empty(0)
            closed = []
            for _, s1, _ in self._static:
                i = int(np.searchsorted(T0, s1))
                closed.append(s1 == t_hi and not (i < len(T0) and T0[i] == s1))
            self._table = (key, np.array([s[0] for s in self._static], dtype=float),
                           np.array([s[1] for s in self._static], dtype=float),
                           np.array(closed, dtype=np.bool_))
        return self._table[1:]

    def _polynomials(self, ts: np.ndarray, out: np.ndarray) -> None:
        """The collocation polynomials at ``ts`` into ``out`` (each ``t`` on the step with
        ``T0[i] <= t < T0[i+1]``, the first or last one outside them)."""
        N = self.N
        T0, H, Y0, D = self._arrays()
        if numba_enabled():  # the same operations compiled (no temporary arrays)
            _evaluate(T0, H, Y0, D, ts, N, out)
            return
        i = np.clip(np.searchsorted(T0, ts, side="right") - 1, 0, len(T0) - 1)
        s = (ts - T0[i]) / H[i]
        l1, l2, l3 = dense_weights(s)
        y = Y0[i] + (l1[:, None] * D[i, 0] + l2[:, None] * D[i, 1] + l3[:, None] * D[i, 2])
        L1, L2, L3 = position_weights(s)
        V = slice(N, 2 * N)
        x = Y0[i, :N] + H[i][:, None] * (s[:, None] * Y0[i, V] + (
            L1[:, None] * D[i, 0, V] + L2[:, None] * D[i, 1, V] + L3[:, None] * D[i, 2, V]))
        out[:, 0] = ts
        out[:, 1:1 + 2 * N:2] = x
        out[:, 2:2 + 2 * N:2] = y[:, N:2 * N]
        out[:, 1 + 2 * N:] = y[:, 2 * N:]


_C1, _C2, _C3 = C
_W1 = _C1 * (_C1 - _C2) * (_C1 - _C3)  # the denominators of radau.dense_weights
_W2 = _C2 * (_C2 - _C1) * (_C2 - _C3)
_W3 = _C3 * (_C3 - _C1) * (_C3 - _C2)
# (the other two nodes, the denominator) of each weight, for position_weights
_L_NODES = ((_C2, _C3, _W1), (_C1, _C3, _W2), (_C1, _C2, _W3))


@njit(cache=True)
def _scan_times(ts, t_lo, t_hi):
    """``(index of the first time outside [t_lo, t_hi] or -1, whether ts is sorted)``."""
    ordered = True
    for r in range(ts.shape[0]):
        t = ts[r]
        if not (t >= t_lo and t <= t_hi):
            return r, ordered
        if r > 0 and t < ts[r - 1]:
            ordered = False
    return -1, ordered


@njit(cache=True)
def _in_static(t, S0, S1, CL) -> bool:
    """``t`` lies in a stuck interval ``[S0[k], S1[k])`` (or at a closed ``S1[k]``) found
    by bisection on ``S0`` (intervals in time order and disjoint)."""
    k = np.searchsorted(S0, t, side="right") - 1
    while k >= 0 and S1[k] >= t:
        if t < S1[k] or (CL[k] and t == S1[k]):
            return True
        k -= 1
    return False


@njit(cache=True)
def _evaluate(T0, H, Y0, D, ts, N, out, S0, S1, CL, ordered) -> None:
    """:meth:`DenseOutput.__call__`'s numpy evaluation, operation for operation, in one
    loop: the step ``i`` with ``T0[i] <= t < T0[i+1]`` (the last one at the end), the
    weights of :func:`~lumped.solvers.radau.tableau.dense_weights`, ``y_n + sum_k l_k D_k``, and
    for the positions :func:`position_weights`, ``x_n + h (s v_n + sum_k L_k D_k^v)``.

    A row in a stuck interval ``[S0[k], S1[k])`` (closed at ``S1[k]`` where ``CL[k]``) is
    left to :func:`_static_fill`, which writes all of it. With ``ordered`` times the step
    and the stuck interval are found by walking forward, else by bisection (the driver
    makes the intervals in time order and disjoint; membership is tested exactly, so
    other intervals would only leave rows to be evaluated here and overwritten)."""
    n = T0.shape[0]
    ny = Y0.shape[1]
    ns = S0.shape[0]
    i = -1
    k = 0
    for r in range(ts.shape[0]):
        t = ts[r]
        if ns:
            if ordered:  # the first interval that does not end before t
                while k < ns - 1 and (S1[k] < t or (S1[k] == t and not CL[k])):
                    k += 1
                if S0[k] <= t and (t < S1[k] or (CL[k] and t == S1[k])):
                    continue
            elif _in_static(t, S0, S1, CL):
                continue
        if ordered and i >= 0:
            while i + 1 < n and T0[i + 1] <= t:
                i += 1
        else:
            i = np.searchsorted(T0, t, side="right") - 1
        i = min(max(i, 0), n - 1)
        s = (t - T0[i]) / H[i]
        l1 = s * (s - _C2) * (s - _C3) / _W1
        l2 = s * (s - _C1) * (s - _C3) / _W2
        l3 = s * (s - _C1) * (s - _C2) / _W3
        ss = s * s
        L1 = (ss * (3.0 * ss - 4.0 * (_C2 + _C3) * s + 6.0 * _C2 * _C3)) / (12.0 * _W1)
        L2 = (ss * (3.0 * ss - 4.0 * (_C1 + _C3) * s + 6.0 * _C1 * _C3)) / (12.0 * _W2)
        L3 = (ss * (3.0 * ss - 4.0 * (_C1 + _C2) * s + 6.0 * _C1 * _C2)) / (12.0 * _W3)
        out[r, 0] = t
        for j in range(ny):
            if j < N:
                jv = N + j
                out[r, 1 + 2 * j] = Y0[i, j] + H[i] * (s * Y0[i, jv] + (
                    L1 * D[i, 0, jv] + L2 * D[i, 1, jv] + L3 * D[i, 2, jv]))
                continue
            y = Y0[i, j] + (l1 * D[i, 0, j] + l2 * D[i, 1, j] + l3 * D[i, 2, j])
            if j < 2 * N:
                out[r, 2 + 2 * (j - N)] = y
            else:
                out[r, 1 + j] = y


@njit(cache=True)
def _static_fill(ts, s0, s1, closed, y0, fkind, fpar, c, minv, free, N, out) -> None:
    """A stuck interval's rows at the ``ts`` in ``[s0, s1)`` (``[s0, s1]`` if ``closed``):
    ``x, v`` of ``y0``, the forces of ``y0`` but those of ``free``, which follow the static
    balance ``-K_free^-1 (f(t) + c)`` (:class:`lumped.solvers.modes.stuck.StaticHold`; the
    forcing by the scalar formulas of its kinds: 1 constant, 2 sine burst). The row is
    made once and copied; only a sine burst that is on makes the free forces anew at each
    time (after the last burst's ``t_off`` they are those of any later time)."""
    width = out.shape[1]
    row = np.empty(width)
    for i in range(N):
        row[1 + 2 * i] = y0[i]
        row[2 + 2 * i] = y0[N + i]
    for e in range(width - 1 - 2 * N):
        row[1 + 2 * N + e] = y0[2 * N + e]
    g = np.empty(N)
    t_on = -math.inf  # the forcing varies up to the latest t_off of a sine burst
    for i in range(N):
        if fkind[i] == 2:
            t_on = max(t_on, fpar[i, 2])
    fresh = True
    steady = False  # the row holds the forces of a time when no sine burst is on
    for r in range(ts.shape[0]):
        t = ts[r]
        if not (t >= s0 and (t < s1 or (closed and t == s1))):
            continue
        if fresh or not (steady and t > t_on):
            fresh = False
            steady = t > t_on
            for i in range(N):
                kind = fkind[i]
                f = 0.0
                if kind == 1:
                    f = fpar[i, 0]
                elif kind == 2 and not t > fpar[i, 2]:
                    f = fpar[i, 0] * math.sin(fpar[i, 1] * t)
                g[i] = f + c[i]
            for k in range(free.shape[0]):
                s_ = 0.0
                for i in range(N):
                    s_ += minv[k, i] * g[i]
                row[1 + 2 * N + free[k]] = s_
        out[r, 0] = t
        for j in range(1, width):
            out[r, j] = row[j]
