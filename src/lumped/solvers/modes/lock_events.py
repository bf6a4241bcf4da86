r"""What a new mode does to the state at an event of the adaptive method: the locks it
enters and the impacts.

A dashpot that enters a rate lock (``q = const``) gets its rate set exactly
(:func:`hold_rate_locks`), so a stuck velocity is exactly zero; every element on a lock up
to the step's tolerance is put exactly on it (:func:`snap_to_locks`); the force interval
each lock admits weighs the split of the force among locks in parallel (:func:`lock_cones`,
for :func:`lumped.solvers.radau.cone_split.cone_solver`); a spring that locks its
elongation while its ends approach takes an impulse (:func:`apply_impacts`, by
:mod:`lumped.solvers.nonsmooth.impacts`), and the forces the locks then carry start the
choice of the mode after it (:func:`after_impact_forces`). The mode itself is chosen in
:mod:`lumped.solvers.modes.choice`.
"""

from __future__ import annotations

import math
import sys
from collections.abc import Sequence

from ...scene import Mass, Scene
from ...scene.network import across
from ..nonsmooth.impacts import impact_solve
from ..nonsmooth.lock_forces import forces_with_held

__all__ = ["after_impact_forces", "apply_impacts", "hold_rate_locks",
           "hold_strung_junctions", "hold_taut_strings", "lock_cones", "snap_to_locks"]

_EPS = sys.float_info.epsilon


def hold_rate_locks(scene: Scene, branches: Sequence, modes: Sequence[int],
                    v: list[float], locked_now: Sequence[int] = ()) -> list[int]:
    """Set exactly the rate fixed by every dashpot on a rate-locking branch (``q = L``).

    Only a dashpot between a mass and ground is set here (``v = +-L``, exactly), and one
    between a junction and ground that the event just locked (``locked_now``: a junction
    stopping in finite time, whose probe read the lock at a rate of ``-2e-7``: left so,
    the step after the stop started off its stages and its dense output carried ``6e-8``
    into the junction's rest); one between two nodes is left as the probe step found it.
    Returns the elements set.
    """
    done = []
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot":
            continue
        info = branches[e].info[modes[e]]
        if not info.locks or info.lock_value is None:
            continue
        a, b = scene.elem_a[e], scene.elem_b[e]
        L = float(info.lock_value)
        if a < 0 and b >= 0 and (isinstance(scene.nodes[b], Mass) or e in locked_now):
            v[b] = L
        elif b < 0 and a >= 0 and (isinstance(scene.nodes[a], Mass) or e in locked_now):
            v[a] = -L if L != 0.0 else 0.0
        else:
            continue
        done.append(e)
    return done


def hold_strung_junctions(scene: Scene, branches: Sequence, modes: Sequence[int],
                          v: list[float], tol: float) -> list[int]:
    r"""Put the junctions that held position locks (taut strings, ``q = L``, so ``q' =
    0``) join to anything back on those locks, when one of them is off its lock's rate by
    more than ``tol``; ``v`` in place. Returns the locks held (empty: ``v`` unchanged).

    After an impact the junctions take the mode probe's velocities, at ``t + h_p``: where
    every short probe failed, a junction a string had just gone taut on read ``-0.7866``
    (the probe of ``1.6e-4`` s) beside its mass's ``-0.7768``, and the first step from that
    state failed at every size down to the step floor (its dense output's defect 561
    against the string's lock, whatever the step). The velocities move to the nearest
    ones in the kinetic-energy norm that hold every such lock's rate at 0
    (:func:`lumped.solvers.nonsmooth.impacts.impact_solve` with targets, as
    :func:`snap_to_locks`): a junction has no mass, so it takes the velocity its strings
    tie it to, through a chain of junctions too, and no mass moves. Within ``tol`` (the
    run's velocity tolerance) every junction keeps the probe's velocity, whose forces it
    matches (set always, a Coulomb element stuck at a junction ``1e-8`` s after an
    impact started ``1.2e-7`` beyond its yield force)."""
    ea, eb, nodes = scene.elem_a, scene.elem_b, scene.nodes
    held = [e for e in _taut_strings(scene, branches, modes) if any(
        i >= 0 and not isinstance(nodes[i], Mass) for i in (ea[e], eb[e]))]
    if not any(abs(across(v, ea[e], eb[e])) > tol for e in held):
        return []
    v[:] = _at_rate_zero(scene, v, held)
    return held


