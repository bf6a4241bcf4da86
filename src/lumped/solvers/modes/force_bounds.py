r"""Forces the stage Newton leaves off the bounds their laws put them on, put back.

1. :func:`onto_joint_bounds`. Two or more elements held on locks between the same two
   nodes (a mass stuck on a Coulomb element and a Herschel-Bulkley dashpot to ground)
   share the load ``T`` between them; each admits the interval ``[lo_e, hi_e]`` of its
   lock (:func:`lumped.solvers.modes.lock_events.lock_cones`). When ``T`` is the sum of
   their upper (or lower) bounds, the only split is every force on that bound,

   .. math:: \sum_e s_e F_e = \sum_e \mathrm{hi}'_e \ \Longrightarrow\
             s_e F_e = \mathrm{hi}'_e,

   (``s_e = +-1`` the element's direction against the pair's, ``[lo'_e, hi'_e]`` its
   interval so turned), but the stage Newton leaves the split to its force tolerance:
   seen on one mass under a load equal to the joint yield force to the last bit, one
   force ``1.4e-13`` above its yield force and the other as far below (rtol ``1e-10``),
   whose guard reads crossed at once (a step below the step floor and a backward-Euler
   bridge). The caller checks that every balance still holds to round-off.
2. :func:`onto_slip_ends`. A yield dashpot between masses and ground (its force read by
   no junction's balance) that switches branch at a guard event with its rate within the
   velocity tolerance of 0 (a reversal through its yield band, a break-out) has at ``t``
   its yield force: the edge of its law's set at rest nearest the probe's force
   (:func:`lumped.solvers.implicit.initial_slip.rest_edge`, as at ``t = 0``). The probe
   reads it at its own rate: a Herschel-Bulkley ``n = 2`` dashpot (``q = -gamma (|F| -
   tau)^2``, flat at its yield force) reversing under a sine took ``-tau - 2.4e-6``, off
   its law at the rate ``2e-15`` left by the landing, and every stage from there failed
   down to the step floor (a backward-Euler bridge of ``3.9e-7`` s).
3. :func:`slip_beyond_joint_bounds`. The converse of 1: stuck dashpots in parallel
   between ground and one node (a mass or a junction that no other lock holds, joined to
   nothing else but springs, whose forces at ``t`` are their laws' at ``x``) carry the
   load ``T`` on that node only within their joint interval,

   .. math:: \sum_e \min(s_e \mathrm{lo}_e, s_e \mathrm{hi}_e) \le T \le
             \sum_e \max(s_e \mathrm{lo}_e, s_e \mathrm{hi}_e),
             \qquad T = -\Bigl(f_n + \sum_{e \notin \text{group}} s_e F_e\Bigr),

   (``s_e = +1`` at an element's first node ``a``, ``-1`` at its second ``b``, as in the
   balance ``net_n = f_n + sum_{a_e = n} F_e - sum_{b_e = n} F_e``). A load beyond it by
   more than the balance's round-off ``ROUNDOFF (|f_n| + sum_e |F_e|)`` (the rule of
   :func:`lumped.solvers.modes.stuck.equilibrium_hold`, which holds a load within it on
   the bounds) breaks them out together: they share one rate. The mode probe cannot tell
   (its force tolerance over a probe of ``5e-10`` s is ``rtol m / h ~ 6e-5``, and the
   lock rule of :func:`lumped.solvers.nonsmooth.locks.lock_parallel_rates` admits forces
   ``sqrt(eps)`` beyond a yield force): a mass on a Bingham and two Herschel-Bulkley
   dashpots to ground under a load ``2.4e-15`` (``11 eps``) or ``1e-9`` beyond their
   joint yield force read stuck, no split within the bounds balanced the load, and the
   run crept by steps of ``1e-15`` s and stopped after 12 backward-Euler bridges (issue
   29). Their slip is slow (``1e-30`` and ``1e-18`` m/s, the shear-thickening dashpot
   taking the excess), and ``radau5`` takes it in 9 steps.
4. :func:`split_near_joint_bounds`. The same group (or one between two nodes, read at
   one of them that is held by no other lock and joined to nothing else but springs)
   under a load *within* its joint
   interval by less than ``JOINT_MARGIN W`` (``W = sum_e w_e``, the half-widths' sum) never
   moves, but its split is not fixed. The stage rule,
   :func:`lumped.solvers.radau.cone_split.cone_solver`, puts the forces in proportion to
   the half-widths, ``s_e F_e = s_e c_e + w_e (T - sum_k s_k c_k) / W``, each a fraction
   ``(top - T) / W`` of its half-width inside its bound; until that split was solved to
   round-off (issue 29) the stage read it to ``eps m / h``, so a force landed past its
   bound, the active set held it ``1e-6 w_e`` inside
   (:meth:`lumped.solvers.radau.stage.StageSystem.solve`), which left the others more
   than they carry. A mass on a Bingham
   and two Herschel-Bulkley dashpots to ground under loads ``1e-12`` and ``1e-9`` (of
   the joint yield force) inside it read a force ``3e-9`` past its yield force at steps
   of ``8e-8`` s, chattered across the guard of the shear-thickening dashpot, crept and
   stopped after 12 backward-Euler bridges (issue 29). Under a constant forcing
   :func:`lumped.solvers.modes.stuck.equilibrium_hold` holds the group at the stage
   rule's split, exact: ``x`` and ``v = 0`` frozen, every force within its interval,
   ``n``'s balance to round-off (the last member's force is its remainder).
5. :func:`stuck_beside_locks`. A dashpot between two nodes that another element's lock
   holds together (a stuck dashpot, a taut string: their rate is 0) has rate 0 too; on a
   slip branch its law then reads its yield force, the end of its set at rest, where a
   branch flat at its end (Herschel-Bulkley ``n > 1``: ``dR/dF = n gamma (F -
   tau)^(n-1) = 0`` at ``tau``) leaves the stage Newton a singular Jacobian in that force.
   The mode probe reads such a dashpot on its slip branch when its force lands a hair
   beyond its yield force (the rate's round-off through the flat law: ``8e-9`` above
   ``tau`` on a Herschel-Bulkley ``n = 2`` dashpot beside a stuck Bingham one), and every
   step from there failed Newton and was halved: 510 steps and 1115 rejected over the
   ``0.02`` s after the stick, 2355 steps, 6379 rejected and 40 s of CPU over ``[0,
   0.5]`` (seed 23009's draw of the tight-tolerance property). Its stuck branch holds the
   same motion (rate 0, its force within its set at rest): put on it, the two are locks
   in parallel whose split is free (:mod:`lumped.solvers.radau.cone_split`), and the run
   takes 122 steps and 16 rejected over those ``0.02`` s, 128 and 16 over ``[0, 0.5]``
   (1.5 s), its motion within ``3e-15`` of the slow run's.
   Only a dashpot whose force is within its stuck interval to the resolution of a force
   on a flat branch, ``sqrt(rtol) (1 + |F|)`` (as 2.), is moved. The mode probe's rule
   for dashpots whose ends other locks join (:func:`lumped.solvers.nonsmooth.locks.
   lock_parallel_rates`, through a path of locks) reads a rate within the round-off of
   the forces or positions as zero; beside a lock between the *same* two nodes the rate
   is the lock's own, zero by the lock whatever the probe's Newton leaves (``1.4e-13``
   at seed 23009's stick, against a round-off of ``1e-15``), so this rule tests the
   force alone.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...scene import Scene
from ...scene.network import across
from ..implicit.initial_slip import known_rate_dashpots, rest_edge, set_valued_at_rest
from ..newton.criteria import ROUNDOFF
from .lock_events import lock_cones

__all__ = ["JOINT_MARGIN", "onto_joint_bounds", "onto_rest_edges", "onto_slip_ends",
           "slip_beyond_joint_bounds", "split_near_joint_bounds", "stuck_beside_locks",
           "group_modes"]

#: How near an end of their joint interval (a fraction of the half-widths' sum) a load on
#: stuck dashpots in parallel is held by a static split (see the module notes, 4): the
#: inset of a force the stage split holds at its bound (:mod:`lumped.solvers.radau.stage`).
JOINT_MARGIN = 1e-6


def onto_joint_bounds(scene: Scene, cones: dict[int, tuple[float, float, float, float]],
                      F: list[float], rtol: float) -> list[float]:
    """``F`` with each group of locks in parallel (elements of ``cones`` between the same
    two nodes) whose oriented sum lies within ``rtol`` of its members' forces of the sum
    of their upper or lower bounds (see the module notes) put on those bounds; the other
    forces as they are (a new list)."""
    groups: dict[tuple[int, int], list[int]] = {}
    for e in cones:
        a, b = scene.elem_a[e], scene.elem_b[e]
        groups.setdefault((min(a, b), max(a, b)), []).append(e)
    out = list(F)
    for (a, _), members in groups.items():
        if len(members) < 2:
            continue
        s = {e: 1.0 if scene.elem_a[e] == a else -1.0 for e in members}
        total = sum(s[e] * F[e] for e in members)
        tol = rtol * sum(abs(F[e]) for e in members)
        for pick in (3, 2):  # hi, then lo (oriented: -lo, -hi for s = -1)
            bound = {e: cones[e][pick] if s[e] > 0 else cones[e][5 - pick] for e in members}
            if abs(total - sum(s[e] * bound[e] for e in members)) <= tol:
                for e in members:
                    out[e] = bound[e]
                break
    return out


def onto_slip_ends(scene: Scene, old: Sequence[int], new: Sequence[int], v: list[float],
                   F: list[float], tol: float, rtol: float) -> list[float]:
    """``F`` with each yield dashpot between masses and ground that switches from branch
    ``old[e]`` to ``new[e]`` at a rate ``|v_b - v_a| <= tol`` on the edge ``F*`` of its set
    at rest nearest ``F_e`` (:func:`onto_rest_edges`). A new list."""
    return onto_rest_edges(scene, [e for e in range(len(F)) if new[e] != old[e]], v, F, tol,
                           rtol)


def onto_rest_edges(scene: Scene, candidates: Sequence[int], v: list[float],
                    F: list[float], tol: float, rtol: float) -> list[float]:
    """``F`` with each yield dashpot of ``candidates`` between masses and ground at a rate
    ``|v_b - v_a| <= tol`` on the edge ``F*`` of its set at rest nearest ``F_e`` (see the
    module notes; a force within that set stays), when that moves it by at most
    ``sqrt(rtol) (1 + |F*|)``: the resolution of a force on a branch flat at its end (``q
    ~ (|F| - tau)^2``) from rates known to ``rtol``. A larger move is no probe's artefact
    (a steep law whose rate is within ``tol`` of 0 but whose force is not its yield force)
    and is left alone. A new list."""
    out = list(F)
    for e in known_rate_dashpots(scene, list(candidates)):
        a, b = scene.elem_a[e], scene.elem_b[e]
        if abs(across(v, a, b)) <= tol:
            kernel = scene.elements[e].law.kernel
            if set_valued_at_rest(kernel):  # (a yield law)
                edge = rest_edge(kernel, F[e])
                if abs(edge - F[e]) <= math.sqrt(rtol) * (1.0 + abs(edge)):
                    out[e] = edge
    return out


def _stuck_groups(scene: Scene, branches: Sequence, modes: Sequence[int], t: float,
                  F: Sequence[float], grounded: bool = True):
    """Each group of two or more dashpots stuck in parallel between ground and one node
    ``n`` (or, unless ``grounded``, between two nodes, ``n`` one of them), ``n`` held by no
    other lock and joined to nothing else but springs (see the module notes, 3), as
    ``(members, sign, cones, T, scale)``: ``sign[e] = s_e`` at ``n``, ``cones`` their lock
    intervals (:func:`lumped.solvers.modes.lock_events.lock_cones`, every end finite),
    ``T`` the load on ``n`` they carry and ``scale`` the sum of the magnitudes in ``n``'s
    balance (the springs' forces and the members' bounds)."""
    groups: dict[tuple[int, int], list[int]] = {}
    other_locks: set[int] = set()
    for e, el in enumerate(scene.elements):
        a, b = scene.elem_a[e], scene.elem_b[e]
        info = branches[e].info[modes[e]]
        if not info.locks:
            continue
        if el.kind == "dashpot" and info.lock_value == 0.0 and (
                min(a, b) < 0 <= max(a, b) or not grounded and min(a, b) >= 0):
            groups.setdefault((max(a, b), min(a, b)), []).append(e)
        else:
            other_locks.update(i for i in (a, b) if i >= 0)
    f = scene.external_forces(t) if groups else []
    for pair, members in groups.items():
        if len(members) < 2:
            continue
        for n in pair:
            if n < 0 or n in other_locks:
                continue
            others = [e for e in range(len(F)) if e not in members
                      and n in (scene.elem_a[e], scene.elem_b[e])]
            if all(scene.elements[e].kind == "spring" for e in others):
                break  # (a dashpot's force at t may be a held split's, not its law's)
        else:
            continue
        cones = lock_cones(branches, modes, F, members)
        if len(cones) < len(members) or not all(
                math.isfinite(cones[e][2]) and math.isfinite(cones[e][3]) for e in members):
            continue
        sign = {e: 1.0 if scene.elem_a[e] == n else -1.0 for e in members}
        rest, scale = f[n], abs(f[n])
        for e in others:
            rest += (1.0 if scene.elem_a[e] == n else -1.0) * F[e]
            scale += abs(F[e])
        scale += sum(max(abs(cones[e][2]), abs(cones[e][3])) for e in members)
        yield members, sign, cones, -rest, scale


def _joint_interval(members: list[int], sign: dict[int, float],
                    cones: dict[int, tuple[float, float, float, float]]) -> tuple[float, float]:
    """``(bottom, top)``: the interval of loads ``sum_e s_e F_e`` a group of
    :func:`_stuck_groups` carries with each force within its lock interval."""
    return (sum(min(sign[e] * cones[e][2], sign[e] * cones[e][3]) for e in members),
            sum(max(sign[e] * cones[e][2], sign[e] * cones[e][3]) for e in members))


def slip_beyond_joint_bounds(scene: Scene, branches: Sequence, modes: list[int], t: float,
                             F: Sequence[float]) -> list[int]:
    """``modes`` with each group of two or more dashpots stuck in parallel between ground
    and one node ``n`` (held by no other lock, joined to nothing else but springs) whose
    load just after ``t`` (the forcing and the springs' forces ``F``) lies beyond their
    joint interval by more than the round-off of ``n``'s balance put on the branches their
    laws read beyond it (see the module notes, 3); the other modes as they are (a new list).

    The forcing is read one ulp after ``t``, beyond a jump at ``t`` (the mode is the one
    after it): a sine burst switched off at its peak, ``1e-12`` to ``1e-7`` beyond the
    joint yield force, takes that peak at ``t_off`` itself, and the group, which the probe
    read stuck under the load ``0`` after it, was sent to slip on; every step failed and
    the run stopped on its work budget (issue 29)."""
    out = list(modes)
    after = math.nextafter(t, math.inf)
    for members, sign, cones, T, scale in _stuck_groups(scene, branches, modes, after, F):
        bottom, top = _joint_interval(members, sign, cones)
        if T - top > ROUNDOFF * scale:
            up = True
        elif bottom - T > ROUNDOFF * scale:
            up = False
        else:
            continue
        for e in members:  # s_e F_e beyond its end: F_e beyond hi (s_e > 0) or lo
            _, _, lo, hi = cones[e]
            beyond = hi + 1.0 + abs(hi) if (sign[e] > 0) == up else lo - 1.0 - abs(lo)
            b = branches[e].branch(0.0, beyond)
            if not branches[e].info[b].locks:
                out[e] = b
    return out


def split_near_joint_bounds(scene: Scene, branches: Sequence, modes: Sequence[int],
                            t: float, F: Sequence[float]) -> tuple[list[float], set[int]]:
    r"""``(F, members)``: ``F`` with each group of dashpots stuck in parallel between
    ground and one node, or between two nodes, one of which is held by no other lock and
    joined to nothing else but springs (as :func:`slip_beyond_joint_bounds`, which takes
    only groups to ground), whose load ``T`` on that node lies within
    their joint interval but within ``JOINT_MARGIN W`` of an end of it (``W`` their
    half-widths' sum) given the split of the stage rule (see the module notes, 4),

    .. math:: s_e F_e = s_e c_e + w_e \frac{T - \sum_k s_k c_k}{W},

    the last member's force the balance's remainder; the members so split (a new list and
    set; both as they were when no group is that near)."""
    out, split = list(F), set()
    for members, sign, cones, T, _ in _stuck_groups(scene, branches, modes, t, F, grounded=False):
        bottom, top = _joint_interval(members, sign, cones)
        W = sum(cones[e][1] for e in members)
        if not (bottom <= T <= top and min(top - T, T - bottom) <= JOINT_MARGIN * W):
            continue
        share = (T - sum(sign[e] * cones[e][0] for e in members)) / W
        got = {}
        for e in members:  # (within its interval: |share| <= 1 when T is within)
            c, w, lo, hi = cones[e]
            got[e] = min(max(c + sign[e] * w * share, lo), hi)
        last = max(members, key=lambda e: cones[e][1])
        got[last] = sign[last] * (T - sum(sign[e] * got[e] for e in members if e != last))
        if not cones[last][2] <= got[last] <= cones[last][3]:
            continue  # (an interval off centre whose split the clamp moved: the steps')
        for e, Fe in got.items():
            out[e] = Fe
        split.update(members)
    return out, split


def stuck_beside_locks(scene: Scene, branches: Sequence, modes: Sequence[int],
                       F: Sequence[float], rtol: float) -> list[int]:
    """``modes`` with each dashpot on a slip branch between two nodes that another element's
    lock holds together put on its stuck branch (its locking branch at rate 0), when its
    force ``F_e`` lies within that branch's interval (:func:`lock_cones`) to
    ``sqrt(rtol) (1 + |F_e|)`` (see the module notes, 5); the other modes as they are (a
    new list). A lock holds two nodes together when it is a spring's position lock (a
    taut string) or a dashpot's lock at rate 0 (a stuck Bingham, Coulomb or
    Herschel-Bulkley element)."""
    out = list(modes)
    ea, eb, elements = scene.elem_a, scene.elem_b, scene.elements
    for e, el in enumerate(elements):
        if el.kind != "dashpot" or branches[e].info[out[e]].locks:
            continue
        ends = {ea[e], eb[e]}
        if not any(k != e and {ea[k], eb[k]} == ends and _holds_together(
                elements[k].kind, branches[k].info[out[k]]) for k in range(len(elements))):
            continue
        stuck = next((i for i, info in enumerate(branches[e].info)
                      if info.locks and info.lock_value == 0), None)
        if stuck is None:
            continue
        trial = list(out)
        trial[e] = stuck
        cone = lock_cones(branches, trial, F, (e,)).get(e)
        Fe = float(F[e])
        if cone is not None and cone[2] - math.sqrt(rtol) * (1.0 + abs(Fe)) <= Fe \
                <= cone[3] + math.sqrt(rtol) * (1.0 + abs(Fe)):
            out[e] = stuck
    return out


def group_modes(scene: Scene, branches: Sequence, modes: Sequence[int], t: float,
                F: Sequence[float], rtol: float) -> list[int]:
    """The modes after ``t`` of the groups of locks in parallel: :func:`slip_beyond_joint_bounds`,
    then :func:`stuck_beside_locks` (a new list)."""
    return stuck_beside_locks(scene, branches, slip_beyond_joint_bounds(
        scene, branches, modes, t, F), F, rtol)


def _holds_together(kind: str, info) -> bool:
    """Whether a branch holds its element's two nodes together: a spring's position lock,
    or a dashpot's lock at rate 0."""
    return bool(info.locks) and info.lock_value is not None and (
        kind == "spring" or info.lock_value == 0)
