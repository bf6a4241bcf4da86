r"""One pass of the ``radau5`` Python loop: a step solved, checked, and accepted or redone.

:class:`StepPass` is a part of :class:`lumped.solvers.eventdriven.run.Radau5Run` (a mixin
on the run's state): :meth:`StepPass._step` sizes the step (to the next breakpoint of the
forcing, above the step floor), solves its stages (compiled when the scene's loop is, in
Python otherwise, with a longer budget for a landing step and a line-search fallback after
eight failures in a row), and reads the error estimate, a kink of the force split, the
guards along the step (:meth:`StepPass._redo_for_a_guard`: land on the first crossing),
the dense output's defect after an event and the laws' folds. A step that passes them all
is accepted (:meth:`StepPass._accept`: the dense output, the creep test, Gustafsson's
controller, the event it landed on); a failed stage solve is :meth:`StepPass._failed`.
"""

from __future__ import annotations

import math

from ..modes.guards import fold_crossed
from ..modes.junctions_at import rate_lock_chains
from ..radau.flat_start import FlatEnds, flat_start
from ..radau.rows import row_of
from ..radau.stage import DAMPED_AFTER, MAX_NEWTON, STALL_PASSES
from ..radau.tableau import A as _A
from ..radau.tableau import C
from ..status import Status
from .creep import CREEP_STEPS, creep_floor, creep_stop
from .landing import Landing
from .setup import step_floor

__all__ = ["NOT_SOUGHT", "StepPass"]

_EPS = 2.220446049250313e-16
#: Cuts of one step at kinks of the force split (:mod:`~lumped.solvers.modes.split_kink`).
_KINK_CUTS = 8
#: A compiled attempt's crossing when its root was not sought (its compiled root finder,
#: :func:`lumped.solvers.eventdriven.attempt_root_jit.attempt_root`, is not compiled yet): the
#: Python test runs, the same algorithm.
NOT_SOUGHT = "not sought"


