r"""Globalisation of the step's Newton solve, used when plain semismooth Newton fails.

Two remedies, both generic (no law is recognised by name):

* :func:`stuck_guess` -- restart points. A friction element that slips at a massless
  junction leaves the junction's velocity out of its Jacobian row (``dR/dq = 0`` on the
  slipping branch), so Newton cannot move it; restarting with every junction moving with
  a dashpot neighbour (that element stuck) puts the iterate where the Jacobian sees it.
* :func:`force_projector` -- nonlinear elimination. Every trial iterate gets each
  element's force from its own law at the elongation (rate) the iterate's velocities
  give, solved by a safeguarded scalar root in a bracket. Newton then acts on the reduced
  system ``balance(v, F(q(v))) = 0``, which stays well conditioned where a law's graph is
  steep in ``F``: Herschel-Bulkley with ``n < 1`` has ``dq/dF -> infinity`` at its yield
  force, while its inverse ``F = tau + (q / gamma)^(1/n)`` is smooth there. Any user law
  with such a point gets the same help.
"""

from __future__ import annotations

import math

from ...scene import Junction, Scene
from ..newton.criteria import residual_ok
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.scalar_root import scalar_root
from ..newton.semismooth import newton_solve
from ..nonsmooth.groups import connected_groups
from ..nonsmooth.impacts import lock_state, lockable_elements
from .branch_check import known_monotone

__all__ = [
    "balance_sweeps", "force_projector", "laws_hold", "solve_globalized", "split_free_forces",
    "stuck_guesses",
]


def _no_force_at(kernel, q: float, F0: float) -> bool:
    """True when a law monotone in ``F`` admits no force at ``q``: ``R`` has one sign at
    ``F0`` and at ``+-1e300`` (a taut string's law past its length, ``q > L``). Three
    kernel calls, where :func:`~lumped.solvers.newton.scalar_root.scalar_root` would double its
    bracket some 2000 times before it gives up (most of the time of a globalised step
    with a string an ulp past its length)."""
    R0 = kernel(q, F0)[0]
    if R0 == 0.0 or R0 != R0:
        return False
    lo, hi = kernel(q, -1e300)[0], kernel(q, 1e300)[0]
    if R0 > 0.0:
        return lo > 0.0 and hi > 0.0
    return lo < 0.0 and hi < 0.0


#: A dashpot's rate within this many ulps of its ends' velocities is rest to
#: :func:`force_projector` (with ``admit=True``) where its law admits the force at rest.
_REST_ULPS = 4.0


def _at_rest(kernel, u: list[float], a: int, b: int, q: float, F: float) -> bool:
    """True when the rate ``q = u_b - u_a`` of a dashpot is below the rounding of its
    ends' velocities (:data:`_REST_ULPS` ulps of the larger) and its law admits ``F`` at
    rest on a piece flat in ``F`` (``R(0, F) = 0``, ``dR/dF = 0``: stuck)."""
    ends = max(abs(u[a]) if a >= 0 else 0.0, abs(u[b]) if b >= 0 else 0.0)
    if not abs(q) <= _REST_ULPS * math.ulp(ends):
        return False
    R, _, RF = kernel(0.0, F)
    return R == 0.0 and RF == 0.0


