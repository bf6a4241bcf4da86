r"""The consistent initial state's pieces read from the network at rest, without Newton.

This module owns :func:`initial_rest_forces`, the shortcut of
:func:`lumped.solvers.implicit.initial_state.consistent_initial_state` when every node is a
mass: every force fixed by its law, or the others held by the balance with every mass at
rest (dashpots at rest whose laws have no folds, on a regular incidence matrix), or, for
such a dashpot alone on its mass whose held force its law does not admit (it slips from
rest), the edge of its set at rest nearest that force, the limit system's root as the
settling of :mod:`lumped.solvers.implicit.initial_slip` leaves it; and
:func:`cluster_guesses`, the velocity guesses of its last restarts, with every cluster of
junctions moving as one with a dashpot neighbour outside it.
"""

from __future__ import annotations

import itertools
import math

from ...scene import Junction, Scene
from ..nonsmooth.groups import connected_groups, dashpot_links
from ..nonsmooth.rest_balance import rest_forces, rest_inverse
from .branch_check import known_monotone
from .initial_slip import rest_edge

__all__ = ["cluster_guesses", "initial_rest_forces"]


#: At most this many cluster guesses (:func:`cluster_guesses`) per initial state.
_MAX_CLUSTER_GUESSES = 64


def cluster_guesses(scene: Scene, v0: list[float]) -> list[list[float]]:
    """Velocity guesses (``N`` entries) with every cluster of junctions (joined to each
    other by dashpots) moving as one with one of its dashpot neighbours outside it (a
    mass's ``v0``, or ground's rest), each combination of the clusters' choices (at most
    :data:`_MAX_CLUSTER_GUESSES`). A chain of stuck elements from a moving mass (mass,
    Coulomb, junction, Herschel-Bulkley, junction) moves so; the guesses of
    :func:`lumped.solvers.implicit.globalize.stuck_guesses` move each junction with its own
    neighbour only, as it was, and swept one junction at a time such a chain stays at
    rest (each junction's balance holds on its own with the next element slipping)."""
    N = len(scene.nodes)
    junction = [isinstance(nd, Junction) for nd in scene.nodes]
    links = dashpot_links(scene)
    clusters = connected_groups([i for i in range(N) if junction[i]], links)
    members, anchors = [], []
    for group in clusters:
        outside = []
        for a, b in links:
            for end, other in ((a, b), (b, a)):
                if end in group and (other < 0 or not junction[other]):
                    vel = 0.0 if other < 0 else v0[other]
                    if vel not in outside:
                        outside.append(vel)
        if outside:
            members.append(group)
            anchors.append(outside)
    out = []
    for choice in itertools.islice(itertools.product(*anchors), _MAX_CLUSTER_GUESSES):
        w = list(v0[:N])
        for group, vel in zip(members, choice, strict=True):
            for i in group:
                w[i] = vel
        out.append(w)
    return out


_MONOTONE: dict[int, tuple[object, bool]] = {}


def _monotone(bound) -> bool:
    """:func:`lumped.solvers.implicit.branch_check.known_monotone`, kept per law object
    (``bound.law``, which it reads alone: the same for every value of the numbers)."""
    law = getattr(bound, "law", None)
    if law is None:
        return known_monotone(bound)
    got = _MONOTONE.get(id(law))
    if got is None or got[0] is not law:
        if len(_MONOTONE) > 256:
            _MONOTONE.clear()
        got = _MONOTONE[id(law)] = (law, known_monotone(bound))
    return got[1]


def initial_rest_forces(scene: Scene, pinned: list[float | None], q0: list[float],
                        f: list[float], eps: float | None = None) -> list[float] | None:
    """The forces of the limit system when it needs no Newton (every node a mass), or
    ``None``: every force fixed by its law (the accelerations, which the result does not
    hold, are then the only unknowns), or the others held by the balance with every mass
    at rest, one per node on a regular incidence matrix
    (:func:`lumped.solvers.nonsmooth.rest_balance.rest_forces`, the held interval's formula), each
    admitted by its law at its ``q0`` exactly (``R(q0, F) = 0``: with the accelerations
    zero the limit system holds, its mass rows to round-off).

    The forces so held are those of dashpots at rest (``q0 = 0``: their rows
    ``R(eps (a_b - a_a), F) = 0`` then fix the accelerations) whose laws have no folds
    (:func:`lumped.solvers.implicit.branch_check.known_monotone`): the limit system has one
    solution, which Newton finds too. A force the law leaves free at ``q0 != 0`` (a taut
    string, whose row sees ``q0 + eps^2 a``, which rounds to ``q0``) leaves the
    accelerations to Newton's minimum-norm rule: not taken here.

    With the limit step ``eps`` given, a dashpot whose held force its law does not admit
    at rest (it slips from rest: ``k x0 > tau``) takes the edge of its set at rest nearest
    that force, when it alone moves its mass (:func:`_slip_edges`); without ``eps``, or
    where that does not hold, ``None``."""
    free = tuple(e for e, Fp in enumerate(pinned) if Fp is None)
    F = [0.0 if Fp is None else Fp for Fp in pinned]
    if not free:
        return F
    elements = scene.elements
    for e in free:
        if not (elements[e].kind == "dashpot" and q0[e] == 0.0 and _monotone(elements[e].law)):
            return None
    got = rest_inverse(len(scene.nodes), tuple(zip(scene.elem_a, scene.elem_b, strict=True)),
                       free)
    if got is None:
        return None
    F, _ = rest_forces(*got, free, f, F)
    slipping = []
    for e in free:
        if not math.isfinite(F[e]):
            return None
        if elements[e].law.kernel(q0[e], F[e])[0] != 0.0:
            slipping.append(e)
    if slipping and (eps is None or not _slip_edges(scene, got[1], free, slipping, f, F, eps)):
        return None
    return F


