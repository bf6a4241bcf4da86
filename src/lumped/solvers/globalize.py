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

from ..scene import Junction, Scene
from .initial_state import _scalar_root
from .newton import NewtonCode, NewtonOptions, NewtonResult, _residual_ok, newton_solve

__all__ = [
    "balance_sweeps", "force_projector", "solve_globalized", "split_free_forces", "stuck_guesses",
]


def force_projector(scene: Scene, h: float, x_hat: list[float]):
    """``u -> u'``: every element's force replaced by the root of its own law at the
    elongation (rate) that ``u``'s velocities give, where the law fixes the force there
    (a stuck dashpot's force is left as is if its law admits it, else moved to a force
    it admits). See ``project`` of
    :func:`~lumped.solvers.newton.newton_solve`."""
    N = len(scene.nodes)
    items = [(N + e, scene.elem_a[e], scene.elem_b[e], el.kind == "spring", el.law.kernel)
             for e, el in enumerate(scene.elements)]

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
        for k, a, b, is_spring, kernel in items:
            q = elongation(u, a, b, is_spring)
            try:
                F, fixed = _scalar_root(kernel, q, u[k])
            except ValueError:  # no force at this q: leave it to Newton
                continue
            if math.isfinite(F) and (fixed or kernel(q, u[k])[0] != 0.0):
                # a force the law fixes; or, where the law leaves it free (a stuck
                # dashpot), one it admits if the iterate's is not
                out[k] = F
            if not fixed and free is not None:
                free.append((k, q))
        return out

    return project


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
                   sweeps: int = 50) -> list[float] | None:
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
    sticks: its force fills an interval at rate 0), the bisection ends at adjacent floats
    around the jump; the velocity is then snapped to the value in that bracket at which a
    rate vanishes exactly (0, or one of ``anchors(u)``: the other nodes' velocities), so
    that Newton starts on the stuck pieces. Returns the projected point, or
    None if some balance cannot be bracketed (a non-finite row where it starts).

    Used as a restart of :func:`solve_globalized` and, with the masses' accelerations
    held, for the junctions at ``t = 0`` (:mod:`lumped.solvers.initial_state`).
    """
    u = project(list(start))

    def g(i: int, w: float) -> float:
        u[i] = w
        return evaluate(project(u))[0][i]

    for _ in range(sweeps):
        moved = 0.0
        for i in nodes:
            w0 = u[i]
            g0 = g(i, w0)
            if not math.isfinite(g0):
                return None
            if g0 == 0.0:
                continue
            sign0 = g0 > 0.0
            direction = -1.0 if sign0 else 1.0
            step = 1e-3 * (1.0 + abs(w0))
            inside, outside = w0, None
            for _ in range(200):
                w = w0 + direction * step
                gw = g(i, w)
                # beyond the root, or where no force exists (a string past its length):
                # the root lies before
                if not math.isfinite(gw) or gw == 0.0 or (gw > 0.0) != sign0:
                    outside = w
                    break
                inside = w
                step *= 2.0
            if outside is None:
                u[i] = w0
                return None
            for _ in range(1100):
                mid = 0.5 * (inside + outside)
                if mid in (inside, outside):
                    break
                gm = g(i, mid)
                if math.isfinite(gm) and gm != 0.0 and (gm > 0.0) == sign0:
                    inside = mid
                else:
                    outside = mid
            lo, hi = min(inside, outside), max(inside, outside)
            snap = [c for c in [0.0, *anchors(u)] if lo <= c <= hi]
            if snap:
                u[i] = snap[0]
            else:  # the side where the balance has crossed zero (or is zero), if finite
                u[i] = outside if math.isfinite(g(i, outside)) else inside
            moved = max(moved, abs(u[i] - w0) / (1.0 + abs(u[i])))
        if moved <= 1e-15:
            break
    return project(u)


def split_free_forces(scene: Scene, evaluate, project, u: list[float]) -> list[float]:
    r"""At fixed velocities, the forces the laws leave free (stuck dashpots, taut strings)
    chosen to balance the nodes: the bounded least-squares problem

    .. math:: \min_{dF} \sum_i \Bigl(\frac{G_i + \sum_k J_{ik}\, dF_k}{S_i}\Bigr)^2
              + \mu \sum_k \Bigl(\frac{dF_k}{s}\Bigr)^2,
              \quad lo_k \le F_k + dF_k \le hi_k,

    with ``[lo_k, hi_k]`` the forces element ``k``'s law admits at its elongation (rate)
    (:func:`lumped.solvers.junction_balance.force_range`), the rows in units of their own
    terms ``S_i`` and ``mu = 1e-12``: where the balances fix the forces this is their
    solution, where they do not (locked elements in parallel) the small penalty picks the
    change of least norm, the rule of the minimum-norm Newton step. Newton then polishes
    from the result (the velocities, found by :func:`balance_sweeps`, stay)."""
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
    w = np.array([1.0 / max(S[i], 1e-300) for i in range(N)])
    A = np.array([[J[i][k] for k in ks] for i in range(N)]) * w[:, None]
    rhs = -np.array(G[:N]) * w
    lo, hi = [], []
    for k, q in free:
        a, b = force_range(scene.elements[k - N].law.kernel, q, u[k])
        lo.append(a - u[k])
        hi.append(b - u[k])
    if not all(lo_k <= 0.0 <= hi_k for lo_k, hi_k in zip(lo, hi, strict=True)):
        return u
    s = 1.0 + max(abs(u[k]) for k in ks)
    mu = 1e-6  # sqrt of the penalty 1e-12
    M = np.vstack([A, (mu / s) * np.eye(len(ks))])
    r = np.concatenate([rhs, np.zeros(len(ks))])
    sol = lsq_linear(M, r, bounds=(lo, hi), method="bvls")
    if not sol.success or not np.all(np.isfinite(sol.x)):
        return u
    for k, d in zip(ks, sol.x, strict=True):
        u[k] += float(d)
    return u


def solve_globalized(scene: Scene, evaluate, h: float, x_hat: list[float], v: list[float],
                     F: list[float], options: NewtonOptions) -> NewtonResult:
    """The step system ``evaluate`` solved from the restart points: the previous solution,
    the nodes' balances solved one at a time (:func:`balance_sweeps`) and every
    :func:`stuck_guesses` point, each first by plain (minimum-norm) Newton, then with
    nonlinear elimination (:func:`force_projector`). The first success is returned, else
    the first failure (the counters add up over all attempts)."""
    project = force_projector(scene, h, x_hat)
    first: NewtonResult | None = None
    its = res_ev = jac = facts = 0

    def starts():
        yield list(v) + list(F)
        N = len(scene.nodes)
        swept = balance_sweeps(evaluate, project, list(v) + list(F), list(range(N)),
                               lambda u: u[:N])
        if swept is not None:
            yield split_free_forces(scene, evaluate, project, swept)
        yield from stuck_guesses(scene, v, F)

    for start in starts():
        for proj in (None, project):
            res = newton_solve(evaluate, start, options, None, min_norm=True, project=proj,
                               check_scaled=True)
            its += res.iterations
            res_ev += res.residual_evals
            jac += res.jacobian_evals
            facts += res.factorizations
            if res.code is NewtonCode.SUCCESS:
                # the last correction is applied unevaluated: keep the solution only if
                # the residual test holds where it landed (after nonlinear elimination a
                # correction may leave a friction element's interval by 1e-8)
                G, _, S = evaluate(res.u)
                res_ev += 1
                if _residual_ok(G, S, options.rtol, options.atol):
                    break
                res.code = NewtonCode.DIVERGED
            first = first or res
        if res.code is NewtonCode.SUCCESS:
            break
    else:
        res = first
    res.iterations, res.residual_evals = its, res_ev
    res.jacobian_evals, res.factorizations = jac, facts
    return res
