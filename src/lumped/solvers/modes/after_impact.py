"""The mode right after an impact: impacted locks held or released, and the forces of
the dashpots the impact stopped.

This module owns :func:`hold_impacted_locks`, :func:`release_resting_locks` and
:func:`beside_released`, which
correct the mode choice after an impact (:meth:`lumped.solvers.eventdriven.mode_state.
ModeState.change_mode`) where its vanishing probe step cannot see a lock at rest: they
decide by the balance of accelerations
(:func:`~lumped.solvers.modes.lock_events.after_impact_forces`), without dividing by the
probe's size.
"""

from __future__ import annotations

import itertools
import math
import sys
from collections.abc import Sequence

from ...scene import Scene
from ...scene.network import across
from ..newton.scalar_root import scalar_root
from .force_bounds import onto_rest_edges
from .guards import guard_tolerance
from .lock_events import after_impact_forces
from .mode_guess import try_modes

__all__ = ["beside_released", "held_through", "hold_impacted_locks", "release_resting_locks"]

_EPS = sys.float_info.epsilon


def held_through(scene: Scene, branches: Sequence, modes: Sequence[int],
                 hits: Sequence[tuple[int, float]]) -> list[int]:
    """The elements an impact concerns (:func:`hold_impacted_locks`): the impacted ones
    (``hits``, ``(element, impulse)``), then every spring held on a lock before it (a taut
    string carries its share of the impulse: a mass hung by one on another that reaches its
    own string's length stops both).

    The choice after the impact reads such a string off its lock only by round-off too:
    two masses moving together on a taut string, the one reaching the other string's
    length at ``8.05``, both stopped by the impact, the load of ``221`` on the far mass
    holding both strings taut; the probe (``9e-11`` s) moved the string's ends by ``2e-18``,
    below the rounding of their positions (``1e-16``), and read it slack: the next event
    came ``1.4e-16`` s later, both strings slack, and the run bounced back at ``-6.3``
    where the masses rest (a draw of the tight random-network property, issue 29)."""
    out = [e for e, _ in hits]
    out += [e for e, el in enumerate(scene.elements) if el.kind == "spring" and e not in out
            and branches[e].info[modes[e]].locks]
    return out


def hold_impacted_locks(scene: Scene, branches: Sequence, t: float, hits: Sequence[int],
                        threshold: float, x: Sequence[float], v: Sequence[float],
                        F: Sequence[float], new: list[int], F_p: list[float],
                        rtol: float = 0.0) -> None:
    """Put back on its lock each impacted element that the mode choice after the impact
    read off it only by round-off (``new`` and ``F_p``, the choice's modes and forces, in
    place).

    The choice's probe cannot see a lock at rest: it moves ``q`` by ``h_p^2 a < ulp(L)``
    (:func:`after_impact_forces`). Where it read an element of ``hits`` on a free branch
    with ``q`` still on the lock's value to round-off, the balance of accelerations
    decides: an element whose balance force lies strictly inside its lock's set stays
    locked, with that force (``threshold``: the rate below which an element is at rest
    relative to its ends). When all of them stay, every dashpot takes the balance's force
    too, the probe's being one of the free branch's: a Herschel-Bulkley ``n = 1.5``
    dashpot stopped by a string kept ``tau + (a h_p)^(1/n)``, ``2.3e-7`` above its yield
    force ``tau`` (its rate over the probe, ``1e-10``, beside the slack string), for as
    long as the string held its mass (issue 29). Its branch stays the choice's where that
    branch's guards admit the force (a slip branch at ``F = tau``), else the law reads it
    there.

    First, each yield dashpot between masses and ground that the impact left at rest
    (``|q| <= threshold``) with the choice's force just outside its set at rest (by at
    most ``sqrt(rtol) (1 + |F*|)``, the probe's resolution on a branch flat at its end)
    takes the edge ``F*`` of that set, as a switch at a guard event does
    (:func:`~lumped.solvers.modes.force_bounds.onto_rest_edges`): a Herschel-Bulkley
    ``n = 2`` dashpot beside a stuck Coulomb element, its mass stopped by a string, kept
    the probe's ``tau + 3.9e-9`` for the whole hold (issue 29)."""
    q = scene.elongations(x, v)
    if rtol > 0.0:  # (the impact changed every rate: each dashpot a candidate)
        edges = onto_rest_edges(scene, range(len(F_p)), v, F_p, threshold, rtol)
        for e, edge in enumerate(edges):
            if edge != F_p[e]:
                _take_force(branches[e], q[e], edge, new, F_p, e)
    # (on a lock to the rounding of its ends' positions, or to the run's rtol of them: a
    # string held before the impact moves off its lock by the impacted one's snap, 1.3e-13)
    ends = [abs(x[a]) if a >= 0 else 0.0 for a in scene.elem_a]
    ends = [s + (abs(x[b]) if b >= 0 else 0.0) for s, b in zip(ends, scene.elem_b, strict=True)]
    doubt = [e for e in hits if not branches[e].info[new[e]].locks
             and any(info.locks and info.lock_value is not None
                     and abs(q[e] - info.lock_value) <= max(4.0 * _EPS * max(
                         abs(info.lock_value), abs(q[e]), ends[e]), rtol * ends[e])
                     for info in branches[e].info)]
    if not doubt and not all(branches[e].info[new[e]].locks for e in hits):
        return
    # (the locks the choice kept hold in that balance too: a string the choice read slack
    # beside an impacted one it kept is held with it, as both stopped the masses)
    both = doubt + [e for e in hits if e not in doubt and branches[e].info[new[e]].locks]
    forces, holding = after_impact_forces(scene, t, x, v, F, both, threshold)
    for e in holding:
        new[e] = branches[e].branch(q[e], forces[e])
        F_p[e] = forces[e]
    if len(holding) < len(both):
        return
    for e, el in enumerate(scene.elements):
        f = forces[e]
        # (a dashpot the impact set moving keeps the choice's slip: a junction dragged
        # at -0.78 by a string gone taut was read at rest from the balance's force alone)
        if el.kind != "dashpot" or e in holding or f == F_p[e] or abs(q[e]) > threshold:
            continue
        _take_force(branches[e], q[e], f, new, F_p, e)


