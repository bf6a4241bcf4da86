r"""The forces of the locks between nodes at rest on ``radau5``'s dense output (issue 29).

On a step whose held mode keeps a node at rest (``v_n = 0`` and ``V_k = 0`` at every stage,
bit-exact: a stuck dashpot's row is ``V_k = 0``), the node's balance (eq. 4a with
``v' = 0``)

.. math::

    r_i(t) = f_i(t) + \sum_{a_e = i} F_e(t) - \sum_{b_e = i} F_e(t) = 0

holds at every ``t``, and the forces of the locks that join such nodes to each other or to
ground (a stuck dashpot, a taut string: :attr:`lumped.codegen.branches.BranchInfo.locks`)
are algebraic: they follow the load. The stage values hold the balance at the nodes
``s = c_k``; between them the collocation cubic interpolates the forces, and with them the
load, whose interpolation error (a sine at ``omega h = 1.3``: ``5e-3`` of its amplitude)
the error estimate does not see: ``x`` and ``v`` are exact, and the forces whose guards
decide events are held only to ``min(1e-3, 100 rtol)``, enough to show a guard's sign
change. Nor is the start of a step after an event on the balance where its forces come
from a probe. So at each output time the dense output puts those forces onto the balance
by the correction of least weighted norm,

.. math::

    F_L(t) \leftarrow F_L(t) - W K^T \left(K W K^T\right)^{+} r(t),

``r`` the residual of the interpolated forces at the nodes at rest that a lock joins,
``K`` the incidence of those locks (``+1`` at the end ``a``, ``-1`` at ``b``) and ``W``
the weights of the split among locks in parallel, the half-widths ``w_e`` of their force
intervals (:func:`lumped.solvers.radau.cone_split.cone_solver`), ``1`` for a lock alone.
The stage rule's split of a load ``S`` among locks in parallel is ``F_e = c_e + w_e
lambda(S)``, so the corrected forces are that rule's split of the exact load: each inside
its interval while the load is inside their joint one. A lock alone at a node takes
exactly ``-r``. Moving nodes, and the forces of other elements, are left as interpolated
(their accuracy is the step's); a step at the forcing's breakpoint reads the load's right
limit at its start (the forces after a time event).
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...scene.forcing_jit import forcing_arrays, loads_at

__all__ = ["LockedForces"]


class LockedForces:
    """The correction of the module notes for the steps of one scene: the groups of locks
    (:meth:`group`, one per held mode) and :meth:`correct`."""

    def __init__(self, scene) -> None:
        self.N, self.E = len(scene.nodes), len(scene.elements)
        self.ea, self.eb = tuple(scene.elem_a), tuple(scene.elem_b)
        self.forcing = tuple(scene.forcing)
        # the forcing's kind codes ``(fkind, fpar)``, made at the first :meth:`loads`
        self._scene = scene
        self._kinds: tuple[np.ndarray, np.ndarray] | None = None
        self._groups: list[tuple[tuple[int, ...], tuple[float, ...], tuple]] = []
        self._index: dict[tuple, int] = {}
        self._modes: dict[tuple, int] = {}
        self._maps: dict[tuple, tuple | None] = {}

    def group(self, branches: Sequence, modes: Sequence[int], cones: dict) -> int:
        """The index of the held mode's locks and their weights, ``-1`` for a mode without
        locks (its steps are left as interpolated)."""
        key = (tuple(modes), tuple((e, *c[1:]) for e, c in cones.items()))
        got = self._modes.get(key)
        if got is None:
            locks = tuple(e for e in range(self.E) if branches[e].info[modes[e]].locks)
            weights = tuple(float(cones[e][1]) if e in cones else 1.0 for e in locks)
            bounds = tuple((float(cones[e][2]), float(cones[e][3])) if e in cones else
                           (-math.inf, math.inf) for e in locks)
            got = -1
            if locks:
                got = self._index.setdefault((locks, weights, bounds), len(self._groups))
                if got == len(self._groups):
                    self._groups.append((locks, weights, bounds))
            self._modes[key] = got
        return got

    def loads(self, ts: np.ndarray) -> np.ndarray:
        """``f_i(t)`` per node at the times ``ts``, ``(len(ts), N)``
        (:func:`lumped.scene.forcing_jit.loads_at`: by the forcing's kind codes, a
        table's too; a callable without one is called per time)."""
        if self._kinds is None:
            self._kinds = forcing_arrays(self._scene, 1.0, 0, linear=True)[:2]
            self._scene = None  # (read once; the forcing callables are kept)
        return loads_at(*self._kinds, ts, self.forcing)

    def _map(self, g: int, rest: np.ndarray) -> tuple | None:
        """``(lock columns, node rows, incidence of every element at those rows, P)`` with
        ``P = W K^T (K W K^T)^+`` for the locks of group ``g`` whose ends are at rest
        (``rest``) or ground, or ``None`` when there are none."""
        key = (g, rest.tobytes())
        if key in self._maps:
            return self._maps[key]
        locks, weights, _ = self._groups[g]
        still = [bool(r) for r in rest] + [True]  # (index -1: ground)
        free = [(e, w) for e, w in zip(locks, weights, strict=True)
                if still[self.ea[e]] and still[self.eb[e]]]
        nodes = sorted({i for e, _ in free for i in (self.ea[e], self.eb[e]) if i >= 0})
        got = None
        if nodes:
            Kall = self._incidence(nodes, range(self.E))
            cols = [e for e, _ in free]
            P = _least_weighted(Kall[:, cols], np.array([w for _, w in free]))
            got = (np.array(cols), np.array(nodes), Kall, P)
        self._maps[key] = got
        return got

    def _incidence(self, nodes: Sequence[int], elems: Sequence[int]) -> np.ndarray:
        """The incidence of the elements ``elems`` (columns) at the nodes ``nodes`` (rows):
        ``+1`` at an element's end ``a``, ``-1`` at ``b`` (a node's balance changes by
        ``K delta`` when the forces change by ``delta``); ground has no row."""
        row = {i: r for r, i in enumerate(nodes)}
        K = np.zeros((len(nodes), len(elems)))
        for k, e in enumerate(elems):
            if self.ea[e] in row:
                K[row[self.ea[e]], k] += 1.0
            if self.eb[e] in row:
                K[row[self.eb[e]], k] -= 1.0
        return K

    def correct(self, ts: np.ndarray, out: np.ndarray, T0: np.ndarray, H: np.ndarray,
                Y0: np.ndarray, D: np.ndarray, G: np.ndarray, skip: np.ndarray) -> None:
        """Correct the rows ``out`` (the dense output's, at the times ``ts``, of the steps
        ``(T0, H, Y0, D)`` with the groups ``G``) in place, but those of ``skip``."""
        N = self.N
        i = np.clip(np.searchsorted(T0, ts, side="right") - 1, 0, len(T0) - 1)
        sel = (G[i] >= 0) & ~skip
        if not sel.any():
            return
        steps = np.unique(i[sel])
        V = slice(N, 2 * N)
        rest = (Y0[steps, V] == 0.0) & np.all(D[steps][:, :, V] == 0.0, axis=1)
        maps: dict[tuple, int] = {}
        code = np.full(len(T0), -1)
        found: list[tuple] = []
        for s, still in zip(steps, rest, strict=True):
            key = (int(G[s]), still.tobytes())
            if key not in maps:
                maps[key] = len(found)
                found.append(self._map(int(G[s]), still))
            code[s] = maps[key]
        Fcols = slice(1 + 2 * N, 1 + 2 * N + self.E)
        for k, got in enumerate(found):
            rows = np.flatnonzero(sel & (code[i] == k))
            if got is None or not len(rows):
                continue
            cols, nodes, Kall, P = got
            t = ts[rows]
            # the load's right limit at a step's start (the forces after a time event)
            t = np.where(t == T0[i[rows]], np.nextafter(t, math.inf), t)
            r = self.loads(t)[:, nodes] + out[rows, Fcols] @ Kall.T
            out[rows[:, None], 1 + 2 * N + cols[None, :]] -= r @ P.T
        for g in np.unique(G[i[sel]]):
            self._keep_cones(int(g), out[:, Fcols], np.flatnonzero(sel & (G[i] == g)))

    def _keep_cones(self, g: int, F: np.ndarray, rows: np.ndarray) -> None:
        r"""Put the interpolated forces of group ``g``'s locks back into their intervals
        ``[lo_e, hi_e]`` on the rows ``rows`` of ``F`` (a view of the output's forces,
        changed in place), along the cycles of the locks.

        The split of a load among locks in parallel is free (a cycle of locks carries
        any circulating force): the stage rule puts it at ``F_e = c_e + w_e lambda``, and
        holds a force that would leave its interval at the end it meets. Where it meets
        it inside a step, the stage values follow ``lambda`` up to some node and the end
        after it, and the collocation cubic through that kink overshoots the end (by
        ``3e-4`` of a Coulomb bound ``tau = 1`` on a step of ``0.05``, above the error
        the step was accepted with). A force out of its interval is put at the end,
        ``d_V = clip(F_V) - F_V``, and the others of the group take the change by the
        correction of least weighted norm that keeps every node's balance,

        .. math::

            \delta_R = -W_R K_R^T \left(K_R W_R K_R^T\right)^{+} K_V d_V,

        ``K`` the incidence of the locks at their nodes (``+1`` at the end ``a``, ``-1``
        at ``b``; a node's balance changes by ``K \delta``), ``W`` the half-widths: the
        motion is unchanged and the locks stay in their intervals while their joint one
        holds the load (at most 3 passes, each holding what left its interval; a row the
        locks cannot carry together is left as interpolated). Rows within the intervals
        are left bit for bit as they are."""
        locks, weights, bounds = self._groups[g]
        lo = np.array([b[0] for b in bounds])
        hi = np.array([b[1] for b in bounds])
        if not len(rows) or (np.isinf(lo).all() and np.isinf(hi).all()):
            return
        cols = np.array(locks)
        Fl = F[rows[:, None], cols[None, :]]
        bad = np.flatnonzero(((Fl < lo) | (Fl > hi)).any(axis=1))
        if not len(bad):
            return
        K = self._incidence(sorted({i for e in locks for i in (self.ea[e], self.eb[e])
                                    if i >= 0}), locks)
        W = np.array(weights)
        for r in bad:
            f = Fl[r].copy()
            held = np.zeros(len(locks), dtype=bool)
            for _ in range(3):
                out_ = (f < lo) | (f > hi)
                if not out_.any():
                    break
                held |= out_
                d = np.zeros(len(locks))
                d[out_] = np.clip(f[out_], lo[out_], hi[out_]) - f[out_]
                free = ~held
                res = K @ d
                KR = K[:, free]
                delta = _least_weighted(KR, W[free]) @ res
                if not np.allclose(KR @ delta, res, rtol=0.0,
                                   atol=1e-12 * (1.0 + np.abs(f).max())):
                    break  # (the locks cannot carry the clipped load together)
                f = f + d
                f[free] -= delta
            if ((f >= lo) & (f <= hi)).all():
                F[rows[r], cols] = f


def _least_weighted(K: np.ndarray, W: np.ndarray) -> np.ndarray:
    """``P = W K^T (K W K^T)^+``: ``P r`` is the force change of least ``W^-1``-weighted
    norm that changes the balances ``K`` by ``r``."""
    return (W[:, None] * K.T) @ np.linalg.pinv((K * W) @ K.T)
