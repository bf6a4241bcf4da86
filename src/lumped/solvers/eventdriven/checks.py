r"""What the ``radau5`` driver reads off a solved step before it accepts it.

:class:`StepChecks` is a part of :class:`lumped.solvers.eventdriven.run.Radau5Run` (a mixin:
it reads the run's state, ``x``, ``v``, ``F`` at the step's start ``t``, the held mode and
the stage system): the forces the step's polynomials start from after an event, the first
guard crossing along the step, the dense output's defect against the held laws, a kink of
the force split among locks in parallel, and a guard's value at the step's end. None of
them changes the run's state.

Each reads the laws' arguments at the nodes of the step's polynomial
(:meth:`~lumped.solvers.radau.stage.StageSystem.element_nodes`, which add a support's
offset at each node's time), so each sets the support clock bare first
(:meth:`StepChecks.bare`): the guards and kernels are then
the laws' own.
"""

from __future__ import annotations

import math

from ..modes.crossing_root import first_root_py
from ..modes.guards import guard_tolerance
from ..modes.split_kink import split_kink
from ..radau.dense_defect import dense_defect
from ..radau.tableau import START_WEIGHTS

__all__ = ["StepChecks"]


def _admitted(guard, q0: float, F0: float, q1: float, F1: float) -> float:
    """``F0`` if ``guard(q0, F0)`` holds (every value ``>= 0``), else the force on the
    segment from ``(q0, F0)`` to ``(q1, F1)`` nearest ``F0`` that it admits (bisection;
    ``F0`` when ``(q1, F1)`` is not admitted either)."""
    if min(guard(q0, F0), default=0.0) >= 0.0 or not min(guard(q1, F1), default=0.0) >= 0.0:
        return F0
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if min(guard(q0 + mid * (q1 - q0), F0 + mid * (F1 - F0))) >= 0.0:
            hi = mid
        else:
            lo = mid
    return F0 + hi * (F1 - F0)


def _skipping(guard, skip: tuple[int, ...]):
    """``guard`` with its guards ``skip`` read as held (``+inf``): a tangency at ``t``
    that the full laws kept (see :meth:`StepChecks.crossing`)."""
    def held(q: float, F: float) -> list[float]:
        return [math.inf if j in skip else g for j, g in enumerate(guard(q, F))]
    return held