def force_projector(scene: Scene, h: float, x_hat: list[float], *, admit: bool = False):
    """``u -> u'``: every element's force replaced by the root of its own law at the
    elongation (rate) that ``u``'s velocities give, where the law fixes the force there
    (a stuck dashpot's force is left as is; with ``admit=True`` only if its law admits
    it, else moved to a force it admits; a dashpot whose rate is below the rounding of
    its ends' velocities reads as stuck where its law admits its force at rest,
    :func:`_at_rest`). See ``project`` of
    :func:`~lumped.solvers.newton.semismooth.newton_solve`. After each call ``project.missing``
    lists the rows of the elements whose law admits no force at their ``q`` (their
    force is left as it was)."""
    N = len(scene.nodes)
    items = [(N + e, scene.elem_a[e], scene.elem_b[e], el.kind == "spring", el.law.kernel)
             for e, el in enumerate(scene.elements)]
    # springs whose law may admit no force at some q (a string past its length), tested
    # first by _no_force_at; only laws known to be monotone in F (no folds)
    may_miss = {N + e for e, el in enumerate(scene.elements)
                if el.kind == "spring" and known_monotone(el.law)}

    def elongation(u: list[float], a: int, b: int, is_spring: bool) -> float:
        if is_spring:
            qb = x_hat[b] + h * u[b] if b >= 0 else 0.0
            qa = x_hat[a] + h * u[a] if a >= 0 else 0.0
        else:
            qb = u[b] if b >= 0 else 0.0
            qa = u[a] if a >= 0 else 0.0
        return qb - qa

    def project(u: list[float], free: list[tuple[int, float]] | None = None) -> list[float]:
        out = list(u)
        missing = project.missing = []
        for k, a, b, is_spring, kernel in items:
            q = elongation(u, a, b, is_spring)
            if admit and not is_spring and q != 0.0 and _at_rest(kernel, u, a, b, q, u[k]):
                # a rate below the rounding of its ends' velocities (a junction moving
                # with a stuck neighbour, solved an ulp or two off it), at a force the
                # law admits at rest: stuck, its force left to Newton. Read as slipping
                # it would jump to its yield force, and its node's balance with it
                if free is not None:
                    free.append((k, 0.0))
                continue
            try:
                if k in may_miss and _no_force_at(kernel, q, u[k]):
                    raise ValueError  # a string past its length: no root to search for
                F, fixed = scalar_root(kernel, q, u[k])
            except ValueError:  # no force at this q: leave it to Newton
                missing.append(k)
                continue
            if math.isfinite(F) and (fixed or (admit and kernel(q, u[k])[0] != 0.0)):
                # a force the law fixes; or, where the law leaves it free (a stuck
                # dashpot), one it admits if the iterate's is not
                out[k] = F
            if not fixed and free is not None:
                free.append((k, q))
        return out

    def ulp_scales(u: list[float]) -> list[tuple[int, float]]:
        """``(row, rho / eps)`` per law row: ``rho`` the largest change of ``R`` when ``F``
        moves to a floating-point neighbour, the round-off floor of the row at ``u``
        (where the law is steep in ``F`` no float may give a smaller residual)."""
        out = []
        for k, a, b, is_spring, kernel in items:
            q = elongation(u, a, b, is_spring)
            R = kernel(q, u[k])[0]
            rho = max(abs(kernel(q, math.nextafter(u[k], d))[0] - R)
                      for d in (-math.inf, math.inf))
            out.append((k, rho / 2.220446049250313e-16))
        return out

    project.ulp_scales = ulp_scales
    return project


def laws_hold(scene: Scene, h: float, x_hat: list[float], u: list[float], rtol: float,
              atol: float) -> bool:
    """Every element's law holds at the step's solution ``u`` (velocities, forces) to
    Newton's residual test, ``|R| <= rtol S + atol`` (``S`` from
    :func:`~lumped.solvers.implicit.step_system.law_scale`), read from the kernels directly.

    Newton applies its last correction without evaluating where it lands (it is below
    the update tolerance); taken with the Jacobian of one piece of a law in a direction
    the balances leave free (locks in parallel), it can leave a stuck dashpot ``1e-8``
    beyond its yield force. This check costs one kernel call per element and no
    residual evaluation, so the counters of a step that passes are unchanged."""
    from .step_system import law_scale

    N = len(scene.nodes)
    for e, el in enumerate(scene.elements):
        a, b = scene.elem_a[e], scene.elem_b[e]
        if el.kind == "spring":
            q = ((x_hat[b] + h * u[b]) if b >= 0 else 0.0) - ((x_hat[a] + h * u[a]) if a >= 0
                                                               else 0.0)
        else:
            q = (u[b] if b >= 0 else 0.0) - (u[a] if a >= 0 else 0.0)
        F = u[N + e]
        R, Rq, RF = el.law.kernel(q, F)
        if not abs(R) <= rtol * law_scale(el.law.kernel, q, F, R, Rq, RF) + atol:
            return False
    return True


