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
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...scene import Scene
from ..implicit.initial_slip import known_rate_dashpots, rest_edge, set_valued_at_rest

__all__ = ["onto_joint_bounds", "onto_slip_ends"]


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
    at rest nearest ``F_e`` (see the module notes; a force within that set stays), when
    that moves it by at most ``sqrt(rtol) (1 + |F*|)``: the resolution of a force on a
    branch flat at its end (``q ~ (|F| - tau)^2``) from rates known to ``rtol``. A larger
    move is no probe's artefact (a steep law whose rate is within ``tol`` of 0 but whose
    force is not its yield force) and is left alone. A new list."""
    out = list(F)
    for e in known_rate_dashpots(scene, [e for e in range(len(F)) if new[e] != old[e]]):
        a, b = scene.elem_a[e], scene.elem_b[e]
        if abs((v[b] if b >= 0 else 0.0) - (v[a] if a >= 0 else 0.0)) <= tol:
            kernel = scene.elements[e].law.kernel
            if set_valued_at_rest(kernel):  # (a yield law)
                edge = rest_edge(kernel, F[e])
                if abs(edge - F[e]) <= math.sqrt(rtol) * (1.0 + abs(edge)):
                    out[e] = edge
    return out
