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

For a method that locates its events (``radau5``), the stick intervals come from the
events themselves (:func:`event_lock_intervals`): a stick starts at ``t = 0`` or at the
event into a locking branch and ends at the event out of it, at the located times. A
velocity reversal (slip to slip through ``q = 0``) is no stick, although the sample at
its event has ``q = 0`` and a force within the lock's range.
"""

from __future__ import annotations

import numpy as np

from lumped.scene import Scene
from lumped.solvers import Event

from .columns import F_col, elongations

__all__ = ["branch_history", "switch_events", "lock_intervals", "locking_branches",
           "event_lock_intervals"]


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


def event_lock_intervals(events, element: str, locking: frozenset[int], t0: float,
                         t_end: float, initial: int) -> list[tuple[float, float]]:
    """The intervals on which ``element`` is on a branch in ``locking``, from its located
    switching events (``kind == "switch"``, in time order): ``initial`` is its branch at
    ``t0``; a stick runs from ``t0`` or the event into a locking branch to the event out of
    it, or to ``t_end``."""
    out: list[tuple[float, float]] = []
    start = t0 if initial in locking else None
    for ev in sorted((e for e in events if e.element == element and e.kind == "switch"),
                     key=lambda e: e.t):
        if start is None and ev.to_branch in locking:
            start = ev.t
        elif start is not None and ev.to_branch not in locking:
            out.append((start, ev.t))
            start = None
    if start is not None:
        out.append((start, t_end))
    return out
