r"""The stage guess of a step that starts where a held branch is flat at its end.

A branch ``R = alpha(q) + beta (s F + d)^p`` with ``p > 1`` (Herschel-Bulkley ``n > 1``
slipping, ``q = gamma (F - tau)^n``) has ``dR/dF = 0`` at its end ``s F + d = 0``. A step
that starts there with the constant guess ``(v_n, F_n)`` at every stage gives Newton a
Jacobian with ``dR/dF = 0`` in that element's rows: its first iteration loads the whole
excess force onto the element (``F = 2.59`` where the root is ``tau + 1.4e-4``), its
second jumps to forces of order ``1/h``, and Newton on a power far from its root gains a
factor ``1/3`` per iteration, short of :data:`~lumped.solvers.radau.stage.MAX_NEWTON` at
every step size down to the floor (issue 29: seed 191 of ``benchmarks/tight_hunt.py``,
29 failed solves at ``t = 0.0893`` and a backward-Euler bridge).

:func:`flat_start` starts such a stage on the branch instead: the velocities by an
explicit predictor, ``V_k,i = v_n,i + c_k h net_i(t_n, F_n) / m_i`` (a junction keeps
``v_n,i``, unless dashpots on rate locks tie it to a mass or ground: it then moves with
them, ``follow``), and the force of each element at its flat end from the branch's inverse
at the predicted rate, ``F_k = G(q_k)`` (:meth:`lumped.codegen.branches.LawBranches.
flat_start_for`; ``tau + (q_k / gamma)^{1/n}``). The guess is kept only when each such
element stays on its held branch (its stage guards ``>= 0`` at every stage): a load that
drives it back off its branch leaves the constant guess. The other elements' guards are
not read: the predictor moves each mass on its own, so a lock between two masses reads a
rate it does not hold (Newton restores it; seed 191: a Coulomb element stuck between two
masses read ``-6e-13``). Read from the law's branch, never from its name.

A junction that stuck dashpots tie to a mass starting from rest, beside a
Herschel-Bulkley ``n = 1.5`` dashpot to ground that slips from rest at its yield force
(row 0 of ``radau5``, its junction at the mass's rate 0, :mod:`lumped.solvers.modes.
junctions_at`): kept at ``v_n = 0``, it gave that dashpot the rate 0 and ``F_k = tau``,
Newton's ``dR/dF = 0`` again, and every step failed down to the floor (issue 29).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from .tableau import C

__all__ = ["AT_END", "FlatEnds", "at_flat_end", "flat_base", "flat_start"]

#: A force is at its branch's flat end when its base ``|s F + d|`` is within this
#: fraction of ``max(|s F|, |d|)`` (a few thousand ulps: the end located to round-off by
#: an event, or a force held there by the mode choice).
AT_END = 1e-12


#: The force at which :func:`flat_base` reads a base's slope: ``s X + d`` rounds to
#: ``s X`` exactly (a power of two: ``s X`` is exact) for any shift ``|d| < 2^147``.
_FAR = 2.0 ** 200


def flat_base(start: Callable | None) -> tuple[float, float] | None:
    """``(s, d)`` of a flat start's base ``s F + d`` (affine in ``F``, no ``q``:
    :func:`~lumped.codegen.stage_forms.flat_inverse`), read off the start itself: ``d`` at
    ``F = 0`` and ``s`` at ``F = 2^200``, both exact; ``None`` for ``None``."""
    if start is None:
        return None
    return start(0.0, _FAR)[0] / _FAR, start(0.0, 0.0)[0]


def at_flat_end(bases: Sequence[tuple[float, float] | None], F_n: Sequence[float]
                ) -> list[int]:
    """The elements whose held branch is flat at its end (``bases[e]``, the
    :func:`flat_base` of the branch's
    :meth:`~lumped.codegen.branches.LawBranches.flat_start_for`, not ``None``) and whose
    force ``F_n[e]`` is at that end: ``|s F + d| <= AT_END max(|s F|, |d|)``. The compiled
    loop (:func:`lumped.solvers.eventdriven.loop_jit.advance`) makes the same test on the
    same numbers (:meth:`FlatEnds.table`) before each step, and leaves such a step to
    this loop."""
    out = []
    for e, sd in enumerate(bases):
        if sd is None:
            continue
        sF = sd[0] * F_n[e]
        if abs(sF + sd[1]) <= AT_END * max(abs(sF), abs(sd[1])):
            out.append(e)
    return out


class FlatEnds:
    """:func:`at_flat_end` of a run's held modes and state, once per state: the held
    branches' flat starts (:attr:`starts`, ``flat_start_for``) and their bases
    (:attr:`bases`, :func:`flat_base`) are read once per modes, the elements at their ends
    once per ``F``, of which they are a function, however often the loop asks at one
    state (the run loop, the step, the stage guess)."""

    def __init__(self, lbs: Sequence) -> None:
        self.lbs = lbs
        self.modes: tuple[int, ...] | None = None
        self.starts: list[Callable | None] = []
        self.bases: list[tuple[float, float] | None] = []
        self._table: np.ndarray | None = None
        self._any = False
        self._state: list[float] | None = None
        self._ends: list[int] = []

    def _read(self, modes: Sequence[int]) -> None:
        key = tuple(modes)
        if key != self.modes:
            self.modes, self._state, self._table = key, None, None
            self.starts = [getattr(lb, "flat_start_for", lambda i: None)(i)
                           for lb, i in zip(self.lbs, key, strict=True)]
            self.bases = [flat_base(start) for start in self.starts]
            self._any = any(self.starts)

    def __call__(self, modes: Sequence[int], F: list[float]) -> list[int]:
        """The elements at their flat ends with the forces ``F`` on ``modes``."""
        self._read(modes)
        if not self._any:
            return []
        if self._state != F:
            self._state = list(F)
            self._ends = at_flat_end(self.bases, F)
        return list(self._ends)

    def table(self, modes: Sequence[int]) -> np.ndarray:
        """:attr:`bases` of ``modes`` as an ``(E, 2)`` array, ``nan`` where a branch has
        no flat end: the compiled loop's copy of :func:`at_flat_end`'s numbers."""
        self._read(modes)
        if self._table is None:
            self._table = np.array([sd if sd is not None else (math.nan, math.nan)
                                    for sd in self.bases], dtype=float).reshape(-1, 2)
        return self._table


def flat_start(system, U: list[float], h: float, x_n: list[float], v_n: list[float],
               F_n: list[float], net_n: Sequence[float], starts: Sequence[Callable | None],
               guards: Sequence[Callable], ends: Sequence[int],
               follow: Sequence[tuple[int, int, float]] = ()) -> bool:
    """Put the on-branch guess (see the module notes) into ``U`` (laid out as the stage
    system's, :class:`~lumped.solvers.radau.stage.StageSystem`) for a step of size ``h``
    from ``(x_n, v_n, F_n)``, ``net_n`` the nodes' net forces at ``t_n``, ``ends`` the
    elements at their flat ends (:func:`at_flat_end`), ``follow`` the junctions that move
    with a node, ``(j, i, L)``: ``V_k,j = V_k,i + L`` (``i = -1``: ground; in order, as
    :func:`lumped.solvers.modes.junctions_at.rate_lock_chains` gives them). Returns
    whether it did; ``U`` is unchanged when the guess takes one of them off its held
    branch (or is not finite)."""
    N, n, m = system.N, system.n, system.m
    trial = list(U)
    for k in range(3):
        for i in range(N):
            if m[i] > 0.0:
                trial[k * n + i] = v_n[i] + C[k] * h * net_n[i] / m[i]
        for j, i, L in follow:  # (a junction on rate locks: its mass's rate)
            trial[k * n + j] = (trial[k * n + i] if i >= 0 else 0.0) + L
    for e in ends:
        q = system.element_nodes(trial, h, x_n, v_n, F_n, e)[0]
        for k in range(3):
            trial[k * n + N + e] = starts[e](q[k + 1], F_n[e])[1]
    for e in ends:  # (the others' guards may read the predictor off their locks)
        q, F = system.element_nodes(trial, h, x_n, v_n, F_n, e)
        for k in range(1, 4):
            if not all(g >= 0.0 for g in guards[e](q[k], F[k])):  # (nan fails too)
                return False
    U[:] = trial
    return True