class StepPass:
    """The Python loop's pass over one step (see the module notes).

    Reads and updates the run's state (:class:`~lumped.solvers.eventdriven.run.Radau5Run`):
    ``t, x, v, F``, the step size ``h`` and the controller's ``h_acc``, ``err_acc``,
    ``h_good``, ``h_big``, the landing bracket ``target``, the flags ``kept``,
    ``floor_tried``, ``tangent``, the counters ``stalled``, ``creeping``, ``kink_cuts``
    and ``stats``, and ``status``/``message`` on a stop; its output ``dense`` and ``rows``.
    """

    _flat: FlatEnds | None = None

    def _step(self) -> None:
        """One pass of the Python loop: a step from ``t`` solved, checked and accepted,
        or the step size (the mode, the landing bracket) changed for the next pass."""
        stats, t = self.stats, self.t
        self.stalled += 1
        if self.stalled > STALL_PASSES:
            self.status, self.message = Status.STEP_TOO_SMALL, (
                f"radau5 stopped at t = {t!r}: {STALL_PASSES} attempts without an accepted "
                f"step (step size {self.h!r})")
            return
        if self.stop(self.budget.check(t, stats)):  # (also after the compiled loop's return)
            return
        t_stop = self.t_stop()
        room = t_stop - t
        to_stop = False
        if t + 1.0001 * self.h >= t_stop or self.h >= room:
            self.h = room
            to_stop = True
        h_min = step_floor(t, self.t_final)
        if self.h < h_min and self.target is None and self.watched and not self.floor_tried:
            # the held branches end here (e.g. a law whose slip branch has no
            # continuation at zero rate, where Newton fails on every step): let the full
            # laws choose
            self.floor_tried = True
            self.h_acc = None
            changed = self.choose_again(self.h_good)
            if changed is None:
                return
            if changed:
                self.h = self.h_good
                return
        if self.h < h_min and self.target is None:
            self.status, self.message = Status.STEP_TOO_SMALL, (
                f"radau5: step size {self.h!r} below its floor {h_min!r} at t = {t!r}")
            return
        h = self.h
        # this attempt compiled (the same numbers), unless a Jacobian is singular
        # (a step from a flat end is Python's in both loops: its guess, .flat_start)
        got = None if self.fast is None or self.flat_ends() else self.fast.attempt(
            t, h, self.x, self.v, self.F, self.dF_n, self.F_seen,
            self.breaks[self.bi - 1] if self.bi > 0 else math.nan, self.modes, self.watched,
            self.ms.after_impact)
        hit_c = None
        if got is not None:
            sol, its, nfac, err_norm, self.F_seen, hit_c = got
        else:
            sol, its, nfac = self.attempt(h, MAX_NEWTON)
        if sol is None and self.target is not None:
            # a landing step near the singular end of a branch (a junction's
            # Herschel-Bulkley n < 1 dashpot stopping in finite time, its rate ~ sqrt(t* -
            # t)): Newton contracts slowly there and 10 iterations missed steps that 60
            # take; the bracket closed early, 1e-5 s before the stop, again and again
            # down to the step floor. Once more, with a longer budget
            sol, its_more, nfac_more = self.attempt(h, 6 * MAX_NEWTON)
            its, nfac, got = its + its_more, nfac + nfac_more, None
        elif sol is None and not self.cones and self.stalled >= DAMPED_AFTER:
            # an eighth failure in a row: a stage that starts where its branch's rate is
            # flat in the force (Herschel-Bulkley n > 1 at its yield force), which the
            # simplified Newton misses at every step size; the line-search fallback
            sol, its_more, nfac_more = self.attempt(h, MAX_NEWTON, damped=True)
            its, nfac, got = its + its_more, nfac + nfac_more, None
        stats["newton_iterations"] += its
        stats["factorizations"] += nfac
        stats["nfev"] += its + 1
        stats["njev"] += nfac
        stats["max_newton_iterations"] = max(stats["max_newton_iterations"], its)
        if sol is None:
            self._failed(h, h_min)
            return
        if got is None:
            x, v, F = self.x, self.v, self.F
            bi = self.bi
            t_n0 = math.nextafter(t, math.inf) if (bi > 0 and t == self.breaks[bi - 1]) else t
            net_n = self.scene.net_forces(t_n0, F)
            self.clock(t)  # (the laws at y_n: the support offsets at t)
            q_n = self.scene.elongations(x, v)
            jac_n = [self.kernels[e](q_n[e], F[e])[1:] for e in range(self.E)]
            err = self.system.error(self.U, h, x, v, net_n, jac_n)
            err_norm = math.inf if err is None else self.system.error_norm(
                self.U, h, x, v, F, err, self.rtol, self.atol, self.dF_n, self.watched,
                self.Fref)
        fac = 0.9 * (2 * MAX_NEWTON + 1) / (2 * MAX_NEWTON + its)
        if not math.isfinite(err_norm):
            stats["rejected"] += 1
            self.h *= 0.2
            self.h_acc = None
            return
        quot = max(0.125, min(5.0, err_norm ** 0.25 / fac))
        if err_norm > 1.0 and self.target is None:
            stats["rejected"] += 1
            self.h = h / quot
            self.h_acc = None
            return
        s_kink = self.kink(sol, h) if self.target is None and \
            self.kink_cuts < _KINK_CUTS else None
        if s_kink is not None:
            self.kink_cuts += 1
            # the split among locks in parallel kinks inside the step, and the force's
            # cubic overshoots its lock's interval: end the step at the kink
            stats["rejected"] += 1
            stats["split_rejected"] = stats.get("split_rejected", 0) + 1
            self.h *= s_kink
            self.h_acc = None
            return
        if self._redo_for_a_guard(sol, h, got is None, hit_c, h_min):
            return
        if self.ms.forces_from_probe and self.target is None:
            # the first step after an event, no guard crossed in it: its dense output
            # against the held laws between the nodes (a junction's Herschel-Bulkley
            # n < 1 dashpot breaking out starts as (t - t*)^n, which the error estimate
            # does not see)
            d = self.defect(sol, h)
            if d > 1.0:
                stats["rejected"] += 1
                stats["defect_rejected"] = stats.get("defect_rejected", 0) + 1
                self.h *= max(0.1, min(0.5, 0.8 / d))
                self.h_acc = None
                return
        F_0 = self.start_forces(sol) if self.checked else self.F
        self.bare()  # (element_nodes hold the support offsets)
        folded = [e for e in self.checked if fold_crossed(
            self.kernels[e], *self.system.element_nodes(sol, h, self.x, self.v, F_0, e))]
        if folded:
            el = self.scene.elements[folded[0]]
            self.status, self.message = Status.BRANCH_LOST, (
                f"element {el.name!r} (law {el.law_name!r}) reaches a fold of its law "
                f"between t = {t!r} and {t + h!r}: dR/dq or dR/dF changes sign, there is no "
                "solution continuous with the past beyond it")
            return
        self._accept(sol, h, t_stop if to_stop else t + h, to_stop, h_min, quot, err_norm)

    def flat_ends(self) -> list[int]:
        """The elements held on a branch flat at its end and starting there, none with
        moving supports (:class:`~lumped.solvers.radau.flat_start.FlatEnds`: once per state)."""
        return [] if self.frame is not None else self.flat_reader()(self.modes, self.F)

    def flat_reader(self) -> FlatEnds:
        """The run's :class:`~lumped.solvers.radau.flat_start.FlatEnds` (made when first
        asked; its ``table`` is the compiled loop's copy)."""
        self._flat = self._flat or FlatEnds(self.lbs)
        return self._flat

    def stage_guess(self, h: float, damped: bool = False) -> list[float]:
        """The stage guess of a step of size ``h``: ``(v_n, F_n)`` at every stage, or,
        when a held branch starts at its flat end, on the branches
        (:func:`~lumped.solvers.radau.flat_start.flat_start`; not for the line search)."""
        U = (list(self.v) + list(self.F)) * 3
        ends = [] if damped else self.flat_ends()
        if ends:  # (the forcing's value just past a breakpoint at t, as the error's)
            t, bi = self.t, self.bi
            net_n = self.scene.net_forces(math.nextafter(t, math.inf) if (
                bi > 0 and t == self.breaks[bi - 1]) else t, self.F)
            flat_start(self.system, U, h, self.x, self.v, self.F, net_n, self._flat.starts,
                       self.guards, ends, rate_lock_chains(self.scene, self.lbs, self.modes))
        return U

    def _failed(self, h: float, h_min: float) -> None:
        """A step of size ``h`` whose stage solve failed: the mode chosen again where the
        locks in parallel cannot carry the load, the landing bracket closed, or the step
        halved."""
        self.stats["rejected"] += 1
        self.h_acc = None
        t, target = self.t, self.target
        if self.system.infeasible and target is None and t != self.infeasible_at:
            # the locks in parallel cannot carry the load together (no guard sees it: the
            # cone split keeps every force in its cone): let the full laws choose the
            # mode at t, once per t
            self.infeasible_at = t
            # (probes on the scale of the step that failed: the lock breaks within it)
            changed = self.choose_again(h)
            if changed is None:
                return
            if changed:
                self.h = self.h_good
                return
            # the full laws keep the locks (a probe's step holds where the stage's does
            # not): the split of least squares stands, as before, until an accepted step
            self.infeasible_modes = list(self.modes)
            return
        # a landing step that Newton cannot take: no solution that far, the bracket ends
        # there (halving alone went below the step that held, to 0)
        h_next = None if target is None else target.failed_stage(h, t)
        if h_next is not None:
            self.h = h_next
            return
        self.h *= 0.5
        if target is not None and self.h < h_min:  # no landing step holds: the event is
            self.target, self.dF_n = None, None  # at t itself, the full laws choose the mode
            old = list(self.modes)
            if self.stop(self.at_event(t, self.h_good, "guard")):
                return
            self.kept, self.h = self.modes == old or self.ms.returned, self.h_good
            self.tangent.clear()

    def _redo_for_a_guard(self, sol: list[float], h: float, in_python: bool, hit_c,
                          h_min: float) -> bool:
        """The guards along a solved step: whether it is redone (shorter, to land on the
        first crossing; or not at all, the event being at ``t``; or as a failed step,
        ``h_min`` its floor, when it went beyond a guard read as a tangency) rather than
        accepted. A landing step is accepted once it ends on its guard."""
        t, tiny = self.t, 16 * _EPS * max(1.0, abs(self.t))
        tangent, kept, target = self.tangent, self.kept, self.target
        # (the compiled attempt has found the crossing by the same algorithm; after an
        # event it saw the probe's forces: tested again from the stage forces, compiled)
        hit = self.crossing(sol, h) if (in_python or tangent or hit_c is NOT_SOUGHT) else (
            self.fast.root_from(hit_c, self.start_forces(sol)) if self.ms.forces_from_probe
            else hit_c)
        while kept and hit is not None and (hit[0] * h <= tiny or (
                tangent and hit[0] <= 1.001 * C[0]) or self.held_on_lock(sol, h, hit[1])):
            # the full laws kept the mode at t: a guard read crossed at t is a tangency
            # (round-off), and so is one crossed later only by the stage rates' round-off
            # on a lock (a stuck Coulomb element at its yield force on a junction: landed
            # on every 4e-6 s at rtol 1e-10); one crossed otherwise is an event (a Coulomb
            # element stuck at its yield force beside two stuck dashpots hid their
            # break-out: the step went on to 2 % beyond their yield forces). One crossed by
            # the first stage is the state at t too (a stuck Coulomb element's stage split
            # a hair beyond its yield force beside a junction's stopping Herschel-Bulkley
            # dashpot was landed on again and again: the run crept on by 1e-15 s)
            tangent.add(hit[1])
            hit = self.crossing(sol, h)
        if tangent and self.beyond_tangent(sol, h):
            # a guard read as a tangency is off at a stage beyond the tolerance: another root
            # of the held branch (Herschel-Bulkley n = 2's mirror root below tau), failed
            self._failed(h, h_min)
            return True
        if target is not None:  # a landing step: bracket the event by end-of-step values
            g_end, tol = self.end_guard(sol, h, target.which)
            s_in = hit[0] if hit is not None and hit[0] < 1.0 else None
            g_other = None if s_in is None or hit[1] == target.which else self.end_guard(
                sol, h, hit[1])[0]
            if g_other is not None and target.switches(g_end, g_other):
                # another guard crosses first; at t itself: no landing, the event is at t
                at_t = s_in * h <= tiny
                self.target = None if at_t else Landing(hit[1], h, g_other, target.h_found)
                self.h = h if at_t else s_in * h
                return True
            s_in = s_in if g_other is None else None  # (this guard's crossing inside)
            landed = target.landed(g_end, tol, t, h, s_in)  # (a step that lands is accepted)
            self.h = h if landed else target.next_size(h, g_end, s_in)
            return not landed
        if hit is None or not hit[0] < 1.0 or (kept and hit[0] * h <= tiny):
            return False
        s_hit = hit[0]
        if s_hit * h <= tiny:
            # the event is at t itself: choose the mode again, no step
            self.dF_n = None
            old = list(self.modes)
            if self.stop(self.at_event(t, h, "guard")):
                return True
            # the full laws keep the mode at t (a tangency, round-off): the retried step
            # is accepted unless a guard fails later in it
            self.kept = self.modes == old or self.ms.returned
            tangent.clear()
            return True
        self.target = Landing(hit[1], h, self.end_guard(sol, h, hit[1])[0], h)
        self.h = s_hit * h
        return True

    def _accept(self, sol: list[float], h: float, t_new: float, to_stop: bool, h_min: float,
                quot: float, err_norm: float) -> None:
        """Accept the step ``sol`` of size ``h`` (ending at ``t_new``): its dense output
        and row, the creep test, the next step size (Gustafsson's predictive
        controller), and the event the step landed on or the time event at its end."""
        N, n, x, stats = self.N, self.n, self.x, self.stats
        Y = []
        for k in range(3):
            Xk = []
            for i in range(N):
                s_ = 0.0
                for j in range(3):
                    s_ += _A[k][j] * sol[j * n + i]
                Xk.append(x[i] + h * s_)
            Y.append(Xk + sol[k * n:k * n + N] + sol[k * n + N:k * n + n])
        F0 = self.dense_start_forces(sol, h)
        ms = self.ms
        ms.forces_from_probe = False
        self.dense.add(self.t, h, x + self.v + F0, Y, self.lock_group())
        self.dF_n = self.system.end_slope(sol, h, self.F)
        target = self.target
        event_here = target is not None
        h_found = target.h_found if event_here else 0.0
        ms.hint = self.watched[target.which[0]] if event_here else None
        self.target = None
        t_prev, t = self.t, t_new
        self.t = t
        self.clock(t)
        self.x, self.v, self.F = Y[2][:N], Y[2][N:2 * N], Y[2][2 * N:]
        self.commit(t)
        stats["steps"] += 1
        self.kink_cuts = 0
        self.rows.append(row_of(t, self.x, self.v, self.F))
        # a landing step is exempt from the step floor; landings of ulps, one after the
        # other, with the full laws keeping the mode each time, move t by nothing (a
        # junction on a Coulomb element, a Herschel-Bulkley n = 0.3 dashpot and a spring
        # in parallel: 2000 steps moved t by 1e-12, and max_steps = 1e6 would take hours)
        # (or 1e-12 of the run: a junction on one Coulomb element beside a mass landed
        # 5000 times on its guard with steps of 3e-14 s, 40 times the floor, 77 s a run)
        floor = creep_floor(t_prev, self.t_final)
        self.creeping = self.creeping + 1 if t - t_prev < floor else 0
        if self.creeping >= CREEP_STEPS:
            el = self.scene.elements[ms.hint] if ms.hint is not None else None
            self.status, self.message = creep_stop(t, self.creeping, floor, el)
            return
        ms.mark_free(t_prev, t, self.x, self.v, self.F)  # locks on cycles: forces not unique
        # the step size for the next step (Gustafsson's predictive controller)
        h_new = h / quot
        if self.h_acc is not None and err_norm > 0.0:
            facgus = (self.h_acc / h) * (err_norm ** 2 / self.err_acc) ** 0.25 / 0.9
            facgus = max(0.125, min(5.0, facgus))
            h_new = h / max(quot, facgus)
        self.h_acc, self.err_acc = h, max(1e-2, err_norm)
        self.h_good, self.floor_tried, self.kept, self.stalled = h, False, False, 0
        self.h_big = max(self.h_big, h)
        self.tangent.clear()
        # after a landing the step goes on from the size that found the event (the
        # landing step can be ulps long when the event sits at the step's start)
        self.h = max(h_new, h_found)
        is_break = to_stop and self.bi < len(self.breaks) and t == self.breaks[self.bi]
        if is_break and not event_here:
            self.time_event(self.h)  # (a kink of the forcing: no mode choice)
        elif event_here:
            if is_break:
                self.bi += 1
                ms.time_event(t)
            self.dF_n, self.h_acc, old = None, None, list(self.modes)
            self.stop(self.at_event(t, self.h, "guard"))
            self.kept = self.modes == old or ms.returned  # (as for an event at t itself)