def hold_taut_strings(scene: Scene, branches: Sequence, modes: Sequence[int],
                      v: list[float]) -> list[float]:
    r"""``v`` with every taut string of ``modes`` (a spring on a position lock, ``q = L``,
    so ``q' = 0``) at rate 0: the velocities nearest in the kinetic-energy norm that hold
    them all (:func:`lumped.solvers.nonsmooth.impacts.impact_solve` with targets 0, an
    impulse along the strings: momentum conserved, no energy added), a new list; ``v``
    itself when every such rate is 0 already.

    The end of a bridge by backward Euler (:mod:`lumped.solvers.eventdriven.bridge`) is
    accurate to its steps only: a mass held by a taut string to ground ended one at
    ``v = -2.1e-9``, and the mode the full laws chose there kept the string taut. Every
    ``radau5`` step from that state read the string's rate as an error of ``2e4``
    tolerances, whatever its size, down to the step floor; 11 more bridges, each followed
    by the same stop, and the run failed (a draw of the tight-tolerance property, seed
    25039 of the ``long`` profile: two masses, three strings and a Coulomb element).
    With moving supports (a :class:`~lumped.scene.supports.SupportFrame`'s view) a
    string's rate holds its support's velocity too: ``v`` is left as it is there."""
    if getattr(scene, "support_frame", None) is not None:
        return v
    held = _taut_strings(scene, branches, modes)
    if all(across(v, scene.elem_a[e], scene.elem_b[e]) == 0.0 for e in held):
        return v
    return _at_rate_zero(scene, v, held)


def _taut_strings(scene: Scene, branches: Sequence, modes: Sequence[int]) -> list[int]:
    """The springs ``modes`` holds on a position lock (a taut string, ``q = L``)."""
    return [e for e, el in enumerate(scene.elements) if el.kind == "spring"
            and branches[e].info[modes[e]].locks
            and branches[e].info[modes[e]].lock_value is not None]


def _at_rate_zero(scene: Scene, v: list[float], held: list[int]) -> list[float]:
    """The velocities nearest ``v`` in the kinetic-energy norm with every element of
    ``held`` at rate 0 (:func:`lumped.solvers.nonsmooth.impacts.impact_solve` with targets
    0), as Python floats."""
    return [float(vi) for vi in impact_solve(scene, v, held, 0.0, target=[0.0] * len(held))[0]]


def snap_to_locks(scene: Scene, branches: Sequence, x: list[float], v: list[float],
                  F: list[float], tol: float, tol_x: float = 0.0) -> list[int]:
    r"""Put every element that sits on a lock, up to the step's tolerance, exactly on it.

    An element is *on a lock* at an event when one of its law's locking branches with a
    known value ``L`` (:attr:`BranchInfo.locks`, ``lock_value``; a stuck dashpot,
    ``q' = 0``, or a taut string, ``q = L``) admits its force (every guard of that branch
    at ``(L, F_e)`` above ``-sqrt(eps) (1 + |F_e|)``) and its rate is within ``tol`` of the
    lock's rate (``|q - L| <= tol`` for a dashpot, ``|q'| <= tol`` for a spring, whose
    elongation must also be within ``max(sqrt(eps) (1 + |L|), tol_x)`` of ``L``: a slow
    mass whose string's length was located ``1.2e-7`` late, within the step's position
    tolerance ``tol_x``, kept its rate of ``6e-5`` against the taut string, and every
    step from there failed down to the step floor).

    The velocities ``v`` are moved, in place, to the nearest ones in the kinetic-energy norm
    that hold all those rates exactly (:func:`lumped.solvers.nonsmooth.impacts` with
    targets: momentum conserved, a change of at most ``tol``). Why: where a slip branch ends
    flat (``dq/dF = 0`` at the yield force, Herschel-Bulkley ``n > 1``) a force located on
    its guard to round-off still leaves a rate of the order of the Newton tolerance, and the
    vanishing probe step of :func:`lumped.solvers.modes.choice.select_modes` reads ``m q' /
    h_p`` as a force far beyond the yield force: the element would be sent to the opposite
    slip branch.

    Returns
    -------
    list of int
        The elements held (empty: ``v`` is unchanged).
    """
    slack = math.sqrt(_EPS)
    held, target = [], []
    q_x = scene.elongations(x, [0.0] * len(x))
    for e, el in enumerate(scene.elements):
        lb = branches[e]
        a, b = scene.elem_a[e], scene.elem_b[e]
        rate = across(v, a, b)
        for info in lb.info:
            L = info.lock_value
            if not info.locks or L is None:
                continue
            dashpot = el.kind == "dashpot"
            off = rate - L if dashpot else rate
            if abs(off) > tol or (not dashpot and abs(q_x[e] - L) > max(
                    slack * (1.0 + abs(L)), tol_x)):
                continue
            gs = lb.guards_for(info.index)(L if dashpot else q_x[e], F[e])
            if all(g >= -slack * (1.0 + abs(F[e])) for g in gs):
                held.append(e)
                target.append(float(L) if dashpot else 0.0)
                break
    if held and not _ground_locks(scene, held, target, v):
        v_new, _, _ = impact_solve(scene, v, held, 0.0, target=target)
        v[:] = v_new
    return held