def stuck_guesses(scene: Scene, v: list[float], F: list[float]) -> list[list[float]]:
    """Restart points for Newton: in the ``k``-th, every junction moves with its ``k``-th
    neighbour across a dashpot-like element (that element's rate zero: stuck; ``k`` taken
    modulo the junction's count), forces as given; then the same with all forces zero.
    Empty for a scene without junctions."""
    N = len(scene.nodes)
    partners: list[tuple[int, list[int]]] = []
    for i, nd in enumerate(scene.nodes):
        if not isinstance(nd, Junction):
            continue
        others = [scene.elem_b[e] if scene.elem_a[e] == i else scene.elem_a[e]
                  for e, el in enumerate(scene.elements)
                  if el.kind == "dashpot" and i in (scene.elem_a[e], scene.elem_b[e])]
        if others:
            partners.append((i, others))
    if not partners:
        return []
    out = []
    for k in range(max(len(o) for _, o in partners)):
        w = list(v[:N])
        for i, others in partners:
            o = others[k % len(others)]
            w[i] = w[o] if o >= 0 else 0.0
        out.append(w + list(F))
    out += [g[:N] + [0.0] * len(F) for g in out]
    return out


def balance_sweeps(evaluate, project, start: list[float], nodes: list[int], anchors,
                   links: list[tuple[int, int]] = (), sweeps: int = 20,
                   widths: list[float] | None = None) -> list[float] | None:
    """A starting point for Newton from the nodes' balances solved one at a time
    (nonlinear Gauss-Seidel).

    With every force on its own law (``project``, see :func:`force_projector`), node
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
    string past its length: ``project.missing``, see :func:`force_projector`) has no
    balance there (its stale force would read as balanced); it first moves to the
    nearest point, either way, where every such law admits one, and is solved from there.
    Returns the projected point, or None if some balance cannot be bracketed (a
    non-finite row where it starts).

    Used as a restart of :func:`solve_globalized` and, with the masses' accelerations
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
    from the result (the velocities, found by :func:`balance_sweeps`, stay). ``rows``: the
    balance rows to satisfy (default every node's; the initial state's masses have free
    accelerations, so only its junctions' rows count there)."""
    import numpy as np
    from scipy.optimize import lsq_linear

    from ..nonsmooth.junction_balance import force_range

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
    # a row with no terms yet (a junction whose forces are all zero so far) in the units
    # of the forces it may receive: a weight of 1e300 would swamp every other row
    reach = [sum(abs(J[i][k]) * max((abs(u[k] + x) for x in (lo[j], hi[j]) if math.isfinite(x)),
                                    default=0.0) for j, k in enumerate(ks)) for i in rows]
    w = np.array([1.0 / (S[i] if S[i] > 0.0 else max(r, 1e-300))
                  for i, r in zip(rows, reach, strict=True)])
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


def _motion_determined(evaluate, u: list[float], N: int, options: NewtonOptions) -> bool:
    """True when ``u`` (velocities, then forces) passes the residual test and the
    (minimum-norm) Newton correction there moves no velocity beyond the update test:
    the motion is determined to tolerance, only forces are not. Newton then runs out of
    iterations walking along a direction of forces that the residual does not see --
    locks in parallel whose free split of the forces is pinned only by a law flat at its
    yield force (Herschel-Bulkley ``n > 1``: ``dR/dF -> 0`` there, so the step matrix is
    nearly, not exactly, singular and no minimum-norm step leaves the split alone)."""
    from ..newton.criteria import update_ok
    from ..newton.min_norm import equilibrated_min_norm

    G, J, S = evaluate(u)
    if not (math.isfinite(sum(G)) and residual_ok(G, S, options.rtol, options.atol)):
        return False
    du = equilibrated_min_norm(J, G)
    return math.isfinite(sum(du)) and update_ok(du[:N], u[:N], options.rtol, options.atol)


