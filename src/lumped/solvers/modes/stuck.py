r"""Stuck intervals of ``radau5`` without steps: the static balance and a scan of the
guards in time.

When every node is at rest (``v_i = 0`` exactly) and the held mode locks as many
elements as there are nodes, each on a branch whose residual does not depend on the force
(:attr:`lumped.codegen.branches.BranchInfo.locks`: a stuck dashpot ``q' = 0``, a taut
string ``q = L``) and whose incidence matrix is square and regular, the held-mode DAE
has the solution

.. math::

    x(t) = x(t_0), \qquad v(t) = 0, \qquad
    F_\text{free}(t) = -K_\text{free}^{-1} \bigl(f(t) + K_\text{fixed} F_\text{fixed}\bigr),

where ``K`` is the incidence of eq. (4a) (``net_i = f_i + sum_{a_e = i} F_e - sum_{b_e = i}
F_e``: ``+1`` at an element's first node ``a``, ``-1`` at its second node ``b``) and the
other elements keep their forces (their elongation or rate is frozen and ``dR/dF != 0``).
It holds until a guard of a locked element's branch turns negative. The guards are
scanned on ``F_free(t)`` at the forcing's extrema (where a forcing that is a
:class:`~lumped.scene.forcing.SineBurst` turns) and half-way between them, and the first
sign change is refined by Brent's method in ``t``. The scan is exact when each guard is
monotone in the force between two extrema of the forcing (the affine guards of every
built-in law, ``tau -+ F``, with one forcing); with forcings of several frequencies the
half-way samples are a heuristic.

Nothing here names a law: the locks, the guards and the lock values come from the
generated branches (:func:`lumped.codegen.branches.law_branches`). Only forcings that are
absent, constant or a sine burst are taken (the kinds of the compiled loop,
:func:`lumped.scene.forcing_jit.forcing_arrays`); any other runs the steps.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from ...scene import Scene
from ..newton.criteria import ROUNDOFF
from ..nonsmooth.rest_balance import rest_inverse
from ..radau.rows import row_of
from .force_bounds import onto_joint_bounds, split_near_joint_bounds
from .guards import guard_tolerance
from .static_balance import StaticHold, structure_arrays

__all__ = ["StaticHold", "equilibrium_hold", "static_hold", "forcing_kinds"]


def forcing_kinds(scene: Scene, plan) -> tuple[np.ndarray | None, np.ndarray | None]:
    """``(fkind, fpar)`` of the scene's forcing (kinds 0 none, 1 constant, 2 sine burst),
    or ``(None, None)`` when a forcing is of another kind; kept on ``plan``."""
    got = getattr(plan, "forcing_kinds", None)
    if got is None:
        from ...scene.forcing import zero_forcing
        from ...scene.forcing_jit import forcing_arrays

        fkind, fpar, _ = forcing_arrays(scene, 1.0, 0)
        for i, fn in enumerate(scene.forcing):
            if fn is zero_forcing:
                fkind[i] = 0
        got = (None, None) if (fkind == 3).any() else (fkind, fpar)
        plan.forcing_kinds = got
    return got


def static_hold(scene: Scene, plan, modes: Sequence[int], x: list[float],
                v: list[float], F: list[float], fkind: np.ndarray | None,
                fpar: np.ndarray | None) -> StaticHold | None:
    """The :class:`StaticHold` of the state, or ``None`` when the scene is not at rest in a
    mode that locks every node (see the module notes) or its forcing is not taken. The
    structure of a mode is kept on ``plan.structure`` (the scene's
    :class:`~lumped.solvers.eventdriven.setup.ScenePlan`'s parts of its structure alone,
    shared by the plans of that structure)."""
    if fkind is None or any(vi != 0.0 for vi in v):
        return None
    cache = plan.structure.setdefault("hold_structure", {})
    key = tuple(modes)
    got = cache.get(key, False)
    if got is False:
        got = cache[key] = _structure(scene, plan.branches, modes)
    if got is None:
        return None
    free, minv, K, fixed, arrays = got
    c = [sum(K[i][e] * F[e] for e in fixed) for i in range(len(v))]
    return StaticHold(scene, x, v, F, free, minv, c, fkind, fpar, arrays)


def equilibrium_hold(scene: Scene, ms, t: float, x: list[float], v: list[float],
                     F: list[float], fkind: np.ndarray | None, fpar: np.ndarray | None
                     ) -> StaticHold | None:
    r"""The :class:`StaticHold` of an equilibrium under a constant forcing, or ``None``.

    When every node is at rest (``v_i = 0`` exactly), the forcing is constant (absent or
    constant, no sine burst), every node's balance holds to the rounding of its terms,

    .. math::

        \Bigl|f_i + \sum_{a_e = i} F_e - \sum_{b_e = i} F_e\Bigr| \le 4 \epsilon
        \Bigl(|f_i| + \sum_{e \ni i} |F_e|\Bigr),

    every guard of every element's held branch holds at ``(q_e, F_e)`` (to its
    round-off tolerance, :func:`lumped.solvers.modes.guards.guard_tolerance`), and every
    lock in parallel (``ms.cones``) sits on a bound of its force interval (a guard zero to
    that tolerance: the split has no room on that side; one inside its interval leaves
    the split to the steps' rule, :mod:`lumped.solvers.radau.cone_split`), then
    ``x(t) = x(t_0)``, ``v = 0``, ``F(t) = F(t_0)`` solves the held mode's DAE
    (``x' = v = 0``, ``m v' = 0``, and each law ``R_e(q_e, F_e) = 0`` at its frozen ``q_e``),
    and its guards stay where they are: it holds up to the next breakpoint. This takes
    the locks in parallel too (a split among them that the steps' cone rule would keep),
    which :func:`static_hold` leaves to the steps: e.g. a mass on two stuck Bingham
    dashpots loaded by exactly the sum of their yield forces, both forces on their
    bounds, where the stage forces scattered around the bounds and each step read a
    crossing (38 loop passes an accepted step). Such
    forces within ``rtol`` of a joint bound are put on it first (:mod:`.force_bounds`).
    Stuck dashpots in parallel to ground whose load lies within their joint interval by
    less than the steps resolve are held at the stage rule's split, each force inside its
    interval (:func:`lumped.solvers.modes.force_bounds.split_near_joint_bounds`).
    """
    if fkind is None or (fkind == 2).any() or any(vi != 0.0 for vi in v):
        return None
    snapped = onto_joint_bounds(scene, ms.cones, F, ms.rtol)  # (a load at their joint bound)
    hold = _equilibrium_hold(scene, ms, t, x, v, snapped, fkind, fpar)
    if hold is None and snapped != F:
        hold = _equilibrium_hold(scene, ms, t, x, v, F, fkind, fpar)
    if hold is None:  # (a load within their joint bound by less than the steps resolve)
        split, members = split_near_joint_bounds(scene, ms.lbs, ms.modes, t, F)
        if members:
            hold = _equilibrium_hold(scene, ms, t, x, v, split, fkind, fpar, members)
    return hold


def _equilibrium_hold(scene: Scene, ms, t: float, x: list[float], v: list[float],
                      F: list[float], fkind: np.ndarray, fpar: np.ndarray | None,
                      split: set[int] = frozenset()) -> StaticHold | None:
    """:func:`equilibrium_hold` at the forces ``F`` (the nodes at rest, the forcing
    constant); the locks in parallel of ``split`` may sit inside their intervals."""
    N = len(v)
    net = scene.net_forces(t, F)
    scale = [abs(fi) for fi in scene.external_forces(t)]
    for e, Fe in enumerate(F):
        for i in (scene.elem_a[e], scene.elem_b[e]):
            if i >= 0:
                scale[i] += abs(Fe)
    if not all(abs(r) <= ROUNDOFF * s for r, s in zip(net, scale, strict=True)):
        return None
    q = scene.elongations(x, v)
    for e, guard in enumerate(ms.guards):
        tol = guard_tolerance(q[e], F[e])
        gs = guard(q[e], F[e])
        if not all(g + tol >= 0.0 for g in gs):
            return None
        if e in ms.cones and e not in split and not any(abs(g) <= tol for g in gs):
            return None  # inside its cone: the split is the steps' rule's to choose
    return StaticHold(scene, x, v, F, [], [], [0.0] * N, fkind, fpar,
                      (np.zeros((0, N)), np.zeros(0, dtype=np.int64)))


def _structure(scene: Scene, branches: Sequence, modes: Sequence[int]):
    """``(free, -K_free^-1, K, fixed, (-K_free^-1, free) as arrays)`` of a mode, or
    ``None`` when it does not lock every node."""
    N = len(scene.nodes)
    free = []
    for e, el in enumerate(scene.elements):
        info = branches[e].info[modes[e]]
        if info.locks:
            if info.lock_value is None or (el.kind == "dashpot" and info.lock_value != 0.0):
                return None
            free.append(e)
        elif info.dR_dF.is_number and info.dR_dF == 0:
            return None
    got = rest_inverse(N, tuple(zip(scene.elem_a, scene.elem_b, strict=True)), tuple(free))
    if got is None:
        return None
    minv, K, fixed = got
    return free, minv, K, fixed, structure_arrays(minv, free)


def hold_interval(scene: Scene, plan, ms, t: float, t_stop: float, x: list[float],
                  v: list[float], F: list[float], dense, rows
                  ) -> tuple[float, list[float], bool] | None:
    """Take the stuck interval from ``t`` in one piece, if the state allows it
    (:func:`static_hold`): the dense segment and the output rows at the scan's samples go
    into ``dense`` and ``rows``; returns ``(t_1, F(t_1), broke_out)`` where ``t_1`` is the
    break-out time or ``t_stop``, or ``None`` (the steps must run: not stuck, or the
    break-out is at ``t`` itself)."""
    fkind, fpar = forcing_kinds(scene, plan)
    if ms.cones:
        # locks in parallel: their split rule is the steps' (lumped.solvers.radau.stage),
        # unless nothing moves and no force changes
        hold = equilibrium_hold(scene, ms, t, x, v, F, fkind, fpar)
    else:
        hold = static_hold(scene, plan, ms.modes, x, v, F, fkind, fpar)
    if hold is None:
        return None
    t_b, samples = hold.breakout(t, t_stop, ms.guards, ms.modes, ms.fast)
    if t_b is not None and t_b - t <= 16 * 2.220446049250313e-16 * max(1.0, abs(t)):
        return None
    t1 = t_stop if t_b is None else t_b
    dense.add_static(t, t1, hold)
    F1 = hold.forces(t1)
    # the rows at the samples and at t1, in one block
    rows.extend(np.array([row_of(s, x, v, hold.forces(s)) for s in samples if s < t1]
                         + [row_of(t1, x, v, F1)], dtype=float))
    ms.mark_free(t, t1, x, v, F1)  # elements on cycles whose forces are not unique
    return t1, F1, t_b is not None
