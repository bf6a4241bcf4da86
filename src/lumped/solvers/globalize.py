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

__all__ = ["force_projector", "stuck_guess"]


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


def stuck_guess(scene: Scene, v: list[float], F: list[float],
                 zero_forces: bool) -> list[float] | None:
    """A restart point for Newton: every junction moves with a neighbour it shares a
    dashpot-like element with (that element's rate zero: stuck), forces as given or zero.
    ``None`` when the scene has no junction and the forces are kept (nothing new)."""
    N = len(scene.nodes)
    w = list(v)
    junctions = [i for i, nd in enumerate(scene.nodes) if isinstance(nd, Junction)]
    if not junctions and not zero_forces:
        return None
    for i in junctions:
        for e, el in enumerate(scene.elements):
            a, b = scene.elem_a[e], scene.elem_b[e]
            if el.kind == "dashpot" and i in (a, b):
                o = b if a == i else a
                w[i] = w[o] if o >= 0 else 0.0
                break
    Fs = [0.0] * len(F) if zero_forces else list(F)
    return w[:N] + Fs
