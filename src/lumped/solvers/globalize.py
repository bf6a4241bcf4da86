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
from .newton import NewtonCode, NewtonOptions, NewtonResult, newton_solve

__all__ = ["force_projector", "solve_globalized", "stuck_guesses"]


def force_projector(scene: Scene, h: float, x_hat: list[float]):
    """``u -> u'``: every element's force replaced by the root of its own law at the
    elongation (rate) that ``u``'s velocities give, where the law fixes the force there
    (a stuck dashpot's force is left as is). See ``project`` of
    :func:`~lumped.solvers.newton.newton_solve`."""
    N = len(scene.nodes)
    items = [(N + e, scene.elem_a[e], scene.elem_b[e], el.kind == "spring", el.law.kernel)
             for e, el in enumerate(scene.elements)]

    def project(u: list[float]) -> list[float]:
        out = list(u)
        for k, a, b, is_spring, kernel in items:
            if is_spring:
                qb = x_hat[b] + h * u[b] if b >= 0 else 0.0
                qa = x_hat[a] + h * u[a] if a >= 0 else 0.0
            else:
                qb = u[b] if b >= 0 else 0.0
                qa = u[a] if a >= 0 else 0.0
            try:
                F, fixed = _scalar_root(kernel, qb - qa, u[k])
            except ValueError:  # no force at this q: leave it to Newton
                continue
            if fixed and math.isfinite(F):
                out[k] = F
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


def solve_globalized(scene: Scene, evaluate, h: float, x_hat: list[float], v: list[float],
                     F: list[float], options: NewtonOptions) -> NewtonResult:
    """The step system ``evaluate`` solved from the restart points: the previous solution
    and every :func:`stuck_guesses` point, each first by plain (minimum-norm) Newton, then
    with nonlinear elimination (:func:`force_projector`). The first success is returned,
    else the first failure (the counters add up over all attempts)."""
    project = force_projector(scene, h, x_hat)
    first: NewtonResult | None = None
    its = res_ev = jac = facts = 0
    for start in [list(v) + list(F), *stuck_guesses(scene, v, F)]:
        for proj in (None, project):
            res = newton_solve(evaluate, start, options, None, min_norm=True, project=proj)
            its += res.iterations
            res_ev += res.residual_evals
            jac += res.jacobian_evals
            facts += res.factorizations
            if res.code is NewtonCode.SUCCESS:
                break
            first = first or res
        if res.code is NewtonCode.SUCCESS:
            break
    else:
        res = first
    res.iterations, res.residual_evals = its, res_ev
    res.jacobian_evals, res.factorizations = jac, facts
    return res