def solve_globalized(scene: Scene, evaluate, h: float, x_hat: list[float], v: list[float],
                     F: list[float], options: NewtonOptions, *,
                     sweeps: bool = False) -> NewtonResult:
    """The step system ``evaluate`` solved from the restart points: the previous solution,
    the nodes' balances solved one at a time (:func:`balance_sweeps`) and every
    :func:`stuck_guesses` point, each first by plain (minimum-norm) Newton, then with
    nonlinear elimination (:func:`force_projector`). The first success is returned, else
    the first failure (the counters add up over all attempts).

    ``sweeps=True`` (the fixed-step methods) adds the :func:`balance_sweeps` start, keeps
    a Newton success only where the residual test holds after its last correction, and
    accepts the swept point itself when Newton cannot polish it; when every start runs
    out of iterations, it keeps one whose motion is determined (:func:`_motion_determined`,
    the forces split freely). The default leaves the
    solve as ``radau5``'s event probes were tuned with (their step control reads the
    probe's success; see the report of branch s2-netbdf)."""
    project = force_projector(scene, h, x_hat, admit=sweeps)
    first: NewtonResult | None = None
    its = res_ev = jac = facts = 0

    def starts():
        yield list(v) + list(F), False
        if not sweeps:
            yield from ((g, False) for g in stuck_guesses(scene, v, F))
            return
        N = len(scene.nodes)
        links = [(scene.elem_a[e], scene.elem_b[e]) for e, el in enumerate(scene.elements)
                 if el.kind == "dashpot"]
        # first as before (rates snapped to zero between neighbouring floats), then with
        # the widths of the positions' rounding (a node on a lock: see balance_sweeps)
        for widths in (None, [abs(math.ulp(xh)) / h for xh in x_hat[:N]]):
            swept = balance_sweeps(evaluate, project, list(v) + list(F), list(range(N)),
                                   lambda u: u[:N], links, widths=widths)
            if swept is not None:
                yield split_free_forces(scene, evaluate, project, swept), True
        for guess in stuck_guesses(scene, v, F):
            yield guess, False
        yield from ((g, False) for g in one_lock_at_a_time())

    def one_lock_at_a_time():
        """Where Newton ended with several position locks (a mass past two strings to
        ground in one step), they may not all hold: their rows then disagree and the
        minimum-norm steps stall. From that iterate, each lock in turn is kept and the
        others get back their force at the step's start (the spring branch)."""
        if first is None or not lockable:
            return
        N = len(scene.nodes)
        u = first.u
        x = [x_hat[i] + h * u[i] for i in range(N)]
        q = scene.elongations(x, u[:N])
        locked = [e for e in lockable if lock_state(scene.elements[e].law, q[e], u[N + e])]
        if len(locked) < 2:
            return
        for keep in locked:
            start = list(u)
            for e in locked:
                if e != keep:
                    start[N + e] = F[e]
            yield start

    lockable = lockable_elements(scene) if sweeps else []
    stalled: list[NewtonResult] = []  # out of iterations (see _motion_determined)
    for start, swept in starts():
        for proj in (None, project):
            res = newton_solve(evaluate, start, options, None, min_norm=True, project=proj,
                               check_scaled=sweeps)
            its += res.iterations
            res_ev += res.residual_evals
            jac += res.jacobian_evals
            facts += res.factorizations
            if res.code is NewtonCode.SUCCESS and sweeps:
                # the last correction is applied unevaluated: keep the solution only if
                # the residual test holds where it landed (after nonlinear elimination a
                # correction may leave a friction element's interval by 1e-8)
                G, _, S = evaluate(res.u)
                res_ev += 1
                if residual_ok(G, S, options.rtol, options.atol):
                    break
                res.code = NewtonCode.DIVERGED
            first = first or res
        if res.code is not NewtonCode.SUCCESS and swept:
            # Newton could not polish the swept point (locks in parallel whose rows are
            # proportional only up to rounding: a near-singular matrix, no minimum-norm
            # step; or a law steep in F whose root lies between two floats). The point
            # itself has every force on its law, each node balanced by bisection with the
            # others held: keep it if the residual test holds there, each law row measured
            # against its round-off floor (the change of R over one ulp of F).
            G, J, S = evaluate(start)
            res_ev += 1
            S = list(S)
            for k, floor in project.ulp_scales(start):
                if floor > S[k] and math.isfinite(floor):
                    S[k] = floor
            if residual_ok(G, S, options.rtol, options.atol):
                res = NewtonResult(list(start), NewtonCode.SUCCESS, 0, 0, 0, 0, G, 0, J)
        if res.code is NewtonCode.SUCCESS:
            break
        if res.code is NewtonCode.MAX_ITERS:
            stalled.append(res)
    else:
        res = first
        if sweeps:
            for cand in stalled:
                if _motion_determined(evaluate, cand.u, len(scene.nodes), options):
                    res_ev += 1
                    res = NewtonResult(list(cand.u), NewtonCode.SUCCESS, 0, 0, 0, 0,
                                       cand.residual, 0, cand.jacobian, True)
                    break
    res.iterations, res.residual_evals = its, res_ev
    res.jacobian_evals, res.factorizations = jac, facts
    return res
