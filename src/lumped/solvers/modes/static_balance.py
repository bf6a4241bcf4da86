r"""The static balance of a stuck scene (:class:`StaticHold`): the locked elements'
forces as functions of time, their break-out scan and the dense segment of a held
interval.

When to hold, and from which forces, is :mod:`lumped.solvers.modes.stuck`'s (the maths
is in its notes): ``F_free(t) = -K_free^{-1} (f(t) + K_fixed F_fixed)``, ``x`` and ``v``
frozen.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq

from ...scene import Scene
from ...scene.forcing_jit import loads_at
from .guards import guard_tolerance

__all__ = ["StaticHold", "structure_arrays"]

#: ``id(fpar) -> (fpar, varying, kinds)`` (see :class:`StaticHold`).
_KINDS: dict[int, tuple[np.ndarray, bool, list[tuple[int, float, float, float]]]] = {}


class StaticHold:
    """The static balance of a stuck scene (see the notes of
    :mod:`lumped.solvers.modes.stuck`): forces as functions of time, the break-out time
    and a dense segment.

    Built by :func:`lumped.solvers.modes.stuck.static_hold`; ``free`` are the locked
    elements whose forces follow the balance, ``minv`` is ``-K_free^{-1}`` (rows by
    ``free``), ``c = K_fixed F_fixed``. No reference to ``scene`` is kept (a plan keeps
    holds: it would keep the scene)."""

    def __init__(self, scene: Scene, x: list[float], v: list[float], F: list[float],
                 free: list[int], minv: list[list[float]], c: list[float],
                 fkind: np.ndarray, fpar: np.ndarray,
                 arrays: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        self.free, self.minv, self.c = free, minv, c
        # ``(minv, free)`` as arrays, made once per structure (``static_hold``)
        self._structure_arrays = arrays
        self.fkind, self.fpar = fkind, fpar
        self.y0 = list(x) + list(v) + list(F)
        self.F0 = list(F)
        self.q = scene.elongations(x, v)
        self._arrays: tuple | None = None
        # a forcing that is absent or constant gives the same forces at every time; the
        # scan's samples are asked for twice (the scan, the output rows)
        self._steady: list[float] | None = None
        self._seen: dict[float, list[float]] = {}
        # the forcing's kinds as Python floats, made once per forcing (``fkind`` and
        # ``fpar`` are the plan's arrays, :func:`forcing_kinds`, which nothing changes)
        got = _KINDS.get(id(fpar))
        if got is None or got[0] is not fpar:
            if len(_KINDS) > 256:
                _KINDS.clear()
            got = _KINDS[id(fpar)] = (fpar, bool((fkind == 2).any()), [
                (int(k), float(p[0]), float(p[1]), float(p[2]))
                for k, p in zip(fkind, fpar, strict=True)])
        self.varying, self._kinds = got[1], got[2]

    def forces(self, t: float) -> list[float]:
        """Every element's force at ``t`` (the forcing's own values)."""
        if not self.varying:
            if self._steady is None:
                self._steady = self._forces(t)
            return list(self._steady)
        got = self._seen.get(t)
        if got is None:
            got = self._seen[t] = self._forces(t)
        return list(got)

    def balance(self, t: float) -> list[float]:
        """:meth:`forces` at ``t``, not kept (a time asked once)."""
        return list(self._steady) if self._steady is not None else self._forces(t)

    def _forces(self, t: float) -> list[float]:
        # the forcing by its kind's formula (``scene.external_forces(t)``, the same
        # values: kinds 0 none, 1 constant, 2 sine burst)
        f = [0.0 if k == 0 else a if k == 1 else (0.0 if t > t_off else a * math.sin(w * t))
             for k, a, w, t_off in self._kinds]
        g = [fi + ci for fi, ci in zip(f, self.c, strict=True)]
        F = list(self.F0)
        for r, e in enumerate(self.free):
            row = self.minv[r]
            s = 0.0
            for i, gi in enumerate(g):
                s += row[i] * gi
            F[e] = s
        return F

    def arrays(self) -> tuple:
        """``(y0, fkind, fpar, c, minv, free)`` as arrays, for the compiled dense output."""
        if self._arrays is None:
            minv, free = self._structure_arrays or structure_arrays(self.minv, self.free)
            self._arrays = (np.array(self.y0, dtype=float), self.fkind, self.fpar,
                            np.array(self.c, dtype=float), minv, free)
        return self._arrays

    def forces_many(self, ts: np.ndarray) -> np.ndarray:
        """:meth:`forces` at many times, ``(len(ts), E)`` (the forcing by
        :func:`lumped.scene.forcing_jit.loads_at`: numpy's ``sin``)."""
        f = loads_at(self.fkind, self.fpar, ts)
        out = np.empty((len(ts), len(self.F0)))
        out[:] = self.F0
        if self.free:
            out[:, self.free] = (f + np.asarray(self.c)) @ np.asarray(self.minv).T
        return out

    def samples(self, t0: float, t1: float) -> list[float]:
        """The scan's times in ``(t0, t1]``: the forcing's extrema, the points half-way
        between them, and ``t1``."""
        crit: set[float] = set()
        for kind, _, w, t_off in self._kinds:  # (fkind, fpar as Python numbers)
            if kind != 2 or w == 0.0 or t0 >= t_off:
                continue
            hi = min(t1, t_off)
            k = math.ceil((w * t0 - 0.5 * math.pi) / math.pi)
            while True:
                tk = (0.5 * math.pi + k * math.pi) / w
                if tk >= hi:
                    break
                if tk > t0:
                    crit.add(tk)
                k += 1
        pts = sorted(crit) + [t1]
        out, prev = [], t0
        for p in pts:
            out += [prev + 0.5 * (p - prev), p]
            prev = p
        return out

    def breakout(self, t0: float, t1: float, guards: Sequence, modes: Sequence[int],
                 fast=None, refine: bool = True) -> tuple[float | None, list[float]]:
        """The first time in ``(t0, t1]`` where a guard of a locked element turns negative
        (shifted by its round-off tolerance, as a step's crossing test), refined to a root
        of the guard; ``(None, samples)`` if none. ``samples`` are the scan's times before
        it (for the output rows). With ``fast`` (the run's compiled loop) the root is
        found compiled (:mod:`lumped.solvers.modes.stuck_jit`, the same numbers), and so is the
        scan of the samples under a sine burst when there are more than two of them.
        ``refine=False``: the first sample where a guard fails, not refined (whether there
        is a break-out at all)."""
        done: list[float] = []
        prev = t0
        samples = self.samples(t0, t1)
        if (fast is not None and self.varying and len(samples) > 2
                and (scan := fast.breakout_scan) is not None):
            # the samples' forces and guards in one compiled pass (the same numbers): the
            # loop below starts at the first sample where a guard fails, or ends the scan
            k = self._scan(samples, fast, modes, scan)
            if k < 0:
                return None, samples[:-1]
            if k > 0:
                done, prev, samples = samples[:k], samples[k - 1], samples[k:]
        for s in samples:
            F = self.forces(s)
            roots = []
            for e in self.free:
                gs = guards[e](self.q[e], F[e])
                tol = guard_tolerance(self.q[e], F[e])
                for j, g in enumerate(gs):
                    if g + tol < 0.0:  # the earliest root of all the guards that fail
                        if not refine:
                            return s, done
                        roots.append(self._root(e, j, guards[e], prev, s, modes, fast))
            if roots:
                return min(roots), done
            done.append(s)
            prev = s
        return None, done[:-1]

    def _scan(self, samples: list[float], fast, modes: Sequence[int], scan) -> int:
        """:func:`lumped.solvers.modes.stuck_jit.breakout_scan` on the samples: the index of the
        first one where a guard fails, or ``-1``; the forces of the samples it passed (and
        of the one where it stopped) are kept for :meth:`forces`."""
        y0, fkind, fpar, c, minv, free = self.arrays()
        ts = np.array(samples, dtype=float)
        out = np.empty((len(samples), len(self.F0)))
        k = scan(fast.guards.addr, fast.js.consts, free, np.array(modes, dtype=np.int64),
                 np.array(self.q, dtype=float), fkind, fpar, c, minv,
                 y0[len(y0) - len(self.F0):], ts, out, np.zeros(64))
        rows = out[:len(samples) if k < 0 else k + 1].tolist()
        for s, row in zip(samples, rows, strict=False):  # (rows: up to the stop)
            self._seen[s] = row
        return k

    def _root(self, e: int, j: int, guard, a: float, b: float,
              modes: Sequence[int] | None = None, fast=None) -> float:
        root = None if fast is None else fast.breakout_root  # (None: not compiled yet)
        if root is not None:  # compiled, the same numbers (nan: the reference says why)
            _, fkind, fpar, c, minv, _ = self.arrays()
            r = root(fast.guards.addr, fast.js.consts, e, modes[e], j, self.q[e],
                     self.free.index(e), fkind, fpar, c, minv, a, b,
                     np.zeros(64))  # (the guard values)
            if r == r:
                return r

        def g(t: float) -> float:
            return guard(self.q[e], self.forces(t)[e])[j]

        if not g(a) > 0.0:
            return a
        gb = g(b)
        if gb >= 0.0:  # negative only within its tolerance's shift: the end
            return b
        r = brentq(g, a, b, xtol=4e-16 * max(1.0, abs(b)), rtol=1e-15)
        # just past the crossing (the guard negative), as a landing ends: the mode
        # selection then sees the lock's force beyond its bound, not on it
        step = math.ulp(r)
        while g(r) >= 0.0 and r + step < b:
            r, step = r + step, 2.0 * step
        return r


def structure_arrays(minv: list[list[float]], free: list[int]
                      ) -> tuple[np.ndarray, np.ndarray]:
    """``(minv, free)`` as the arrays of the compiled dense output."""
    return (np.array(minv, dtype=float).reshape(len(free), -1),
            np.array(free, dtype=np.int64))