def _ground_locks(scene: Scene, held: Sequence[int], target: Sequence[float],
                  v: list[float]) -> bool:
    """The rates ``target`` of ``held`` set in place when each held element joins its own
    mass to ground: then the nearest velocities in the kinetic-energy norm move only
    those masses, each onto its lock (``v_b = L`` or ``v_a = -L``); ``False`` (nothing
    changed) otherwise."""
    nodes, vals = [], []
    for e, L in zip(held, target, strict=True):
        a, b = scene.elem_a[e], scene.elem_b[e]
        node, val = (b, L) if a < 0 <= b else ((a, -L if L != 0.0 else 0.0) if b < 0 <= a
                                              else (-1, 0.0))
        if node < 0 or node in nodes or not isinstance(scene.nodes[node], Mass):
            return False
        nodes.append(node)
        vals.append(val)
    for node, val in zip(nodes, vals, strict=True):
        v[node] = float(val)
    return True


def lock_cones(branches: Sequence, modes: Sequence[int], F: Sequence[float],
               elements: Sequence[int]) -> dict[int, tuple[float, float, float, float]]:
    r"""The force interval each locked element of ``elements`` admits, as ``e -> (centre,
    half-width, lo, hi)``: where every guard of its locking branch (at ``q`` = the lock's
    value) is non-negative, read off the guards' slopes in ``F`` at ``F_e`` (exact for the
    affine guards of the built-in laws: Bingham, Coulomb, Herschel-Bulkley stuck,
    ``|F| <= tau``). ``lo, hi`` are the interval's ends; the centre and half-width weigh
    the split (:func:`lumped.solvers.radau.cone_split.cone_solver`). An interval open on a side (a
    taut string, ``F >= k L``) gets the centre ``F_e`` and a half-width ``1e3`` times the
    largest finite one or force, so that it takes the load the others do not, and keeps
    its finite end as ``lo`` or ``hi``: a split below a taut string's ``k L`` (a string
    pushing) is held there. Elements not on a lock with a known value are left out."""
    out: dict[int, tuple[float, float, float, float]] = {}
    open_: list[tuple[int, float, float]] = []
    big = 1.0 + max((abs(f) for f in F), default=0.0)
    for e in elements:
        info = branches[e].info[modes[e]]
        if not info.locks or info.lock_value is None:
            continue
        L, F0 = float(info.lock_value), float(F[e])
        guards = branches[e].guards_for(modes[e])
        d = 1.0 + abs(F0)
        g0, g1 = guards(L, F0), guards(L, F0 + d)
        lo, hi = -math.inf, math.inf
        for a, b in zip(g0, g1, strict=True):
            slope = (b - a) / d
            if slope > 0.0:
                lo = max(lo, F0 - a / slope)
            elif slope < 0.0:
                hi = min(hi, F0 - a / slope)
        if math.isfinite(lo) and math.isfinite(hi) and hi > lo:
            out[e] = (0.5 * (lo + hi), 0.5 * (hi - lo), lo, hi)
            big = max(big, 0.5 * (hi - lo))
        else:
            open_.append((e, lo, hi))
    for e, lo, hi in open_:
        out[e] = (float(F[e]), 1e3 * big, lo, hi)
    return out


