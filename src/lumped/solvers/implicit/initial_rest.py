r"""The consistent initial state's pieces read from the network at rest, without Newton.

This module owns :func:`initial_rest_forces`, the shortcut of
:func:`lumped.solvers.implicit.initial_state.consistent_initial_state` when every node is a
mass: every force fixed by its law, or the others held by the balance with every mass at
rest (dashpots at rest whose laws have no folds, on a regular incidence matrix); and
:func:`cluster_guesses`, the velocity guesses of its last restarts, with every cluster of
junctions moving as one with a dashpot neighbour outside it.
"""

from __future__ import annotations

import itertools
import math

from ...scene import Junction, Scene
from ..nonsmooth.groups import connected_groups
from ..nonsmooth.rest_balance import rest_forces, rest_inverse
from .branch_check import known_monotone

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
    links = [(scene.elem_a[e], scene.elem_b[e]) for e, el in enumerate(scene.elements)
             if el.kind == "dashpot"]
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
    """:func:`lumped.solvers.implicit.branch_check.known_monotone`, kept per bound law object."""
    got = _MONOTONE.get(id(bound))
    if got is None or got[0] is not bound:
        if len(_MONOTONE) > 256:
            _MONOTONE.clear()
        got = _MONOTONE[id(bound)] = (bound, known_monotone(bound))
    return got[1]


def initial_rest_forces(scene: Scene, pinned: list[float | None], q0: list[float],
                 f: list[float]) -> list[float] | None:
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
    accelerations to Newton's minimum-norm rule: not taken here."""
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
    for e in free:
        if not (math.isfinite(F[e]) and elements[e].law.kernel(q0[e], F[e])[0] == 0.0):
            return None
    return F
