r"""Can the massless junctions be balanced at ``t = 0``? The refusal of an initial state
that no law admits, with the junctions and elements that make it so.

A junction has no mass, so at every instant the forces of the elements that meet there
balance its load (sign convention of :mod:`lumped.solvers.bdf.fixed_step`; element ``e``
pulls its end ``b`` towards ``a`` with ``F_e > 0`` under tension)::

    sum_{b_e = i} F_e - sum_{a_e = i} F_e = f_i(0)        for every junction i.

At ``t = 0`` the elongation ``q`` of a spring is known, so its law fixes its force (or
an interval of forces: a taut string, ``F >= k L``); a dashpot at a junction has an
unknown rate, so its force may be anything its law admits at *some* rate: its *range*
(``[-tau, tau]`` for a Coulomb element, everything for a Bingham one). When no choice of
the forces within these ranges balances every junction, no motion satisfies the laws:
e.g. a spring stretched beyond what the friction elements at its junction can hold (the
junction would have to jump). Whether such a choice exists is a small linear program:

.. math::

    \min \sum_i (s_i^+ + s_i^-) \quad\text{s.t.}\quad
    A F + s^+ - s^- = b,\quad lo_e \le F_e \le hi_e,\quad s^\pm \ge 0,

whose optimum is the least total imbalance. The ranges are a relaxation (they ignore that
dashpots in parallel share one rate), so a positive optimum *proves* that the state is
inconsistent; it is then refused by :func:`refuse_unbalanced_junctions`. The ranges are
read from the law's kernel alone (a sign change of ``R`` in ``q``, or ``R = 0`` at the
fixed ``q``), so user laws are treated alike.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from ...scene import Junction, Scene

__all__ = ["force_range", "refuse_unbalanced_junctions"]

#: Rates probed for the range of a dashpot: far beyond any physical rate, first one with
#: finite residuals on both sides wins.
_PROBES = (1e100, 1e30, 1e12, 1e6)

#: Relative imbalance of a junction row beyond which the state is refused: ten times the
#: initial solve's Newton tolerance (``NewtonOptions.rtol``), which no Newton iterate can
#: meet then. Only consulted after that solve failed.
_GAP = 1e-9


def _admitted_at_some_rate(kernel, F: float) -> bool:
    """``R(q, F) = 0`` for some ``q``: ``R`` changes sign (or vanishes) between ``-Q`` and
    ``Q`` for a large probe ``Q`` (a monotone passive law)."""
    for Q in _PROBES:
        lo, hi = kernel(-Q, F)[0], kernel(Q, F)[0]
        if math.isfinite(lo) and math.isfinite(hi):
            return lo * hi <= 0.0
    return True  # cannot tell: never refuse on a guess


def _edge(admits: Callable[[float], bool], start: float, direction: float,
          limit: float) -> float:
    """The end of the interval of admitted forces that contains ``start``, searched in
    ``direction`` (+1 or -1): doubling steps, then bisection to adjacent floats.
    ``+-inf`` when the law admits forces beyond ``limit``."""
    inside = start
    step = 1.0 + abs(start)
    while True:
        cand = start + direction * step
        if not math.isfinite(cand) or abs(cand) > limit:
            return direction * math.inf
        if not admits(cand):
            outside = cand
            break
        inside = cand
        step *= 2.0
    for _ in range(200):
        mid = 0.5 * (inside + outside)
        if mid in (inside, outside):
            break
        if admits(mid):
            inside = mid
        else:
            outside = mid
    return inside


def force_range(kernel, q: float | None = None, start: float = 0.0) -> tuple[float, float]:
    """The interval of forces ``F`` that a law admits: at the elongation (rate) ``q``, or,
    with ``q=None``, at some rate. ``start`` must be admitted (for ``q=None`` passive laws
    admit ``F = 0``); a law that does not admit it gives ``(-inf, inf)`` (no claim)."""
    if q is None:
        # forces beyond 1e30 count as unbounded (the probe rates reach 1e100)
        limit = 1e30

        def admits(F: float) -> bool:
            return _admitted_at_some_rate(kernel, F)
    else:
        limit = 1e300

        def admits(F: float) -> bool:
            return kernel(q, F)[0] == 0.0
    if not admits(start):
        return -math.inf, math.inf
    return _edge(admits, start, -1.0, limit), _edge(admits, start, 1.0, limit)


def refuse_unbalanced_junctions(scene: Scene, pinned: Sequence[float | None],
                                q0: Sequence[float], f: Sequence[float]) -> None:
    """Raise ValueError when no forces within the laws' ranges balance the junctions at
    ``t = 0`` (see the module notes). ``pinned[e]`` is the force that element ``e``'s
    law fixes at its known ``q0[e]`` (None if the law leaves it free there or its rate is
    unknown); ``f`` the external loads at ``t = 0``. Does nothing if the junctions can be
    balanced, or the scene has none."""
    import numpy as np
    from scipy.optimize import linprog

    nodes, elements = scene.nodes, scene.elements
    ea, eb = scene.elem_a, scene.elem_b
    junctions = [i for i, nd in enumerate(nodes) if isinstance(nd, Junction)]
    if not junctions:
        return
    row = {i: r for r, i in enumerate(junctions)}
    b = np.array([f[i] for i in junctions], dtype=float)
    scale = np.abs(b)
    free: list[int] = []
    bounds: list[tuple[float, float]] = []
    coef: list[list[tuple[int, float]]] = []
    for e, el in enumerate(elements):
        ends = [(r, s) for r, s in ((row.get(ea[e]), -1.0), (row.get(eb[e]), 1.0))
                if r is not None]
        if not ends:
            continue
        if pinned[e] is not None:
            for r, s in ends:
                b[r] -= s * pinned[e]
                scale[r] += abs(pinned[e])
            continue
        if el.kind == "spring":  # q known, the law leaves F free there (a taut string)
            from ..newton.scalar_root import scalar_root

            try:
                start, _ = scalar_root(el.law.kernel, q0[e], 0.0)
            except ValueError:
                continue  # refused element by element before
            lo, hi = force_range(el.law.kernel, q0[e], start)
        else:
            lo, hi = force_range(el.law.kernel)
        free.append(e)
        bounds.append((None if math.isinf(lo) else lo, None if math.isinf(hi) else hi))
        coef.append(ends)
        for r, _ in ends:
            scale[r] += max((abs(x) for x in (lo, hi) if math.isfinite(x)), default=0.0)
    m, n = len(junctions), len(free)
    # rows in units of their own terms, so that the imbalance is relative; a row with no
    # terms (a junction joined only by unbounded dashpots, unloaded) in the largest units
    scale = np.maximum(scale, max(1e-9 * float(scale.max()), 1e-300))
    A = np.zeros((m, n + 2 * m))
    for j, ends in enumerate(coef):
        for r, s in ends:
            A[r, j] = s
    A[:, n:n + m] = np.eye(m)
    A[:, n + m:] = -np.eye(m)
    w = 1.0 / scale
    c = np.concatenate([np.zeros(n), np.ones(2 * m)])
    try:
        res = linprog(c, A_eq=A * w[:, None], b_eq=b * w,
                      bounds=bounds + [(0.0, None)] * (2 * m), method="highs",
                      options={"primal_feasibility_tolerance": 1e-10,
                               "dual_feasibility_tolerance": 1e-10})
    except ValueError:  # non-finite data (a law gave no finite range): no verdict
        return
    if res.status != 0:
        return  # no verdict: leave the failure to Newton's report
    # the imbalance of the LP's forces put back inside their ranges (the LP may leave a
    # bound by its feasibility tolerance), in the rows' own units
    lo = np.array([-np.inf if x is None else x for x, _ in bounds])
    hi = np.array([np.inf if x is None else x for _, x in bounds])
    F = np.clip(res.x[:n], lo, hi)
    gap = np.abs(b - A[:, :n] @ F) * w
    bad = [r for r in range(m) if gap[r] > _GAP]
    if not bad:
        return
    parts = [_describe_group(group, b, free, bounds, coef, nodes, elements, junctions)
             for group in _groups(m, coef) if any(r in group for r in bad)]
    raise ValueError(
        "inconsistent initial state: no forces within the laws' ranges balance the "
        "massless junctions (e.g. a spring stretched beyond what the friction elements at "
        "its junction can carry; the junction would have to jump): " + "; ".join(parts)
        + "; change the initial positions or the parameters"
    )


def _groups(m: int, coef: list[list[tuple[int, float]]]) -> list[list[int]]:
    """The junction rows ``0..m-1`` joined by free elements (both ends junctions), as
    groups: their free forces move load between them, so only a group can be refused."""
    parent = list(range(m))

    def root(r: int) -> int:
        while parent[r] != r:
            parent[r] = parent[parent[r]]
            r = parent[r]
        return r

    for ends in coef:
        if len(ends) == 2:
            parent[root(ends[0][0])] = root(ends[1][0])
    groups: dict[int, list[int]] = {}
    for r in range(m):
        groups.setdefault(root(r), []).append(r)
    return list(groups.values())


def _describe_group(group, b, free, bounds, coef, nodes, elements, junctions) -> str:
    """One junction, or a group of junctions joined by elements whose force is not fixed:
    the net force it needs (the fixed forces and loads on it) and the free elements that
    can carry it, those to the rest of the scene and those within the group."""
    members = set(group)
    each = [f"junction {nodes[junctions[r]].name!r}" for r in group]
    names = each[0] if len(each) == 1 else ", ".join(each[:-1]) + " and " + each[-1]
    net = float(sum(float(b[r]) for r in group))

    def carrier(j: int, e: int) -> str:
        return f"{elements[e].name!r} ({elements[e].law_name!r}: {_interval(bounds[j])})"

    out, inner = [], []
    for j, e in enumerate(free):
        rows = [r for r, _ in coef[j]]
        if not any(r in members for r in rows):
            continue
        (inner if len(rows) == 2 else out).append(carrier(j, e))
    if len(group) == 1:
        return (f"{names} needs a net force {net!r} from the elements whose force "
                "is not fixed: " + (", ".join(out + inner) if out or inner else "none"))
    needs = ", ".join(repr(float(b[r])) for r in group)
    return (f"{names}, joined by elements whose force is not fixed "
            f"({', '.join(inner)}), need the net forces {needs} (in total {net!r}) from "
            "those and from the elements that join them to the rest of the scene: "
            + (", ".join(out) if out else "none"))


def _interval(bound: tuple[float | None, float | None]) -> str:
    lo, hi = (None if x is None else float(x) for x in bound)  # plain floats in messages
    if lo is None and hi is None:
        return "any force"
    if lo is not None and hi is not None and -lo == hi:
        return f"|F| <= {hi!r}"
    return f"{'-inf' if lo is None else repr(lo)} <= F <= {'inf' if hi is None else repr(hi)}"