def apply_impacts(scene: Scene, branches: Sequence, old: Sequence[int], new: Sequence[int],
                  x: list[float], v: list[float], threshold: float,
                  restitution: float = 0.0, forces: Sequence[float] | None = None,
                  ) -> tuple[list[tuple[int, float]], float] | str:
    """Apply the impulse of every spring that enters a position lock while its ends approach.

    A spring whose new branch locks ``q`` (:attr:`BranchInfo.locks`) with ``|q'| >
    threshold`` is an impact: the velocities jump to those of
    :func:`lumped.solvers.nonsmooth.impacts.impact_velocities` over all the locked springs (``v`` is
    updated in place), and a lock with a known value between a mass and ground gets its
    position set exactly (``x`` in place). ``forces`` (the element forces before the
    event) say which way a lock at rest holds
    (:func:`~lumped.solvers.nonsmooth.impacts.impact_velocities`): a string taut at rest holds in
    tension, whatever the sign of its rate's round-off.

    Returns
    -------
    (hits, energy_lost) or str
        ``hits``: ``(element, impulse)`` of the impacting elements (empty if none), or a
        message when impacts are needed and :mod:`lumped.solvers.nonsmooth.impacts` is missing.
    """
    ea, eb = scene.elem_a, scene.elem_b
    locked = [e for e, el in enumerate(scene.elements)
              if el.kind == "spring" and branches[e].info[new[e]].locks]
    hits = []
    for e in locked:
        if new[e] == old[e]:
            continue
        a, b = ea[e], eb[e]
        rate = across(v, a, b)
        if abs(rate) > threshold:
            hits.append(e)
    if not hits:
        return [], 0.0
    try:
        from ..nonsmooth.impacts import impact_velocities
    except ImportError:  # pragma: no cover - until the impact model is merged
        el = scene.elements[hits[0]]
        return (f"element {el.name!r} (law {el.law_name!r}) locks its elongation while its "
                "ends approach: an impact, and lumped.solvers.nonsmooth.impacts is not available")
    v_after, impulses, lost = impact_velocities(scene, x, v, locked, restitution, forces)
    v[:] = v_after
    inner, gaps = [], []
    for e in hits:
        L = branches[e].info[new[e]].lock_value
        a, b = ea[e], eb[e]
        if L is None and branches[e].info[new[e]].locks and hasattr(branches[e], "lb"):
            # on a moving support (ShiftedBranches): onto q + o_e(t) = L, the clock at t
            R, Rq, _ = branches[e].kernel_for(new[e])(
                scene.elongations(x, v)[e], 0.0 if forces is None else forces[e])
            if Rq != 0.0 and R == R:
                inner.append(e)
                gaps.append(-R / Rq)
        elif L is not None and a < 0 and b >= 0:  # the lock holds q = L and q' = 0 exactly
            x[b], v[b] = float(L), 0.0
        elif L is not None and b < 0 and a >= 0:
            x[a], v[a] = -float(L), 0.0
        elif L is not None and a >= 0 and b >= 0:
            inner.append(e)
            gaps.append(float(L) - (x[b] - x[a]))
    if inner:  # between two nodes: the least move (kinetic-energy norm) onto q = L
        dx, _, _ = impact_solve(scene, [0.0] * len(x), inner, 0.0, target=gaps)
        x[:] = [xi + di for xi, di in zip(x, dx, strict=True)]
    return [(e, impulses[locked.index(e)]) for e in hits], lost


def after_impact_forces(scene: Scene, t: float, x: Sequence[float], v: Sequence[float],
                        F: Sequence[float], hits: Sequence[int],
                        threshold: float) -> tuple[list[float], list[int]]:
    r"""The forces right after an impact from the balance of accelerations, and the
    impacted locks that hold.

    After a plastic impact a string sits on its lock, ``q = L``, at the relative rate
    ``0``; its force before the impact was the spring's, ``k L``, the kink of ``q =
    min(F/k, L)``. The mode choice's vanishing implicit step (``h_p ~ 1e-9`` s) moves ``q``
    by ``h_p^2 a``, far below ``ulp(L)``, and fixes a lock's force only to ``m ulp(x) /
    h_p^2`` (about 8 N there), so it cannot tell the taut string from the slack one: it read
    "slack" while the load pulled the ends apart, the string's force ``k L`` instead of the
    taut force, until a second impact ``1e-7`` s later (impulse ``1e-7``) put it right
    (issue 29). The balance of accelerations (:func:`~lumped.solvers.nonsmooth.
    lock_forces.forces_from_accelerations`) decides without dividing by ``h_p``.

    Each dashpot whose law fixes its force takes the force at its rate after the impact;
    then every element of ``hits`` whose relative rate is within ``threshold`` of ``0`` (a
    rebound separates clearly and is left to the probe), and every element whose law
    leaves its force free at ``(q, F)`` (``dR/dF = 0``: stuck dashpots, other taut locks),
    holds its relative motion.

    Returns
    -------
    (forces, holding)
        The forces, and the elements of ``hits`` whose balance force is strictly inside
        their lock's set (an element the balance would push out of it is put on its
        boundary, the kink: it goes slack). ``(F, [])`` when no impacted element is at
        rest relative to its ends or the balances have no solution.
    """
    ea, eb = scene.elem_a, scene.elem_b
    held = []
    for e in hits:
        a, b = ea[e], eb[e]
        rate = across(v, a, b)
        if abs(rate) <= threshold:
            held.append(e)
    if not held:
        return list(F), []
    got = forces_with_held(scene, t, x, v, F, held)
    if got is None:
        return list(F), []
    q = scene.elongations(x, v)
    holding = []
    for e in held:
        R, _, RF = scene.elements[e].law.kernel(q[e], got[e])
        # strictly inside: admissible, and its rounding up and down too (not the kink)
        if RF == 0.0 and all(scene.elements[e].law.kernel(q[e], f)[2] == 0.0 for f in
                             (math.nextafter(got[e], -math.inf),
                              math.nextafter(got[e], math.inf))):
            holding.append(e)
    return got, holding
