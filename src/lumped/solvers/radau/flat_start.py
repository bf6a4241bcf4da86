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

from collections.abc import Callable, Sequence

from .tableau import C

__all__ = ["AT_END", "FlatEnds", "at_flat_end", "flat_start"]

#: A force is at its branch's flat end when its base ``|s F + d|`` is within this
#: fraction of ``max(|s F|, |d|)`` (a few thousand ulps: the end located to round-off by
#: an event, or a force held there by the mode choice).
AT_END = 1e-12


def at_flat_end(starts: Sequence[Callable | None], q_n: Sequence[float],
                F_n: Sequence[float]) -> list[int]:
    """The elements whose held branch is flat at its end (``starts[e]``, the branch's
    :meth:`~lumped.codegen.branches.LawBranches.flat_start_for`, not ``None``) and whose
    force ``F_n[e]`` is at that end."""
    out = []
    for e, start in enumerate(starts):
        if start is None:
            continue
        base = start(q_n[e], F_n[e])[0]
        b0 = start(q_n[e], 0.0)[0]  # d, the base at F = 0
        if abs(base) <= AT_END * max(abs(base - b0), abs(b0)):
            out.append(e)
    return out


class FlatEnds:
    """:func:`at_flat_end` of a run's held modes and state, once per state: the held
    branches' flat starts (:attr:`starts`, ``flat_start_for``) are read once per modes,
    the elements at their ends once per ``(x, v, F)``, of which they are a function (no
    moving supports: ``q`` is ``x`` and ``v``'s), however often the loop asks at one
    state (the run loop, the step, the stage guess)."""

    def __init__(self, lbs: Sequence) -> None:
        self.lbs = lbs
        self.modes: tuple[int, ...] | None = None
        self.starts: list[Callable | None] = []
        self._any = False
        self._state: list[list[float]] | None = None
        self._ends: list[int] = []

    def __call__(self, scene, modes: Sequence[int], x: list[float], v: list[float],
                 F: list[float]) -> list[int]:
        """The elements at their flat ends in the state ``(x, v, F)`` of ``scene``."""
        key = tuple(modes)
        if key != self.modes:
            self.modes, self._state = key, None
            self.starts = [getattr(lb, "flat_start_for", lambda i: None)(i)
                           for lb, i in zip(self.lbs, key, strict=True)]
            self._any = any(self.starts)
        if not self._any:
            return []
        if self._state != [x, v, F]:
            self._state = [list(x), list(v), list(F)]
            self._ends = at_flat_end(self.starts, scene.elongations(x, v), F)
        return list(self._ends)


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
