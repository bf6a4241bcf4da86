r"""Which branch of its law every element is on, sample by sample.

A law with kinks (``Abs``, ``Max``, ``Piecewise``, ...) has smooth branches
(:func:`lumped.codegen.branches.law_branches`); a Bingham dashpot, for instance, has a
*sticking* branch on which its residual fixes the rate ``q = 0`` and leaves the force
free (``BranchInfo.locks``), and two slipping branches.

For a method that does not locate events (the fixed-step methods), the branch of each
element is evaluated at every sample ``(q_e(t_n), F_e(t_n))`` by the same rules as the
kernel, and

* a **switching event** is recorded at the first sample ``t_n`` on which the new
  branch is active (the true switch lies in ``(t_{n-1}, t_n]``: the event time is
  late by less than one step);
* a **stick interval** of a dashpot is a maximal run of consecutive samples on a rate
  lock, reported as ``(t_first, t_last)`` of the run (a run of a single sample gives an
  interval of length zero: the discrete motion stopped at that sample only).
"""

from __future__ import annotations

import numpy as np

from lumped.scene import Scene
from lumped.solvers import Event

from .columns import F_col, elongations

__all__ = ["branch_history", "switch_events", "lock_intervals", "locking_branches"]


def _branches(law):
    from lumped.codegen.branches import law_branches

    return law_branches(law)


def branch_history(scene: Scene, data: np.ndarray) -> dict[str, np.ndarray]:
    """Element name -> integer array of its active branch at every sample."""
    out: dict[str, np.ndarray] = {}
    for e, el in enumerate(scene.elements):
        lb = _branches(el.law)
        if lb.count == 1:
            out[el.name] = np.zeros(len(data), dtype=int)
            continue
        q = elongations(scene, data, e).tolist()
        F = data[:, F_col(scene, e)].tolist()
        branch = lb.branch
        out[el.name] = np.fromiter((branch(qk, Fk) for qk, Fk in zip(q, F, strict=True)),
                                   dtype=int, count=len(q))
    return out


def locking_branches(scene: Scene, element: str) -> frozenset[int]:
    """Indices of the branches of ``element``'s law that lock its ``q`` (``info.locks``)."""
    lb = _branches(scene.elements[scene.element_index[element]].law)
    return frozenset(i for i in range(lb.count) if lb.info[i].locks)


def switch_events(t: np.ndarray, history: dict[str, np.ndarray]) -> list[Event]:
    """The branch switches in ``history`` as :class:`~lumped.solvers.Event` s of kind
    ``"switch"``, at the first sample on the new branch, sorted by time (ties in element
    order)."""
    found: list[tuple[int, int, Event]] = []
    for order, (name, idx) in enumerate(history.items()):
        for n in np.flatnonzero(idx[1:] != idx[:-1]) + 1:
            found.append((int(n), order, Event(float(t[n]), name, "switch",
                                               int(idx[n - 1]), int(idx[n]))))
    found.sort(key=lambda item: (item[0], item[1]))
    return [ev for _, _, ev in found]


def lock_intervals(t: np.ndarray, idx: np.ndarray,
                   locking: frozenset[int]) -> list[tuple[float, float]]:
    """Maximal runs of samples whose branch is in ``locking``, as ``(t_first, t_last)``."""
    on = np.isin(idx, list(locking)) if locking else np.zeros(len(idx), dtype=bool)
    edges = np.diff(np.concatenate(([0], on.astype(np.int8), [0])))
    starts = np.flatnonzero(edges == 1)
    ends = np.flatnonzero(edges == -1) - 1
    return [(float(t[a]), float(t[b])) for a, b in zip(starts, ends, strict=True)]