def _slip_edges(scene: Scene, K: list[list[float]], free: tuple[int, ...],
                slipping: list[int], f: list[float], F: list[float], eps: float) -> bool:
    r"""Move the force of each dashpot in ``slipping`` (at rest, ``q0 = 0``, a known
    monotone law; its held force ``F*`` in ``F``, which its law does not admit at rest)
    to the edge of its set at rest ``{F : R(0, F) = 0}`` nearest ``F*``, in place; or
    ``False`` (``F`` partly moved) where that is not the limit system's solution.

    Taken when the dashpot joins a mass ``i`` to ground (on no support), ``i`` has no
    other free element, and the set at rest holds 0. Then the limit system decouples:
    the dashpot's row ``R(eps d, F) = 0``, ``d = +-a_i`` its rate's change, with
    ``m_i a_i`` the mass's net force (the other forces fixed), affine in ``F`` and 0 at
    ``F*``. A monotone law has one root ``F_r``, on the segment from the edge ``F_e`` to
    ``F*`` (checked: the row at the edge, ``R(eps d(F_e), F_e)``, has the other sign
    than ``R(0, F*)``, or is 0: a root at the edge itself, as Coulomb's ``F + r eps d``
    rounds to ``tau``; ``eps d`` not 0), which
    :func:`lumped.solvers.implicit.initial_slip.settle_on_rest_set` moves to ``F_e``
    (:func:`lumped.solvers.implicit.initial_slip.rest_edge`: the edge on the segment from
    0 to ``F_r``, the same float for every point beyond it). So the result is the one
    the limit system's root leads to, bit for bit, without Newton. (Newton itself may
    stop short of that root, inside the set, where its residual test passes: a few ulps
    inside, or anywhere in it when ``eps d`` is below its ``atol``.)"""
    ea, eb, nodes = scene.elem_a, scene.elem_b, scene.nodes
    if any(end.element in slipping for end in scene.support_ends):
        return False  # (a dashpot on a support: its rate has an offset)
    count = [0] * len(nodes)
    for e in free:
        for i in (ea[e], eb[e]):
            if i >= 0:
                count[i] += 1
    for e in slipping:
        i = eb[e] if ea[e] < 0 else ea[e]
        if (ea[e] >= 0 and eb[e] >= 0) or count[i] != 1:
            return False
        kernel = scene.elements[e].law.kernel
        if kernel(0.0, 0.0)[0] != 0.0:
            return False
        R_star, _, RF_star = kernel(0.0, F[e])
        edge = _rest_edge_near(kernel, F[e], R_star, RF_star)
        if edge == F[e]:
            return False
        F[e] = edge
        net = f[i]
        for e2, k in enumerate(K[i]):
            if k != 0.0:
                net += k * F[e2]
        d = eps * (net / nodes[i].m)
        R_edge = kernel(d if eb[e] == i else -d, edge)[0]
        if d == 0.0 or not math.isfinite(R_edge) or (
                R_edge != 0.0 and (R_edge > 0.0) == (R_star > 0.0)):
            return False
    return True


def _rest_edge_near(kernel, F: float, R: float, RF: float, walk: int = 8) -> float:
    """:func:`lumped.solvers.implicit.initial_slip.rest_edge` ``(kernel, F)`` for a law
    whose set at rest is an interval holding 0 (``R = R(0, F) != 0``, ``RF`` its
    ``dR/dF``): from the Newton guess ``F - R / RF`` (the edge itself, to round-off, for
    a law linear in ``F`` beyond it: Bingham, Coulomb), at most ``walk`` ulps to the float
    in the set next to one outside it, which is the bisection's float (the only such pair
    on the segment from 0 to ``F``); else the bisection itself."""
    if RF != 0.0 and math.isfinite(RF):
        g = F - R / RF
        if math.isfinite(g) and abs(g) < abs(F) and (g == 0.0 or (g > 0.0) == (F > 0.0)):
            if kernel(0.0, g)[0] == 0.0:
                for _ in range(walk):  # inside: out toward F
                    n = math.nextafter(g, F)
                    if kernel(0.0, n)[0] != 0.0:
                        return g
                    g = n
            else:
                for _ in range(walk):  # outside: in toward 0
                    if g == 0.0:
                        break
                    g = math.nextafter(g, 0.0)
                    if kernel(0.0, g)[0] == 0.0:
                        return g
    return rest_edge(kernel, F)
