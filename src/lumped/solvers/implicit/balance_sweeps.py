r"""Balance sweeps: a starting point for the step's Newton solve from the nodes' balances
solved one at a time (nonlinear Gauss-Seidel), with every force on its own law.

:func:`balance_sweeps` owns the sweep: the monotone scalar balance of each node (or of a
cluster of nodes joined by stuck dashpots, or of a dashpot's two ends) bracketed and
solved by bisection, snapping onto the velocity where a rate vanishes exactly. It is a
restart of the globalised step solve (:mod:`lumped.solvers.implicit.globalize`) and, with
the masses' accelerations held, of the junctions at ``t = 0``
(:mod:`lumped.solvers.implicit.initial_state`). The forces come from a projector such as
:func:`lumped.solvers.implicit.force_projection.force_projector`.
"""

from __future__ import annotations

import math

from ..nonsmooth.groups import connected_groups

__all__ = ["balance_sweeps"]


def balance_sweeps(evaluate, project, start: list[float], nodes: list[int], anchors,
                   links: list[tuple[int, int]] = (), sweeps: int = 20,
                   widths: list[float] | None = None) -> list[float] | None:
    """A starting point for Newton from the nodes' balances solved one at a time
    (nonlinear Gauss-Seidel).

    With every force on its own law (``project``, see
    :func:`~lumped.solvers.implicit.force_projection.force_projector`), node
    ``i``'s balance row ``G_i`` depends on the velocities alone, and with the others fixed
    it never decreases in ``v_i``: inertia ``(m_i / h)(v_i - v_hat_i)`` grows, and every
    element of a passive law pushes back harder the faster (further) its end moves. So
    ``G_i(v_i) = 0`` is a monotone scalar equation -- solvable by bracketing and
    bisection whatever the laws' slopes (a Herschel-Bulkley law flat or steep at its
    yield force, several friction elements on one node), where Newton on the whole
    system may wander. The nodes ``nodes`` are swept until no velocity moves (relative
    ``1e-15``) or ``sweeps`` sweeps. Where the balance jumps across zero (a dashpot
    sticks: its force fills an interval at rate 0), the root is the velocity at which a
    rate vanishes exactly (0, or one of ``anchors(u)``: every node's velocity, by index):
    the candidates inside the bracket are tried first (a sign change between their float
    neighbours), so that Newton starts on the stuck pieces; else bisection to a width of
    ``1e-16`` of the velocities. Nodes joined by stuck dashpots (``links``:
    the ends ``(a, b)`` of the dashpots, rate ``u_b - u_a`` exactly zero) also move as one
    cluster, the sum of their rows solved for a common shift (their inner forces cancel
    in it): one node at a time cannot break a cluster free that must slip as a whole.
    So do the two ends of every dashpot: where a law is steep in its rate (Herschel-Bulkley
    ``n > 1`` near its yield force, ``dF/dq -> infinity``) single moves are tiny, while
    the pair's common shift is set by the softer rest of the network.
    ``widths[i]`` (optional): the velocity change of node ``i`` below which its position
    ``x_hat + h v`` does not move (``ulp(x_hat) / h``). On a lock (a taut string) the
    balance jumps across zero over that width, not between neighbouring floats: a
    candidate is also taken when the balance changes sign across it, and the node lands
    exactly on it (rate zero) instead of a few ulps off, where a dashpot to a stuck
    neighbour would slip at a rate of ``1e-17`` and carry its full yield force.
    A node (group) that starts where the law of an element at it admits no force (a
    string past its length: ``project.missing``, see
    :func:`~lumped.solvers.implicit.force_projection.force_projector`) has no
    balance there (its stale force would read as balanced); it first moves to the
    nearest point, either way, where every such law admits one, and is solved from there.
    Returns the projected point, or None if some balance cannot be bracketed (a
    non-finite row where it starts).

    Used as a restart of
    :func:`~lumped.solvers.implicit.globalize.solve_globalized` and, with the masses' accelerations
    held, for the junctions at ``t = 0`` (:mod:`lumped.solvers.implicit.initial_state`).
    """
    u = project(list(start))

    def solve(group: list[int], into_domain: bool = False) -> float | None:
        """Shift the velocities of ``group`` together by the ``s`` that zeroes the sum of
        their balance rows (the forces inside the group cancel in it); the relative move,
        or None if it cannot be bracketed."""
        base = [u[i] for i in group]
        others = [c for k, c in enumerate(anchors(u)) if k not in group]

        def g(s: float) -> float:
            for i, b in zip(group, base, strict=True):
                u[i] = b + s
            G, J, _ = evaluate(project(u))
            # an element at the group whose law admits no force where it is (a string
            # past its length, see force_projector): no balance there
            for k in getattr(project, "missing", ()):
                if any(J[i][k] != 0.0 for i in group):
                    return math.nan
            return sum(G[i] for i in group)

        g0 = g(0.0)
        if not math.isfinite(g0) and not into_domain:
            # the group starts where a law at it admits no force: move to the nearest
            # point (either way) where every one does, then solve from there
            step = 1e-3 * (1.0 + max(abs(b) for b in base))
            found = None
            for _ in range(200):
                for cand in (step, -step):
                    if math.isfinite(g(cand)):
                        found = cand
                        break
                if found is not None:
                    break
                step *= 2.0
            if found is None:
                g(0.0)
                return None
            bad, ok = 0.0, found
            width = 1e-16 * (1.0 + max(abs(b) for b in base))
            for _ in range(200):
                mid = 0.5 * (bad + ok)
                if mid in (bad, ok) or abs(ok - bad) <= width:
                    break
                if math.isfinite(g(mid)):
                    ok = mid
                else:
                    bad = mid
            g(ok)
            moved = solve(group, into_domain=True)
            return None if moved is None else max(moved, 2e-15)
        if not math.isfinite(g0):
            return None
        if g0 == 0.0:
            return 0.0
        sign0 = g0 > 0.0
        direction = -1.0 if sign0 else 1.0
        step = 1e-3 * (1.0 + max(abs(b) for b in base))
        inside, outside = 0.0, None
        for _ in range(200):
            gs = g(direction * step)
            # beyond the root, or where no force exists (a string past its length): the
            # root lies before
            if not math.isfinite(gs) or gs == 0.0 or (gs > 0.0) != sign0:
                outside = direction * step
                break
            inside = direction * step
            step *= 2.0
        if outside is None:
            g(0.0)
            return None
        lo, hi = min(inside, outside), max(inside, outside)
        # the bracket's ends count too: a node that starts exactly at rest (or at a
        # neighbour's velocity) may sit on the jump itself, where a stuck dashpot's force
        # fills the gap (its force, left as it was by ``project``, need not balance yet)
        cands = sorted({c - b for c in (0.0, *others) for b in base if lo <= c - b <= hi},
                       key=lambda c: abs(c - inside))
        shift = None
        snapped = True
        wide = 2.0 * max(widths[i] for i in group) if widths else 0.0
        for c in cands[:8]:
            # a jump across zero at c: a rate vanishes there and a dashpot sticks
            gl, gr = g(math.nextafter(c, -math.inf)), g(math.nextafter(c, math.inf))
            if math.isfinite(gl) and math.isfinite(gr) and gl <= 0.0 <= gr:
                shift = c
                break
            if wide > 0.0:
                gl, gr = g(c - wide), g(c + wide)
                if math.isfinite(gl) and math.isfinite(gr) and gl <= 0.0 <= gr:
                    shift = c
                    break
        if shift is None:
            snapped = False
            width = 1e-16 * (1.0 + max(abs(b) for b in base))
            for _ in range(200):
                mid = 0.5 * (inside + outside)
                if mid in (inside, outside) or abs(outside - inside) <= width:
                    break
                gm = g(mid)
                if math.isfinite(gm) and gm != 0.0 and (gm > 0.0) == sign0:
                    inside = mid
                else:
                    outside = mid
            # the side where the balance has crossed zero (or is zero), if finite
            shift = outside if math.isfinite(g(outside)) else inside
            # a rate that vanishes exactly within the bisection's width of the root is
            # the root: the balance jumps there, but its float neighbours did not show it
            # (a Coulomb element's ``F + r q`` rounds to ``F`` for ``|q|`` below an ulp of
            # ``F`` over ``r``, so the jump shows ``1e-17`` away). Landing there would
            # leave the dashpot slipping at ``1e-17`` with its full yield force, and its
            # node's balance unmet, instead of stuck.
            lo, hi = min(inside, outside) - width, max(inside, outside) + width
            near = sorted((c for c in cands if lo <= c <= hi), key=lambda c: abs(c - shift))
            if near and math.isfinite(g(near[0])):
                shift, snapped = near[0], True
        g(shift)
        moved = max(abs(shift) / (1.0 + abs(b + shift)) for b in base)
        if snapped and shift != 0.0 and widths:
            # landed exactly on another node's velocity: however small the move, the
            # neighbours' rates changed from a few ulps to zero; sweep again (with
            # ``widths`` only: the initial state's sweeps stay as they were)
            moved = max(moved, 2e-15)
        return moved

    for _ in range(sweeps):
        moved = 0.0
        groups = ([[i] for i in nodes] + _stuck_clusters(u, nodes, links)
                  + [[a, b] for a, b in links if a in nodes and b in nodes and a != b])
        for group in groups:
            d = solve(group)
            if d is None:
                return None
            moved = max(moved, d)
        if moved <= 1e-15:
            break
    return project(u)


def _stuck_clusters(u: list[float], nodes: list[int],
                    links: list[tuple[int, int]]) -> list[list[int]]:
    """Groups of two or more of ``nodes`` joined by links of rate exactly zero."""
    groups = connected_groups(nodes, [(a, b) for a, b in links
                                      if a >= 0 and b >= 0 and u[a] == u[b]])
    return [g for g in groups if len(g) > 1]
