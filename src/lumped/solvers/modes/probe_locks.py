"""The dashpots a mode probe leaves at rate zero, put on their locks.

A mode probe (:func:`lumped.solvers.modes.choice.select_modes`) reads each element's
branch from its state at the end of a short step ``h_p``. A dashpot that sits on a lock
(exactly, :func:`~lumped.solvers.nonsmooth.locks.prefer_locks`) or whose ends other locks
join (:func:`~lumped.solvers.nonsmooth.locks.lock_parallel_rates`) is read as slipping
whenever round-off moves its rate off zero. The round-off is of two kinds:

* the forces': a force known to ``sqrt(eps)`` of the largest one moves a mass by
  ``sqrt(eps) h_p max|F| / m`` in rate over the probe;
* the positions', where a taut string (a position lock) joins the ends: its rate is a
  difference of positions over the probe, known to a few ulps of them over ``h_p``,
  ``4 eps max|x| / h_p``.

On a slip branch that ends flat (Herschel-Bulkley ``n > 1``: ``q = gamma (|F| - tau)^n``)
such a dashpot's force lies ``(q / gamma)^(1/n)`` beyond its yield force, far more than
the lock's own admission (``sqrt(eps)``). Where a taut string holds the rate, a yield
dashpot whose law, at rate 0 and its force, is off by no more than the positions'
round-off in rate (``|R(0, F) / R_q(0, F)| <= 4 eps max|x| / h_p``) is read at the edge
``F*`` of its set at rest nearest ``F`` (:func:`~lumped.solvers.implicit.initial_slip.
rest_edge`), and locked there when the other locks hold its rate; one left slipping keeps
its force. Held on the flat slip branch at rate 0, the stage Newton meets a double root
(its corrections halve each iteration) and fails at every step size: a mass stopped on a
string at ``x = 0.01`` between a Bingham and a Herschel-Bulkley ``n = 2`` dashpot,
three steps in four failed for 0.1 s of the run, 90 s in all (1 s now). The positions'
round-off counts only while some mass moves (beyond it), so that the run steps; while
every mass is at rest the run holds its state without steps
(:mod:`lumped.solvers.modes.stuck`), where a dashpot on its slip branch at rate 0 keeps
its yield force and the string carries the rest of the load (the split ``bdf2`` keeps;
any split within the locks' sets is a solution).
"""

from __future__ import annotations

from collections.abc import Sequence

from ...scene import Mass, Scene
from ...scene.network import across
from ..implicit.initial_slip import rest_edge, set_valued_at_rest
from ..nonsmooth.locks import lock_parallel_rates, prefer_locks

__all__ = ["lock_probe_rates"]

_EPS = 2.220446049250313e-16
_SQRT_EPS = 1.4901161193847656e-08


def lock_probe_rates(scene: Scene, branches: Sequence, modes: Sequence[int],
                     v_p: list[float], F_p: list[float], x: Sequence[float], h_p: float,
                     m_min: float) -> tuple[list[int], list[float]]:
    """``(modes, F_p)`` of a probe of size ``h_p`` from positions ``x`` (its state ``v_p,
    F_p``; ``m_min`` the smallest mass) with the dashpots that sit on a lock, or that
    other locks hold at rate zero within the probe's round-off, put on their locks (see
    the module notes). ``F_p`` is a new list where a force moved onto its rest edge."""
    new = prefer_locks(scene, branches, modes, v_p, F_p)  # exactly on a lock: locked
    rate_tol = _SQRT_EPS * h_p * max(abs(f) for f in F_p) / m_min
    position_tol = 4.0 * _EPS * max(map(abs, x), default=0.0) / h_p
    strung = any(el.kind == "spring" and branches[e].info[new[e]].locks
                 for e, el in enumerate(scene.elements))
    if not strung or position_tol <= rate_tol or all(
            abs(vi) <= position_tol for vi, nd in zip(v_p, scene.nodes, strict=True)
            if isinstance(nd, Mass)):  # (every mass at rest: held without steps)
        return lock_parallel_rates(scene, branches, new, v_p, F_p, rate_tol), F_p
    edges = list(F_p)
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot" or branches[e].info[new[e]].locks or \
                abs(across(v_p, scene.elem_a[e], scene.elem_b[e])) > position_tol:
            continue
        kernel = el.law.kernel
        R, R_q, _ = kernel(0.0, F_p[e])
        if set_valued_at_rest(kernel) and R_q != 0.0 and abs(R / R_q) <= position_tol:
            edges[e] = rest_edge(kernel, F_p[e])
    out = lock_parallel_rates(scene, branches, new, v_p, edges, rate_tol, position_tol)
    return out, [f if branches[e].info[out[e]].locks else F_p[e] for e, f in enumerate(edges)]
