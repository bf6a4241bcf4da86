r"""Stuck intervals of ``radau5`` without steps: the static balance and a scan of the
guards in time.

When every node is at rest (``v_i = 0`` exactly) and the held mode locks as many
elements as there are nodes, each on a branch whose residual does not depend on the force
(:attr:`lumped.codegen.branches.BranchInfo.locks`: a stuck dashpot ``q' = 0``, a taut
string ``q = L``) and whose incidence matrix is square and regular, the held-mode DAE
has the solution

.. math::

    x(t) = x(t_0), \qquad v(t) = 0, \qquad
    F_\text{free}(t) = -K_\text{free}^{-1} \bigl(f(t) + K_\text{fixed} F_\text{fixed}\bigr),

where ``K`` is the incidence of eq. (4a) (``net_i = f_i + sum_{a_e = i} F_e - sum_{b_e = i}
F_e``: ``+1`` at an element's first node ``a``, ``-1`` at its second node ``b``) and the
other elements keep their forces (their elongation or rate is frozen and ``dR/dF != 0``).
It holds until a guard of a locked element's branch turns negative. The guards are
scanned on ``F_free(t)`` at the forcing's extrema (where a forcing that is a
:class:`~lumped.scene.forcing.SineBurst` turns) and half-way between them, and the first
sign change is refined by Brent's method in ``t``. The scan is exact when each guard is
monotone in the force between two extrema of the forcing (the affine guards of every
built-in law, ``tau -+ F``, with one forcing); with forcings of several frequencies the
half-way samples are a heuristic.

Nothing here names a law: the locks, the guards and the lock values come from the
generated branches (:func:`lumped.codegen.branches.law_branches`). Only forcings that are
absent, constant or a sine burst are taken (the kinds of the compiled loop,
:func:`lumped.scene.forcing_jit.forcing_arrays`); any other runs the steps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.optimize import brentq

from ...scene import Scene
from ..newton.criteria import ROUNDOFF
from ..nonsmooth.rest_balance import rest_inverse
from ..radau.rows import row_of
from .force_bounds import onto_joint_bounds
from .guards import guard_tolerance

__all__ = ["StaticHold", "equilibrium_hold", "static_hold", "forcing_kinds"]

#: ``id(fpar) -> (fpar, varying, kinds)`` (see :class:`StaticHold`).
_KINDS: dict[int, tuple[np.ndarray, bool, list[tuple[int, float, float, float]]]] = {}


class StaticHold:
    """The static balance of a stuck scene (see the module notes): forces as functions
    of time, the break-out time and a dense segment.

    Built by :func:`static_hold`; ``free`` are the locked elements whose forces follow the
    balance, ``minv`` is ``-K_free^{-1}`` (rows by ``free``), ``c = K_fixed F_fixed``.
    No reference to ``scene`` is kept (a plan keeps holds: it would keep the scene)."""

    def __init__(self, scene: Scene, x: list[float], v: list[float], F: list[float],
                 free: list[int], minv: list[list[float]], c: list[float],
                 fkind: np.ndarray, fpar: np.ndarray,
                 arrays: tuple[np.ndarray, np.ndarray] | None = None) -> None:
        self.free, self.minv, self.c = free, minv, c
        self._structure_arrays = arrays  # (made once per structure: static_hold)
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
            minv, free = self._structure_arrays or _structure_arrays(self.minv, self.free)
            self._arrays = (np.array(self.y0, dtype=float), self.fkind, self.fpar,
                            np.array(self.c, dtype=float), minv, free)
        return self._arrays

    def forces_many(self, ts: np.ndarray) -> np.ndarray:
        """:meth:`forces` at many times, ``(len(ts), E)`` (numpy's ``sin``)."""
        N = len(self.c)
        f = np.zeros((len(ts), N))
        for i in range(N):
            kind, (a, w, t_off) = self.fkind[i], self.fpar[i]
            if kind == 1:
                f[:, i] = a
            elif kind == 2:
                f[:, i] = np.where(ts > t_off, 0.0, a * np.sin(w * ts))
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


def forcing_kinds(scene: Scene, plan) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(fkind, fpar)`` of the scene's forcing (kinds 0 none, 1 constant, 2 sine burst),
    or ``(None, None)`` when a forcing is of another kind; kept on ``plan``."""
    got = getattr(plan, "forcing_kinds", None)
    if got is None:
        from ...scene.forcing import zero_forcing
        from ...scene.forcing_jit import forcing_arrays

        fkind, fpar, _ = forcing_arrays(scene, 1.0, 0)
        for i, fn in enumerate(scene.forcing):
            if fn is zero_forcing:
                fkind[i] = 0
        got = (None, None) if (fkind == 3).any() else (fkind, fpar)
        plan.forcing_kinds = got
    return got


def static_hold(scene: Scene, plan, modes: Sequence[int], x: list[float],
                v: list[float], F: list[float], fkind: np.ndarray | None,
                fpar: np.ndarray | None) -> StaticHold | None:
    """The :class:`StaticHold` of the state, or ``None`` when the scene is not at rest in a
    mode that locks every node (see the module notes) or its forcing is not taken. The
    structure of a mode is kept on ``plan`` (the scene's
    :class:`~lumped.solvers.eventdriven.setup.ScenePlan`)."""
    if fkind is None or any(vi != 0.0 for vi in v):
        return None
    cache = plan.__dict__.setdefault("hold_structure", {})
    key = tuple(modes)
    got = cache.get(key, False)
    if got is False:
        got = cache[key] = _structure(scene, plan.branches, modes)
    if got is None:
        return None
    free, minv, K, fixed, arrays = got
    c = [sum(K[i][e] * F[e] for e in fixed) for i in range(len(v))]
    return StaticHold(scene, x, v, F, free, minv, c, fkind, fpar, arrays)


def equilibrium_hold(scene: Scene, ms, t: float, x: list[float], v: list[float],
                     F: list[float], fkind: np.ndarray | None, fpar: np.ndarray | None
                     ) -> StaticHold | None:
    r"""The :class:`StaticHold` of an equilibrium under a constant forcing, or ``None``.

    When every node is at rest (``v_i = 0`` exactly), the forcing is constant (absent or
    constant, no sine burst), every node's balance holds to the rounding of its terms,

    .. math::

        \Bigl|f_i + \sum_{a_e = i} F_e - \sum_{b_e = i} F_e\Bigr| \le 4 \epsilon
        \Bigl(|f_i| + \sum_{e \ni i} |F_e|\Bigr),

    every guard of every element's held branch holds at ``(q_e, F_e)`` (to its
    round-off tolerance, :func:`lumped.solvers.modes.guards.guard_tolerance`), and every
    lock in parallel (``ms.cones``) sits on a bound of its force interval (a guard zero to
    that tolerance: the split has no room on that side; one inside its interval leaves
    the split to the steps' rule, :mod:`lumped.solvers.radau.cone_split`), then
    ``x(t) = x(t_0)``, ``v = 0``, ``F(t) = F(t_0)`` solves the held mode's DAE
    (``x' = v = 0``, ``m v' = 0``, and each law ``R_e(q_e, F_e) = 0`` at its frozen ``q_e``),
    and its guards stay where they are: it holds up to the next breakpoint. This takes
    the locks in parallel too (a split among them that the steps' cone rule would keep),
    which :func:`static_hold` leaves to the steps: e.g. a mass on two stuck Bingham
    dashpots loaded by exactly the sum of their yield forces, both forces on their
    bounds, where the stage forces scatter around the bounds by the stage Newton's
    tolerance and each step read a crossing (38 loop passes an accepted step). Such
    forces within ``rtol`` of a joint bound are put on it first (:mod:`.force_bounds`).
    """
    if fkind is None or (fkind == 2).any() or any(vi != 0.0 for vi in v):
        return None
    snapped = onto_joint_bounds(scene, ms.cones, F, ms.rtol)  # (a load at their joint bound)
    hold = _equilibrium_hold(scene, ms, t, x, v, snapped, fkind, fpar)
    return hold if hold is not None or snapped == F else \
        _equilibrium_hold(scene, ms, t, x, v, F, fkind, fpar)


def _equilibrium_hold(scene: Scene, ms, t: float, x: list[float], v: list[float],
                      F: list[float], fkind: np.ndarray, fpar: np.ndarray | None
                      ) -> StaticHold | None:
    """:func:`equilibrium_hold` at the forces ``F`` (the nodes at rest, the forcing
    constant)."""
    N = len(v)
    net = scene.net_forces(t, F)
    scale = [abs(fi) for fi in scene.external_forces(t)]
    for e, Fe in enumerate(F):
        for i in (scene.elem_a[e], scene.elem_b[e]):
            if i >= 0:
                scale[i] += abs(Fe)
    if not all(abs(r) <= ROUNDOFF * s for r, s in zip(net, scale, strict=True)):
        return None
    q = scene.elongations(x, v)
    for e, guard in enumerate(ms.guards):
        tol = guard_tolerance(q[e], F[e])
        gs = guard(q[e], F[e])
        if not all(g + tol >= 0.0 for g in gs):
            return None
        if e in ms.cones and not any(abs(g) <= tol for g in gs):
            return None  # inside its cone: the split is the steps' rule's to choose
    return StaticHold(scene, x, v, F, [], [], [0.0] * N, fkind, fpar,
                      (np.zeros((0, N)), np.zeros(0, dtype=np.int64)))


def _structure_arrays(minv: list[list[float]], free: list[int]
                      ) -> tuple[np.ndarray, np.ndarray]:
    """``(minv, free)`` as the arrays of the compiled dense output."""
    return (np.array(minv, dtype=float).reshape(len(free), -1),
            np.array(free, dtype=np.int64))


def _structure(scene: Scene, branches: Sequence, modes: Sequence[int]):
    """``(free, -K_free^-1, K, fixed, (-K_free^-1, free) as arrays)`` of a mode, or
    ``None`` when it does not lock every node."""
    N = len(scene.nodes)
    free = []
    for e, el in enumerate(scene.elements):
        info = branches[e].info[modes[e]]
        if info.locks:
            if info.lock_value is None or (el.kind == "dashpot" and info.lock_value != 0.0):
                return None
            free.append(e)
        elif info.dR_dF.is_number and info.dR_dF == 0:
            return None
    got = rest_inverse(N, tuple(zip(scene.elem_a, scene.elem_b, strict=True)), tuple(free))
    if got is None:
        return None
    minv, K, fixed = got
    return free, minv, K, fixed, _structure_arrays(minv, free)


def hold_interval(scene: Scene, plan, ms, t: float, t_stop: float, x: list[float],
                  v: list[float], F: list[float], dense, rows
                  ) -> tuple[float, list[float], bool] | None:
    """Take the stuck interval from ``t`` in one piece, if the state allows it
    (:func:`static_hold`): the dense segment and the output rows at the scan's samples go
    into ``dense`` and ``rows``; returns ``(t_1, F(t_1), broke_out)`` where ``t_1`` is the
    break-out time or ``t_stop``, or ``None`` (the steps must run: not stuck, or the
    break-out is at ``t`` itself)."""
    fkind, fpar = forcing_kinds(scene, plan)
    if ms.cones:
        # locks in parallel: their split rule is the steps' (lumped.solvers.radau.stage),
        # unless nothing moves and no force changes
        hold = equilibrium_hold(scene, ms, t, x, v, F, fkind, fpar)
    else:
        hold = static_hold(scene, plan, ms.modes, x, v, F, fkind, fpar)
    if hold is None:
        return None
    t_b, samples = hold.breakout(t, t_stop, ms.guards, ms.modes, ms.fast)
    if t_b is not None and t_b - t <= 16 * 2.220446049250313e-16 * max(1.0, abs(t)):
        return None
    t1 = t_stop if t_b is None else t_b
    dense.add_static(t, t1, hold)
    F1 = hold.forces(t1)
    # the rows at the samples and at t1, in one block
    rows.extend(np.array([row_of(s, x, v, hold.forces(s)) for s in samples if s < t1]
                         + [row_of(t1, x, v, F1)], dtype=float))
    ms.mark_free(t, t1, x, v, F1)  # elements on cycles whose forces are not unique
    return t1, F1, t_b is not None