def _take_force(lb, q: float, f: float, new: list[int], F_p: list[float], e: int) -> None:
    """Dashpot ``e`` (branches ``lb``) takes the force ``f`` at its rate ``q``: its branch
    stays ``new[e]`` where that branch's guards admit ``f``, else the law reads it."""
    read = lb.branch(q, f)
    if read >= 0 and any(g < -guard_tolerance(q, f) for g in lb.guards_for(new[e])(q, f)):
        new[e] = read
    F_p[e] = f


def release_resting_locks(scene: Scene, branches: Sequence, t: float, old: Sequence[int],
                          threshold: float, x: Sequence[float], v: Sequence[float],
                          F: Sequence[float], new: list[int], F_p: list[float]) -> list[int]:
    r"""Put on its slack branch each spring that the mode choice read onto a position lock
    (``q = L``) it was not held on, at rest relative to its ends, where the balance of
    accelerations does not hold it there (``new`` and ``F_p`` in place).

    At rest on the lock (``|q - L|`` a few ulps, ``|q'| <= threshold``) the choice's probe
    reads the lock's force only to ``m ulp(x) / h_p^2`` (:func:`after_impact_forces`):
    a string that went taut by a plastic impact beside a Herschel-Bulkley ``n = 2``
    dashpot between the same two masses was read taut while the load pulled the ends
    together (the balance wants ``0.14 < k L = 2.9``: it goes slack at once, the dashpot
    slipping from its yield force), and the run alternated between taut and slack with
    steps of ``1e-12`` s until it was bridged (issue 29). The balance (with every element
    whose law leaves its force free: stuck dashpots, other locks) decides without
    dividing by ``h_p``; an element it puts on the lock's boundary (the kink ``F = k L``)
    takes the non-locking branch that holds its law there, with that force.

    Returns
    -------
    list of int
        The elements put on a slack branch (empty: ``new``, ``F_p`` unchanged; also when
        the balances have no solution).
    """
    q = scene.elongations(x, v)
    cand = []
    for e, el in enumerate(scene.elements):
        info = branches[e].info[new[e]]
        L = info.lock_value
        if el.kind != "spring" or new[e] == old[e] or not info.locks or L is None or \
                abs(q[e] - L) > 4.0 * _EPS * max(abs(L), abs(q[e])):
            continue
        a, b = scene.elem_a[e], scene.elem_b[e]
        if abs(across(v, a, b)) <= threshold:
            cand.append(e)
    if not cand:
        return []
    forces, holding = after_impact_forces(scene, t, x, v, F, cand, threshold)
    if forces == list(F):  # (no balance: the probe's choice stands)
        return []
    out = []
    for e in (e for e in cand if e not in holding):
        lb = branches[e]
        for info in lb.info:
            if info.locks:
                continue
            try:
                f = scalar_root(lb.kernel_for(info.index), q[e], forces[e])[0]
            except ValueError:
                continue
            if all(g >= -math.sqrt(_EPS) * (1.0 + abs(f)) for g in
                   lb.guards_for(info.index)(q[e], f)):
                new[e], F_p[e] = info.index, f
                out.append(e)
                break
    return out


def beside_released(scene: Scene, branches: Sequence, t: float, x: list[float],
                    v: list[float], F: list[float], h_p: float, chosen: Sequence[int],
                    new: list[int], released: Sequence[int]) -> tuple | None:
    """The mode after an impact again where :func:`release_resting_locks` released a
    string that the choice had read taut: each element the choice then put on a lock
    besides (``new`` locks it, ``chosen``, the probe's own reading, did not: a dashpot
    at rate 0 whose ends the taut string joined) is read again by a probe of size
    ``h_p`` with the string slack (``new``), its probe's branch first, then its others
    (:func:`~lumped.solvers.modes.mode_guess.try_modes`): ``(modes, v_p, F_p)``, or
    ``None`` when no such element or no probe confirms one.

    A Coulomb element beside a string that went taut by a plastic impact (seed 25039 of
    the tight property) was locked at its yield force ``+tau`` because the string joined
    its ends; the string was then released, and the element stayed stuck where the load
    on it was ``-10.85``: the next probe's forces read ``9e7`` and the run was bridged."""
    added = [e for e in range(len(new)) if e not in released and new[e] != chosen[e]
             and branches[e].info[new[e]].locks]
    if not added:
        return None
    options = [[chosen[e]] + [b for b in range(branches[e].count) if b != chosen[e]]
               for e in added]
    candidates = []
    for combo in itertools.product(*options):
        mode = list(new)
        for e, b in zip(added, combo, strict=True):
            mode[e] = b
        candidates.append(mode)
    return try_modes(scene, branches, candidates, t, x, v, F, h_p)
