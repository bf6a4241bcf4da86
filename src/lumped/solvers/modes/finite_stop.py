r"""A junction's dashpot that stops in finite time, within the tolerance of its stop.

A yield dashpot whose rate vanishes at its yield force more slowly than linearly in the
force's distance to it (a power ``n < 1``) stops in finite time when the springs at a
massless junction drive it. A
Herschel-Bulkley dashpot ``q = -gamma (-F - tau)^n`` with ``n < 1`` at a junction held
by springs of joint stiffness ``K`` relaxes as

.. math::

    \delta' = -K \gamma\, \delta^n, \qquad \delta = -F - \tau \ge 0, \qquad
    \delta(t)^{1 - n} = \delta_0^{1 - n} - (1 - n) K \gamma (t - t_0),

so it reaches its yield force (``delta = 0``) at a finite ``t*`` and sticks there; near
``t*``, ``delta ~ (t* - t)^{1/(1-n)}`` (``(t* - t)^5`` at ``n = 0.8``): flat to the
fifth order. The adaptive method's collocation polynomial cannot follow that end: from a
state a force ``delta`` of ``6e-13`` short of the yield force (``2e-4`` of the run's
force tolerance), every step of ``2e-11`` to ``1e-2`` s put the rate through zero at
``0.54`` of the step, the landing bracket closed on its lower end, the full laws kept
the slip (``delta > 0``: the exact motion still slips, ``3.6e-5`` s more), and the run
crept on by ``2e-11`` s a landing until its work budget stopped it (issue 29).

:func:`take_stop` (called by
:meth:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode` at a guard event where
:func:`~lumped.solvers.modes.lock_events.snap_to_locks` held the landed dashpot on its
lock and the full laws still keep it slipping) takes the stop at such a landing
(:func:`stop_within_tolerance`): when the dashpot's force
is within the run's force tolerance of the edge ``F*`` of its law's set at rest
(:func:`lumped.solvers.implicit.initial_slip.rest_edge`), its rate within the velocity
tolerance of 0, and the junction at one of its ends is joined to nothing but springs off
their locks, the junction is moved to where its balance puts the dashpot's force exactly
on ``F*``,

.. math::

    f_j + \sum_{a_k = j} F_k(x_j) - \sum_{b_k = j} F_k(x_j) = 0,
    \qquad F_e = F^*,

(the sums over every element at ``j``, the dashpot's force held at ``F*``; Newton in
``x_j``, each spring's force from its law at its new elongation, ``dF_k/dq_k = -R_q /
R_F``), when that moves it by at most the position tolerance; the dashpot is
then held on its stuck branch. The state is then the stop itself, where the full laws
read the dashpot stuck.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...scene import Mass, Scene
from ..implicit.initial_slip import rest_edge, set_valued_at_rest
from .guards import guard_tolerance

__all__ = ["stop_within_tolerance", "take_stop"]

_EPS = 2.220446049250313e-16
_NEWTON = 30


def _stuck_branch(lb) -> int | None:
    """The index of the branch of ``lb`` that locks the rate at 0, or None."""
    return next((info.index for info in lb.info if info.locks and info.lock_value == 0.0),
                None)


def _spring_force(kernel, q: float, F: float) -> float | None:
    """The force ``F`` with ``R(q, F) = 0`` on the branch ``kernel``, by Newton from ``F``;
    None when it does not converge."""
    for _ in range(_NEWTON):
        R, _, RF = kernel(q, F)
        if RF == 0.0 or not math.isfinite(R):
            return None
        step = R / RF
        F -= step
        if abs(step) <= 4.0 * _EPS * (1.0 + abs(F)):
            return F
    return None


def _spring_junction(scene: Scene, branches: Sequence, modes: Sequence[int], e: int,
                     j: int) -> list[int] | None:
    """The elements other than ``e`` at the node ``j`` if ``j`` is a junction joined to
    nothing else but springs off their locks, else None."""
    if j < 0 or isinstance(scene.nodes[j], Mass):
        return None
    others = [k for k in range(len(scene.elements))
              if k != e and j in (scene.elem_a[k], scene.elem_b[k])]
    if not others or any(scene.elements[k].kind != "spring"
                         or branches[k].info[modes[k]].locks for k in others):
        return None
    return others


def take_stop(scene: Scene, branches: Sequence, new: list[int], e: int, t: float,
              x: list[float], v: list[float], F: list[float], v_p: list[float],
              F_p: list[float], rtol: float, atol: float
              ) -> tuple[list[int], list[float], list[float]]:
    """The mode and the state the event at ``t`` goes on with, ``(new, v_p, F_p)``, when
    the full laws keep the dashpot ``e`` slipping at a landing on its guard where the
    snap to its lock held it (:func:`~lumped.solvers.modes.lock_events.snap_to_locks`):
    its stop taken (:func:`stop_within_tolerance`, ``x, v, F`` changed in place, and their
    copies as the probe's state) or, if not, the probe's as they were. The tolerances are
    the run's: ``atol + rtol max |v_i|`` for the rate, ``rtol max |F_k|`` for the force and
    ``atol + rtol max |x_i|`` for the junction's move."""
    tols = (atol + rtol * max(abs(vi) for vi in v), rtol * max(abs(f) for f in F),
            atol + rtol * max(abs(xi) for xi in x))
    mode = list(new)
    if stop_within_tolerance(scene, branches, mode, e, t, x, v, F, *tols):
        return mode, list(v), list(F)
    return new, v_p, F_p


def stop_within_tolerance(scene: Scene, branches: Sequence, new: list[int], e: int,
                          t: float, x: list[float], v: list[float], F: list[float],
                          tol_v: float, tol_F: float, tol_x: float) -> bool:
    """Take the stop of the dashpot ``e`` now (see the module notes): ``x``, ``v``, ``F``
    and ``new[e]`` changed in place, and True; or nothing changed, and False.

    Parameters
    ----------
    scene, branches
        The scene and its laws' branches.
    new : list of int
        The mode the full laws chose at the landing (``e`` on a slip branch).
    e : int
        The dashpot whose guard the run landed on.
    t : float
        The time (the junction's load ``f_j(t)``).
    x, v, F : list of float
        The state at ``t``.
    tol_v, tol_F, tol_x : float
        The run's velocity, force and position tolerances: the rate of ``e``, its force's
        distance to its yield force and the junction's move must lie within them.
    """
    el, lb = scene.elements[e], branches[e]
    stuck = _stuck_branch(lb)
    if el.kind != "dashpot" or stuck is None or lb.info[new[e]].locks or scene.support_ends:
        return False
    kernel = el.law.kernel
    if not set_valued_at_rest(kernel):
        return False
    edge = rest_edge(kernel, F[e])
    if not 0.0 < abs(F[e] - edge) <= tol_F:
        return False
    if any(g < -guard_tolerance(0.0, edge) for g in lb.guards_for(stuck)(0.0, edge)):
        return False
    a, b = scene.elem_a[e], scene.elem_b[e]
    va, vb = (v[a] if a >= 0 else 0.0), (v[b] if b >= 0 else 0.0)
    if abs(vb - va) > tol_v:
        return False
    for j, other in ((b, a), (a, b)):
        springs = _spring_junction(scene, branches, new, e, j)
        if springs is None:
            continue
        got = _balance(scene, branches, new, springs, e, edge, j, t, x, F)
        if got is None or abs(got[0] - x[j]) > tol_x:
            continue
        x[j] = got[0]
        for k, Fk in zip(springs, got[1], strict=True):
            F[k] = Fk
        F[e] = edge
        v[j] = v[other] if other >= 0 else 0.0
        new[e] = stuck
        return True
    return False


def _balance(scene: Scene, branches: Sequence, modes: Sequence[int], springs: list[int],
             e: int, edge: float, j: int, t: float, x: list[float], F: list[float]
             ) -> tuple[float, list[float]] | None:
    """``(x_j, [F_k])``: the junction ``j``'s position where its balance holds with the
    dashpot ``e`` at ``edge`` and each spring ``k`` at its law's force (Newton in
    ``x_j``), or None."""
    ea, eb = scene.elem_a, scene.elem_b
    f_j = scene.external_forces(t)[j]
    kernels = [branches[k].kernel_for(modes[k]) for k in springs]
    side = [1.0 if eb[k] == j else -1.0 for k in springs]  # dq_k / dx_j
    xj, Fs = x[j], [F[k] for k in springs]
    base = [0.0] * len(springs)
    for k_i, k in enumerate(springs):  # the elongation without x_j
        o = ea[k] if eb[k] == j else eb[k]
        base[k_i] = -side[k_i] * (x[o] if o >= 0 else 0.0)
    sign_e = 1.0 if ea[e] == j else -1.0
    scale = abs(f_j) + abs(edge) + sum(abs(f) for f in Fs)
    for _ in range(_NEWTON):
        r, dr = f_j + sign_e * edge, 0.0
        for k_i, kernel in enumerate(kernels):
            q = base[k_i] + side[k_i] * xj
            got = _spring_force(kernel, q, Fs[k_i])
            if got is None:
                return None
            Fs[k_i] = got
            _, Rq, RF = kernel(q, got)
            s_k = -side[k_i]  # +F at an element's a end, -F at its b end
            r += s_k * got
            dr += s_k * (-Rq / RF) * side[k_i]
        if abs(r) <= 4.0 * _EPS * scale:
            return xj, Fs
        if dr == 0.0 or not math.isfinite(dr):
            return None
        xj -= r / dr
    return None