class StepChecks:
    """The checks of a solved step ``U`` (the stage values, ``3 (N + E)``) of size ``h``
    from the run's state at ``t`` (see the module notes).

    Reads, from the run: ``x, v, F`` (the state at ``t``), ``N, E, n`` (nodes, elements,
    ``N + E``), ``system`` (the :class:`~lumped.solvers.radau.stage.StageSystem`), ``ms`` (the
    :class:`~lumped.solvers.eventdriven.mode_state.ModeState`) and its lists ``modes``,
    ``kernels``, ``guards``, ``watched``, ``cones``, the plan's branches ``lbs``, the
    scene's ``spring`` and ``massless`` flags, ``tangent``, ``rtol``, ``atol`` and
    ``F_seen``.
    """

    def bare(self) -> None:
        """The support offsets set to 0 (a run with moving supports: its ``frame``), for
        law arguments that hold them already (the nodes of a step's polynomial,
        :meth:`~lumped.solvers.radau.stage.StageSystem.element_nodes`)."""
        frame = getattr(self, "frame", None)
        if frame is not None:
            frame.bare()

    def lock_group(self) -> int:
        """The group of the held mode's locks that the dense output records with a step
        (:meth:`~lumped.solvers.radau.dense.DenseOutput.group`)."""
        return self.dense.group(self.lbs, self.modes, self.cones)

    def start_forces(self, U: list[float]) -> list[float]:
        """The forces at ``t`` the step's polynomial starts from: after an event the
        stage forces' quadratic at ``s = 0`` rather than the probe's forces, whose
        round-off (magnified by ``m / h_probe``) would put a false guard crossing into
        the first step (a dashpot breaking out tangentially chattered: issue 11)."""
        if not self.ms.forces_from_probe:
            return self.F
        n, N = self.n, self.N
        return [sum(w * U[k * n + N + e] for k, w in enumerate(START_WEIGHTS))
                for e in range(self.E)]

    def dense_start_forces(self, U: list[float], h: float) -> list[float]:
        """The forces at ``t`` the dense output's polynomials start from, after an event
        (and at the start when locks act in parallel: the initial state's split of their
        load is not the stage solve's, ``F_0 = -0.077`` against ``-0.1`` held in issue 29).

        The probe's force, the right limit at ``t`` to ``O(h_probe)``, for an element
        that is not locked, or locked between junctions and ground only (its force is
        then set by a junction's balance, an algebraic relation the probe holds). A lock
        that a mass enters, a position lock (a taut string) and locks in parallel
        (``cones``) start from the stage forces' quadratic at ``s = 0``: the probe fixes
        the force of a lock on a mass only to ``m / h_probe`` times the velocity it
        snapped (0.7 for ``4e-9``), a position lock's to ``m ulp(x) / h_probe^2``, and the
        split of locks in parallel is the stage solve's (the quadratic is exact for a
        load shared by locks). The quadratic is off by ``O(h^3)`` times the force's third
        derivative where the step after the event is long and the force curved: a
        junction's dashpot just broken out and relaxing faster than the step (20 % of the
        force at the first output point), a Coulomb element just stuck at a junction (its
        force read beyond its yield force)."""
        F = self.F
        if not self.ms.forces_from_probe:
            return F
        F_q = self.start_forces(U)
        self.bare()
        cones, lbs, modes, massless = self.cones, self.lbs, self.modes, self.massless
        out = []
        for e in range(self.E):
            if not (e in cones or (lbs[e].info[modes[e]].locks and not massless[e])):
                out.append(F[e])
                continue
            # a lock admits the force at the event: a quadratic start beyond its guards
            # (a Coulomb element just stuck beside a string gone taut, 2e-4 tau above it)
            # is moved back along the way to the first stage, which the guards admit
            q, Fe = self.system.element_nodes(U, h, self.x, self.v, F_q, e)
            out.append(_admitted(self.guards[e], q[0], Fe[0], q[1], Fe[1]))
        return out

    def takes_first(self) -> bool:
        """Whether the compiled loop may take the next step: no event since the last
        step, or one whose first step it checks
        (:mod:`lumped.solvers.eventdriven.first_step_jit`: no impact at its start, no locks in
        parallel, its check compiled). Sets ``held``: per element, 1 where the dense
        output starts from the stage forces (:meth:`dense_start_forces`), or ``None``."""
        self.held = None
        if not self.ms.forces_from_probe:
            return True
        if self.ms.after_impact or self.cones or not self.fast.first_step_ready():
            return False
        lbs, modes, massless = self.lbs, self.modes, self.massless
        self.held = [int(bool(lbs[e].info[modes[e]].locks) and not massless[e])
                     for e in range(self.E)]
        return True

    def crossing(self, U: list[float], h: float):
        """The first guard crossing of a watched element along the step,
        ``(s, (which, guard))`` with ``s`` the fraction of the step, or ``None``; the
        guards read crossed at ``t`` by a tangency the full laws kept (``tangent``) are
        read as held."""
        watched, tangent, guards = self.watched, self.tangent, self.guards
        if not watched:
            return None
        self.bare()
        system, x, v = self.system, self.x, self.v
        fns = [guards[e] for e in watched]
        if tangent:
            fns = [_skipping(fn, tuple(j for w2, j in tangent if w2 == w))
                   if any(w2 == w for w2, _ in tangent) else fn for w, fn in enumerate(fns)]
        hit = first_root_py([system.element_nodes(U, h, x, v, self.F, e) for e in watched],
                            fns)
        if hit is None or not self.ms.forces_from_probe or hit[0] == 0.0:
            return hit  # (a guard already off at t: an event at t itself, as before)
        F_0 = self.start_forces(U)  # a crossing inside the step: tested without the offset
        again = first_root_py([system.element_nodes(U, h, x, v, F_0, e) for e in watched],
                              fns)
        # ... but not moved to t itself by the quadratic's own error at s = 0 (a guard at
        # exactly 0 at the event, a tangential break-out, read off at t: issue 29)
        return hit if again is not None and again[0] == 0.0 else again

    def defect(self, U: list[float], h: float) -> float:
        """The largest scaled defect of the step's dense output against the held laws
        (:func:`lumped.solvers.radau.dense_defect.dense_defect`)."""
        n, N, x, v = self.n, self.N, self.x, self.v
        F0 = self.dense_start_forces(U, h)
        self.bare()
        v_scale = max([abs(vi) for vi in v] + [abs(U[2 * n + i]) for i in range(N)])
        x_scale = max(abs(xi) for xi in x) + h * v_scale
        return dense_defect([self.system.element_nodes(U, h, x, v, F0, e)
                             for e in range(self.E)], self.kernels, self.spring, self.rtol,
                            self.atol, v_scale, x_scale, self.F_seen)[0]

    def kink(self, U: list[float], h: float) -> float | None:
        """Where a step whose force split among locks in parallel kinks should end
        (:func:`lumped.solvers.modes.split_kink.split_kink`), or None."""
        system, cones = self.system, self.cones
        free = system.free_split
        if free is None or not cones:
            return None
        x, v = self.x, self.v
        F0 = self.dense_start_forces(U, h)  # (where the dense output starts, after an event)
        nodes = {e: (system.element_nodes(U, h, x, v, F0, e)[1],
                     system.element_nodes(free, h, x, v, F0, e)[1]) for e in cones}
        scale = max(max(abs(Fe) for Fe in F0), max(abs(f) for e in cones for f in nodes[e][0]))
        return split_kink(nodes, cones, 0.5 * self.rtol * scale)

    def beyond_tangent(self, U: list[float], h: float) -> bool:
        """Whether a guard read as held (``tangent``) is off at a stage by more than the
        run's tolerance: not a tangency's round-off, another root of the held branch."""
        return any(self._off_beyond(U, h, which) for which in self.tangent)

    def held_on_lock(self, U: list[float], h: float, which) -> bool:
        """Whether guard ``which = (watched index, guard index)``, read crossed along the
        step, holds at every stage at the rate its element's lock fixes: the element is
        on a locking branch with a known value ``L`` and ``g(L, F_k) >= -guard_tolerance``
        at the stages. On the lock the rate is ``L``; a crossing the stages' rates alone
        make is their round-off (a stuck Coulomb element's guard ``tau - |F + r q|`` at a
        junction's rate of ``1e-15``), not an event."""
        e, j = self.watched[which[0]], which[1]
        info = self.lbs[e].info[self.modes[e]]
        if not info.locks or info.lock_value is None:
            return False
        L = float(info.lock_value)
        self.bare()
        Fe = self.system.element_nodes(U, h, self.x, self.v, self.F, e)[1]
        return all(self.guards[e](L, Fe[k])[j] >= -guard_tolerance(L, Fe[k]) for k in (1, 2, 3))

    def _off_beyond(self, U: list[float], h: float, which) -> bool:
        """Whether guard ``which`` is off at a stage of the step by more than the run's
        tolerance, ``g < -(atol + rtol (|q| + |F|))``."""
        e, j = self.watched[which[0]], which[1]
        self.bare()
        q, Fe = self.system.element_nodes(U, h, self.x, self.v, self.F, e)
        return any(self.guards[e](q[k], Fe[k])[j] < -(self.atol + self.rtol * (
            abs(q[k]) + abs(Fe[k]))) for k in (1, 2, 3))

    def end_guard(self, U: list[float], h: float, which) -> tuple[float, float]:
        """Guard ``which = (watched index, guard index)`` at the step's end, and its
        tolerance."""
        e = self.watched[which[0]]
        self.bare()
        q, Fe = self.system.element_nodes(U, h, self.x, self.v, self.F, e)
        return self.guards[e](q[3], Fe[3])[which[1]], guard_tolerance(q[3], Fe[3])
