"""Connected groups of nodes: a union-find over index pairs.

Used where a solver moves or holds several nodes as one: the junction clusters of the
initial state's last restarts (:mod:`lumped.solvers.implicit.initial_rest`) and the stuck
clusters of the balance sweeps (:mod:`lumped.solvers.implicit.balance_sweeps`).
"""

from __future__ import annotations

from collections.abc import Iterable

from ...scene import Scene

__all__ = ["connected_groups", "dashpot_links"]


def connected_groups(nodes: Iterable[int],
                     pairs: Iterable[tuple[int, int]]) -> list[list[int]]:
    """The groups of ``nodes`` joined by ``pairs`` (each group in the order of ``nodes``,
    the groups in the order of their first member); a pair with an end outside ``nodes``
    joins nothing.

    Examples
    --------
    >>> connected_groups([0, 1, 2, 3], [(0, 2), (2, 3), (1, -1)])
    [[0, 2, 3], [1]]
    """
    parent = {i: i for i in nodes}

    def find(i: int) -> int:
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for a, b in pairs:
        if a in parent and b in parent:
            parent[find(a)] = find(b)
    groups: dict[int, list[int]] = {}
    for i in parent:
        groups.setdefault(find(i), []).append(i)
    return list(groups.values())


def dashpot_links(scene: Scene) -> list[tuple[int, int]]:
    """The ends ``(a, b)`` of every dashpot of ``scene`` (node indices, ``-1`` for
    ground), in the elements' order: the pairs whose rate ``v_b - v_a`` a stuck dashpot
    holds at zero, which the balance sweeps and the initial state's cluster guesses move
    as one."""
    return [(scene.elem_a[e], scene.elem_b[e]) for e, el in enumerate(scene.elements)
            if el.kind == "dashpot"]
