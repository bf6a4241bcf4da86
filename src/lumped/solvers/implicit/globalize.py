r"""Globalisation of the step's Newton solve, used when plain semismooth Newton fails.

This module owns :func:`solve_globalized`, the step system solved from a list of restart
points, each first by plain (minimum-norm) Newton and then with nonlinear elimination of
the forces; its restart points :func:`stuck_guesses`; and :func:`laws_hold`, the check of
a step's solution against every element's law that sends a fixed step here. Both remedies
are generic (no law is recognised by name):

* :func:`stuck_guesses` -- restart points. A friction element that slips at a massless
  junction leaves the junction's velocity out of its Jacobian row (``dR/dq = 0`` on the
  slipping branch), so Newton cannot move it; restarting with every junction moving with
  a dashpot neighbour (that element stuck) puts the iterate where the Jacobian sees it.
  The fixed-step methods also restart from the nodes' balances solved one at a time
  (:mod:`lumped.solvers.implicit.balance_sweeps`), with the forces the laws leave free
  split among the locks (:func:`lumped.solvers.nonsmooth.locks.split_free_forces`).
* nonlinear elimination (:func:`lumped.solvers.implicit.force_projection.force_projector`):
  every trial iterate gets each element's force from its own law, so Newton acts on the
  reduced system ``balance(v, F(q(v))) = 0``, well conditioned where a law's graph is
  steep in ``F`` (Herschel-Bulkley with ``n < 1`` at its yield force).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from ...scene import Junction, Scene
from ..newton.criteria import residual_ok
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.semismooth import newton_solve
from ..nonsmooth.groups import dashpot_links
from ..nonsmooth.impacts import lock_state, lockable_elements
from ..nonsmooth.locks import split_free_forces
from .balance_sweeps import balance_sweeps
from .force_projection import force_projector

__all__ = ["laws_hold", "solve_globalized", "stuck_guesses"]


def laws_hold(scene: Scene, h: float, x_hat: list[float], u: list[float], rtol: float,
              atol: float, kernels: Sequence[Callable] | None = None) -> bool:
    """Every element's law holds at the step's solution ``u`` (velocities, forces) to
    Newton's residual test, ``|R| <= rtol S + atol`` (``S`` from
    :func:`~lumped.solvers.implicit.step_system.law_scale`), read from the kernels directly.

    Newton applies its last correction without evaluating where it lands (it is below
    the update tolerance); taken with the Jacobian of one piece of a law in a direction
    the balances leave free (locks in parallel), it can leave a stuck dashpot ``1e-8``
    beyond its yield force. This check costs one kernel call per element and no
    residual evaluation, so the counters of a step that passes are unchanged.
    ``kernels`` replaces the laws' own kernels (their conditioned forms,
    :func:`~lumped.solvers.implicit.conditioned.conditioned_kernels`)."""
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
        kernel = el.law.kernel if kernels is None else kernels[e]
        R, Rq, RF = kernel(q, F)
        if not abs(R) <= rtol * law_scale(kernel, q, F, R, Rq, RF) + atol:
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
    the nodes' balances solved one at a time
    (:func:`~lumped.solvers.implicit.balance_sweeps.balance_sweeps`) and every
    :func:`stuck_guesses` point, each first by plain (minimum-norm) Newton, then with
    nonlinear elimination
    (:func:`~lumped.solvers.implicit.force_projection.force_projector`). The first
    success is returned, else the first failure (the counters add up over all attempts).

    ``sweeps=True`` (the fixed-step methods) adds the balance sweeps' start, keeps
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
        links = dashpot_links(scene)
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
