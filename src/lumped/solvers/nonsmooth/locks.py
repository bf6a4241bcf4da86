r"""Locked elements in parallel: which forces are not unique, and over which intervals.

An element is *force-free* at a point ``(q, F)`` of its law when the active branch there
leaves the force free: ``dR/dF = 0`` from the law's compiled kernel (a taut string,
``F >= k L``; a stuck dashpot, ``|F| <= tau``, also at ``|F| = tau`` where the kernels
return the stuck branch). The test reads the kernel, so it holds for user laws as for the
built-in ones.

With the motion fixed, a change ``dF`` of the force-free elements' forces must keep every
node's balance (ground takes any reaction). Such a change exists exactly when the
force-free elements close a *cycle* in the network (ground one vertex): two elements in
parallel, a loop through ground, a junction between force-free elements on both sides
and ground. The elements on such cycles are the ones whose forces are *indeterminate*:
the motion is determinate, the split of the load among them is not. The solver then
picks the split by its documented rule (the minimum-norm Newton correction from the
previous step's forces, see :func:`lumped.solvers.newton.semismooth.newton_solve`) and reports the
elements and intervals here. Scenes without a cycle of elements skip the test
(:func:`cyclic_elements`).

Where a start point for Newton is built with the velocities fixed (the balance sweeps of
the globalised step and of the initial state), :func:`split_free_forces` chooses the
free forces among the locks by a bounded least-squares problem: within each law's
interval, balancing the nodes, of least change where the balances leave the split free.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from functools import lru_cache

from ...scene import Scene
from ...scene.network import across

__all__ = ["cyclic_elements", "cycles_among", "indeterminate_elements", "IntervalLog",
           "prefer_locks", "lock_parallel_rates", "split_free_forces"]

@lru_cache(maxsize=256)
def on_cycles(n_nodes: int, edges: tuple[tuple[int, int, int], ...]) -> tuple[int, ...]:
    """Elements (first entry of each edge) that lie on a cycle of the graph of ``edges``
    (``(element, a, b)``, ground ``-1``): those whose removal keeps ``a`` and ``b``
    connected."""
    out = []
    m = n_nodes + 1  # ground (-1) is vertex n_nodes
    for k, (e, a, b) in enumerate(edges):
        parent = list(range(m))
        for j, (_, a2, b2) in enumerate(edges):
            if j != k:
                parent[_find(parent, a2 % m)] = _find(parent, b2 % m)
        if _find(parent, a % m) == _find(parent, b % m):
            out.append(e)
    return tuple(out)


def _find(parent: list[int], i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


def cyclic_elements(scene) -> tuple[int, ...]:
    """Elements on some cycle of the whole network (ground one vertex): the only ones whose
    forces can ever be indeterminate."""
    edges = tuple((e, scene.elem_a[e], scene.elem_b[e]) for e in range(len(scene.elements)))
    return on_cycles(len(scene.nodes), edges)


def cycles_among(scene, elements) -> tuple[int, ...]:
    """Those of ``elements`` that lie on a cycle of the subnetwork made of ``elements`` alone
    (ground one vertex): e.g. of the locked elements, the ones locked in parallel."""
    edges = tuple((e, scene.elem_a[e], scene.elem_b[e]) for e in elements)
    return on_cycles(len(scene.nodes), edges)


def indeterminate_elements(scene, q: Sequence[float], F: Sequence[float],
                           candidates: Sequence[int] | None = None) -> tuple[int, ...]:
    """Indices of the elements whose forces are not unique at ``(q, F)`` (see the module
    notes): force-free elements on a cycle of force-free elements. ``candidates`` (e.g.
    :func:`cyclic_elements`) limits the elements examined."""
    elements = scene.elements
    ea, eb = scene.elem_a, scene.elem_b
    free = []
    for e in (range(len(elements)) if candidates is None else candidates):
        if elements[e].law.kernel(q[e], F[e])[2] == 0.0:
            free.append((e, ea[e], eb[e]))
    if len(free) < 2:
        return ()
    return on_cycles(len(scene.nodes), tuple(free))


class IntervalLog:
    """Collects, step by step, the intervals on which each element's force is not unique.

    ``mark(t_prev, t, elements)`` records that ``elements`` (names) were indeterminate at
    the end of the step ``[t_prev, t]``; consecutive steps join into one interval
    ``(t_first, t_last)``. ``result()`` gives ``{name: [(t0, t1), ...]}``.
    """

    def __init__(self) -> None:
        self._open: dict[str, list[float]] = {}
        self._done: dict[str, list[tuple[float, float]]] = {}

    @property
    def open(self) -> bool:
        """Some interval is open (its element was indeterminate at the last mark)."""
        return bool(self._open)

    def mark(self, t_prev: float, t: float, names: Sequence[str]) -> None:
        names = set(names)
        for name in list(self._open):
            if name not in names:
                t0, t1 = self._open.pop(name)
                self._done.setdefault(name, []).append((t0, t1))
        for name in names:
            span = self._open.get(name)
            if span is not None and span[1] == t_prev:
                span[1] = t
            else:
                if span is not None:
                    self._done.setdefault(name, []).append((span[0], span[1]))
                self._open[name] = [t, t]

    def add_closed(self, intervals: dict[str, list[tuple[float, float]]]) -> None:
        """Close every open interval, then add ``intervals`` (``{name: [(t0, t1), ...]}``,
        later than every mark so far: a backward-Euler bridge's, :mod:`lumped.solvers.
        bridge`)."""
        for name, (t0, t1) in self._open.items():
            self._done.setdefault(name, []).append((t0, t1))
        self._open.clear()
        for name, spans in intervals.items():
            self._done.setdefault(name, []).extend(spans)

    def result(self) -> dict[str, list[tuple[float, float]]]:
        out = {k: list(v) for k, v in self._done.items()}
        for name, (t0, t1) in self._open.items():
            out.setdefault(name, []).append((t0, t1))
        return out


def prefer_locks(scene, branches: Sequence, modes: Sequence[int], v: Sequence[float],
                 F: Sequence[float]) -> list[int]:
    """``modes`` with every dashpot that sits *exactly* on a rate lock put on that lock.

    A dashpot whose rate ``q`` at the velocities ``v`` equals the value ``L`` of one of
    its law's locking branches bit for bit (:attr:`BranchInfo.locks`, ``lock_value``;
    ``q = 0`` for a stuck dashpot), and whose force ``F_e`` that branch admits up to
    ``sqrt(eps) (1 + |F_e|)`` (its guards at ``(L, F_e)``), is on the lock: a slip branch
    at zero rate and the stuck branch at its yield force are the same point of the law.
    The mode probe at an event may read such an element as slipping when a load is shared
    by locks in parallel (its Newton puts one element's force a few ulps beyond its
    yield force, the other's rate fixes the common rate to 0). Held on a slip branch that
    ends flat (Herschel-Bulkley ``n > 1``: ``dq/dF = 0`` at the yield force) the stage
    Newton is singular there and the step fell to its floor. A rate that is not exactly
    ``L`` (a break-out, however slow) keeps the probe's branch.
    """
    out = list(modes)
    ea, eb = scene.elem_a, scene.elem_b
    for e, el in enumerate(scene.elements):
        lb = branches[e]
        if el.kind != "dashpot" or lb.info[out[e]].locks:
            continue
        got = _admitting_lock(lb, across(v, ea[e], eb[e]), F[e])
        if got is not None:
            out[e] = got
    return out


def _admitting_lock(lb, value: float, F_e: float) -> int | None:
    """The index of a locking branch of ``lb`` that fixes ``q = value`` and whose guards at
    ``(value, F_e)`` admit ``F_e`` up to ``sqrt(eps) (1 + |F_e|)``; ``None`` if none."""
    eps_slack = 1.4901161193847656e-08  # sqrt(eps)
    for info in lb.info:
        if not info.locks or info.lock_value is None or value != info.lock_value:
            continue
        gs = lb.guards_for(info.index)(info.lock_value, F_e)
        if all(g >= -eps_slack * (1.0 + abs(F_e)) for g in gs):
            return info.index
    return None


def lock_parallel_rates(scene, branches: Sequence, modes: Sequence[int], v: Sequence[float],
                        F: Sequence[float], rate_tol: float,
                        position_tol: float = 0.0) -> list[int]:
    """``modes`` with every dashpot whose rate the other locks hold at zero put on its own
    zero-rate lock, when its force ``F_e`` is admitted there and its rate at the
    velocities ``v`` is at most ``rate_tol`` (the mode probe's: what round-off in the
    forces gives over the probe step, :meth:`ModeState.change_mode`).

    The elements locked in ``modes`` with a zero rate (a stuck dashpot, ``q = 0``; a taut
    string, whose ``q = L`` holds ``dq/dt = 0``) join the nodes they connect. A dashpot
    whose two ends are joined by a path of such elements (in parallel with a stuck one,
    or on a cycle of them through ground) has rate exactly zero for as long as they hold:
    on a slip branch it would slip at zero rate, which is the stuck branch's point of the
    law when its force is within the yield force (its lock's guards at ``(0, F_e)``, to
    ``sqrt(eps) (1 + |F_e|)``). The mode probe reads such a dashpot as slipping when it
    splits a load among locks in parallel with one force at its yield force and the
    common rate a round-off away from 0; on a slip branch that ends flat (Herschel-Bulkley
    ``n > 1``, ``dq/dF = 0`` at the yield force) the stage Newton then fails for all but
    the shortest steps, and the run crept on by steps of ``1e-7``. A dashpot whose force
    is beyond its yield force keeps the probe's branch (the locks cannot all hold then:
    the stage solve says so), and so does one with a rate above ``rate_tol``: elements
    reversing together through zero rate under a load beyond their joint yield force
    (the probe reads a Herschel-Bulkley ``n < 1`` dashpot as stuck at a rate of
    ``1e-9``, where its force is ``tau`` to the last bit) must not be locked together.

    Where a taut string joins the ends (a position lock), the probe's rates there are its
    positions' differences over the probe step, exact only to their ulps over it: a rate
    up to ``max(rate_tol, position_tol)`` counts as zero (a mass stopped on a string at
    ``x = 0.01`` between a Bingham and a Herschel-Bulkley ``n = 2`` dashpot read at
    ``3e-11`` after a probe of ``2e-8`` s: held on the flat slip branch, 3 steps in 4
    failed for 0.1 s and the run took 90 s).
    """
    out = list(modes)
    ea, eb = scene.elem_a, scene.elem_b
    m = len(scene.nodes) + 1  # ground (-1) is vertex m - 1
    parent = list(range(m))
    held: list[int | None] = []  # each lock's end a, None for a stuck dashpot
    for e, el in enumerate(scene.elements):
        info = branches[e].info[out[e]]
        if info.locks and (el.kind == "spring" or info.lock_value == 0.0):
            parent[_find(parent, ea[e] % m)] = _find(parent, eb[e] % m)
            held.append(ea[e] % m if el.kind == "spring" else None)
    if not held:
        return out
    strung = {_find(parent, a) for a in held if a is not None}  # (joined by a taut string)
    for e, el in enumerate(scene.elements):
        lb = branches[e]
        a, b = ea[e], eb[e]
        root = _find(parent, a % m)
        if el.kind != "dashpot" or lb.info[out[e]].locks or root != _find(parent, b % m) \
                or abs(across(v, a, b)) > (max(rate_tol, position_tol) if root in strung
                                           else rate_tol):
            continue
        got = _admitting_lock(lb, 0.0, F[e])
        if got is not None:
            out[e] = got
    return out


def split_free_forces(scene: Scene, evaluate, project, u: list[float],
                      rows: list[int] | None = None) -> list[float]:
    r"""At fixed velocities, the forces the laws leave free (stuck dashpots, taut strings)
    chosen to balance the nodes: the bounded least-squares problem

    .. math:: \min_{dF} \sum_i \Bigl(\frac{G_i + \sum_k J_{ik}\, dF_k}{S_i}\Bigr)^2
              + \mu \sum_k \Bigl(\frac{dF_k}{s}\Bigr)^2,
              \quad lo_k \le F_k + dF_k \le hi_k,

    with ``[lo_k, hi_k]`` the forces element ``k``'s law admits at its elongation (rate)
    (:func:`lumped.solvers.nonsmooth.junction_balance.force_range`), the rows in units of their own
    terms ``S_i`` and ``mu = 1e-12``: where the balances fix the forces this is their
    solution, where they do not (locked elements in parallel) the small penalty picks the
    change of least norm, the rule of the minimum-norm Newton step. Newton then polishes
    from the result (the velocities, found by
    :func:`lumped.solvers.implicit.balance_sweeps.balance_sweeps`, stay). ``rows``: the
    balance rows to satisfy (default every node's; the initial state's masses have free
    accelerations, so only its junctions' rows count there)."""
    import numpy as np
    from scipy.optimize import lsq_linear

    from .junction_balance import force_range

    N = len(scene.nodes)
    free: list[tuple[int, float]] = []
    u = project(u, free)
    if not free:
        return u
    G, J, S = evaluate(u)
    ks = [k for k, _ in free]
    rows = list(range(N)) if rows is None else rows
    if not rows:
        return u
    lo, hi = [], []
    for k, q in free:
        a, b = force_range(scene.elements[k - N].law.kernel, q, u[k])
        lo.append(a - u[k])
        hi.append(b - u[k])
    # a row in the units of the larger of its terms and the forces it may receive: one
    # with no terms yet (a junction whose forces are all zero so far), or only tiny ones
    # (a spring at 4.8e-36 N from a drawn x0 = 4.8e-37), would otherwise swamp every other
    # row (a weight of 1e300, or 2e35: the split left the other junction unbalanced)
    reach = [sum(abs(J[i][k]) * max((abs(u[k] + x) for x in (lo[j], hi[j]) if math.isfinite(x)),
                                    default=0.0) for j, k in enumerate(ks)) for i in rows]
    w = np.array([1.0 / max(S[i], r, 1e-300) for i, r in zip(rows, reach, strict=True)])
    with np.errstate(invalid="ignore", over="ignore"):  # (overflow: tested below)
        A = np.array([[J[i][k] for k in ks] for i in rows]) * w[:, None]
        rhs = -np.array([G[i] for i in rows]) * w
    if not all(lo_k <= 0.0 <= hi_k for lo_k, hi_k in zip(lo, hi, strict=True)):
        return u
    # a law that admits a single force there (lo = hi: e.g. a regularised friction law
    # at its kink) leaves nothing to choose: that force stays, out of the problem (the
    # solver needs lo < hi)
    cols = [j for j in range(len(ks)) if lo[j] < hi[j]]
    if not cols:
        return u
    s = 1.0 + max(abs(u[k]) for k in ks)
    mu = 1e-6  # sqrt of the penalty 1e-12
    M = np.vstack([A[:, cols], (mu / s) * np.eye(len(cols))])
    r = np.concatenate([rhs, np.zeros(len(cols))])
    if not (np.all(np.isfinite(M)) and np.all(np.isfinite(r))):
        return u  # (a weight from a subnormal scale overflows: no split is chosen)
    try:
        sol = lsq_linear(M, r, bounds=([lo[j] for j in cols], [hi[j] for j in cols]),
                         method="bvls")
    except np.linalg.LinAlgError:  # the SVD inside did not converge
        return u
    if not sol.success or not np.all(np.isfinite(sol.x)):
        return u
    for j, d in zip(cols, sol.x, strict=True):
        u[ks[j]] += float(d)
    return u
