r"""One ``radau5`` run: its state and the loop of
:func:`lumped.solvers.eventdriven.runner.run_radau5`.

:class:`Radau5Run` holds what the loop carries from pass to pass (the state at ``t``, the step
size and the controller's memory, the landing bracket of a guard, the flags of an event at
``t``, the counters) and takes one pass at a time: a stop bridged by backward Euler, a held
interval, a stretch of held-mode steps in the compiled loop, or one step of the Python loop
(:class:`lumped.solvers.eventdriven.step.StepPass`: solved, then accepted or redone shorter).
The checks it reads off a solved step are :class:`lumped.solvers.eventdriven.checks.StepChecks`.
"""

from __future__ import annotations

import math

from ...grid import steps_for
from ...scene import Scene
from ..implicit.initial_state import consistent_initial_state
from ..modes.lock_events import hold_taut_strings
from ..modes.stuck import hold_interval
from ..radau.dense import DenseOutput, LockedForces
from ..radau.error import initial_step
from ..radau.rows import Rows, output_data, row_of
from ..radau.stage import StageSystem
from ..radau.tableau import C
from ..status import BranchError, RawRun, SolverError, Status
from . import compile_when
from . import fast as adaptive_fast
from .bridge import MAX_BRIDGES, take_bridge
from .budget import WorkBudget
from .checks import StepChecks
from .creep import creep_floor, creep_stop
from .landing import Landing
from .mode_state import ModeState
from .setup import read_options, scene_plan, structure, time_events
from .start_mode import start_mode
from .step import StepPass

__all__ = ["Radau5Run", "DEFAULT_RTOL", "DEFAULT_ATOL"]

DEFAULT_RTOL = 1e-6
DEFAULT_ATOL = 1e-9
#: Choices of the mode at (nearly) one time that keep it (a series of
#: :meth:`~lumped.solvers.eventdriven.budget.WorkBudget.kept`) after which the run stops
#: there (and is bridged): a stall. At most 1 in 6300 runs of random networks that did not
#: stall (2100 draws, 3 levels); a stall repeats it every 20-40 loop passes, up to
#: :data:`~lumped.solvers.radau.stage.STALL_PASSES` (4 s a stall).
_KEPT_AT_T = 4
#: The stops that backward Euler bridges (:mod:`lumped.solvers.eventdriven.bridge`, the keyword
#: ``bridge``); a fold of a law (``BRANCH_LOST``), the work budget ``max_steps``
#: (``MAX_ITERS``, :mod:`lumped.solvers.eventdriven.budget`) and ``max_events`` end
#: the run.
_BRIDGED = frozenset({Status.STEP_TOO_SMALL, Status.TOO_MANY_EVENTS, Status.INCONSISTENT})


class Radau5Run(StepPass, StepChecks):
    """The state of one ``radau5`` run of ``scene`` (see the module notes); :meth:`run`
    takes it to the end.

    Set up in the constructor: the consistent initial state and the initial mode (by a
    vanishing implicit step of the full laws), the first step size, the compiled loop if
    the scene has one.

    With moving supports ``scene`` is the view of a
    :class:`~lumped.scene.supports.SupportFrame` (``source`` the user's scene, which a
    bridge runs on): :meth:`clock` sets its offsets to the time of the state being read,
    the stage system sets them per stage, and the checks along a step read the law's
    argument at the polynomial's nodes with the clock bare. Such a run has no compiled
    loop and no held intervals (a node stuck to a moving support moves).
    """

    def __init__(self, scene: Scene, settings, source: Scene | None = None) -> None:
        plan = scene_plan(scene)
        if plan.refused:
            raise ValueError(plan.refused)
        self.scene, self.settings, self.plan = scene, settings, plan
        #: the support frame of a scene with moving supports (else None), and the scene
        #: the user gave
        self.frame = getattr(scene, "support_frame", None)
        self.source = scene if source is None else source
        self.rtol = rtol = DEFAULT_RTOL if settings.rtol is None else settings.rtol
        self.atol = atol = DEFAULT_ATOL if settings.atol is None else settings.atol
        self.opts = opts = read_options(settings)
        dt = settings.dt
        self.t_final = t_final = settings.t_end if dt is None else max(
            settings.t_end, steps_for(dt, settings.t_end) * dt)
        self.N, self.E = N, E = len(scene.nodes), len(scene.elements)
        self.n = N + E
        (self.is_mass, self.masses, self.spring, self.massless,
         self.m_min) = structure(scene, plan)
        self.system = StageSystem(self.masses, scene.elem_a, scene.elem_b, self.spring)
        self.system.frame = self.frame  # (the stage times of the support offsets)
        self.checked = plan.checked
        x = [float(nd.x0) for nd in scene.nodes]
        v, F, ic = consistent_initial_state(scene, time_scale=t_final,
                                            options=settings.options)
        self.x, self.v, self.F = x, v, F
        # the forcing's breakpoints, and whether each is a kink (no mode choice there)
        self.breaks, self.kinks = time_events(scene, t_final)
        zeno_window = opts["zeno_window"] or 1e-6 * t_final
        self.dense = DenseOutput(N, E, LockedForces(scene))
        self.rows = Rows()
        self.rows.append(row_of(0.0, x, v, F))
        self.stats = stats = {
            "steps": 0, "rejected": 0, "newton_iterations": 0, "factorizations": 0,
            "nfev": 0, "njev": 0, "events": 0, "max_newton_iterations": 0,
            "initial_newton_iterations": ic["newton_iterations"], "held_intervals": 0}
        self.status, self.message = Status.SUCCESS, ""
        self.budget = WorkBudget(opts["max_steps"], t_final)  # (lumped.solvers.eventdriven.budget)
        self.fast, stats["loop"] = adaptive_fast.compiled_loop(scene, plan, opts["compiled"])
        self.ms = ms = ModeState(scene, plan, settings, opts, rtol, atol, stats, zeno_window)
        ms.fast = self.fast
        # (the mode's lists, changed in place by ``ms``)
        self.modes, self.kernels, self.guards = ms.modes, ms.kernels, ms.guards
        self.watched, self.cones, self.lbs = ms.watched, ms.cones, plan.branches
        # the compiled stage Newton (compiled=True), built on first need: with the compiled
        # loop the attempts need it only after a singular Jacobian (building it costs ~0.7 ms)
        self.stage_solve = None
        msg = start_mode(ms, 1e-9 * t_final, x, v, F)
        ms.events.clear()
        ms.recent.clear()
        # locks in parallel: the first step starts their split from its stages' as after an
        ms.forces_from_probe = bool(ms.cones)  # event (StepChecks.dense_start_forces)
        if msg:
            raise SolverError(f"radau5: no consistent initial mode: {msg}",
                              status=Status.INCONSISTENT, t=0.0, where="", residual=math.nan)
        self.rows.set_first(row_of(0.0, x, v, F))
        # the last state a step (or a held interval) ended on, before any event there
        # changed it: a bridge starts from it (an event probe's forces on a position lock
        # are m ulp(x) / h_probe^2, 1e11, no start for a Newton iteration)
        self.commit(0.0)

        net = scene.net_forces(0.0, F)
        acc0 = [net[i] / self.masses[i] if self.is_mass[i] else 0.0 for i in range(N)]
        h = opts["first_step"] or initial_step(x, v, acc0, self.is_mass, rtol, atol, t_final)
        self.h = self.h_good = self.h_big = h  # (h_big: the scale of a bridge's steps)
        self.h_acc = self.err_acc = None
        self.F_seen = 0.0
        if self.fast is not None:
            self.fast.setup(t_final, rtol, atol, self.m_min)
        self.dF_n: list[float] | None = None  # force slopes at t (None after events)
        self.target: Landing | None = None  # the guard being landed on and its bracket
        self.floor_tried = False  # a mode change was tried at the step floor since
        self.infeasible_at = math.nan  # the last t where an infeasible stage had the mode
        self.infeasible_modes: list[int] = []  # chosen, and the mode the full laws kept
        self.U: list[float] = []  # the Python attempt's stage values (``attempt``)
        self.Fref = 0.0  # ... and its force scale
        self.kept = False  # an event at t kept the mode (since the last step)
        self.tangent: set[tuple[int, int]] = set()  # ... and the guards read crossed then
        self.t = 0.0
        self.bi = 0  # the next breakpoint of the forcing
        self.bridges: list[str] = []  # the stops bridged by backward Euler, and where
        self.stalled = 0  # loop passes since the last accepted step (a guard on cycles)
        self.creeping = 0  # accepted steps in a row below the step floor (landings)
        self.kink_cuts = 0  # steps cut at a kink of the split since the last accepted one
        self.hold_check = True  # a held interval may start at t

    # -----------------------------------------------------------------------------------
    # small pieces

    def clock(self, t: float) -> None:
        """The support offsets the laws read set to ``o_e(t)`` (no supports: nothing)."""
        if self.frame is not None:
            self.frame.at_time(t)

    def commit(self, t: float) -> None:
        """Keep ``(t, x, v, F)`` as the last state a step or held interval ended on."""
        self.committed = (t, list(self.x), list(self.v), list(self.F))

    def t_stop(self) -> float:
        """The next breakpoint of the forcing, or the end."""
        return self.breaks[self.bi] if self.bi < len(self.breaks) else self.t_final

    def stop(self, got: tuple[Status, str] | None) -> bool:
        """Record a stop ``(status, message)`` if there is one; whether there was."""
        if got:
            self.status, self.message = got
            return True
        return False

    def at_event(self, t: float, h: float, cause: str) -> tuple[Status, str] | None:
        """The mode after an event at ``t`` (:meth:`ModeState.at_event`); a stop when the
        full laws keep the mode at the same ``t`` for the :data:`_KEPT_AT_T`-th time (no
        step in that mode gets away from ``t``: a cycle of landings that every pass of the
        loop would repeat up to :data:`~lumped.solvers.radau.stage.STALL_PASSES`)."""
        self.hold_check = True  # a stuck interval may start here (lumped.solvers.modes.stuck)
        old = list(self.modes)
        stop = self.ms.at_event(t, h, cause, self.x, self.v, self.F)
        if stop or self.modes != old:
            self.tangent.clear()  # (the old mode's (watched, guard) pairs)
            return stop
        count = self.budget.kept(t, self.stats)
        if count < _KEPT_AT_T:
            return None
        since = "" if self.budget.kept_at == t else f", from t = {self.budget.kept_at!r} on"
        return Status.STEP_TOO_SMALL, (
            f"radau5 stopped at t = {t!r}: the full laws kept the mode there {count} times"
            f"{since} (each step in it crosses a guard at once, and no step gets away)")

    def time_event(self, h: float) -> bool:
        """A time event at the breakpoint ``t``; whether the run stops there. At a kink of
        the forcing (:func:`~lumped.solvers.eventdriven.setup.time_events`) the mode goes
        on and no event is recorded; the error estimate starts afresh either way."""
        kink = self.kinks[self.bi]
        self.bi += 1
        self.dF_n = self.h_acc = None
        if kink:
            return False
        self.ms.time_event(self.t)
        return self.stop(self.at_event(self.t, h, "time"))

    def choose_again(self, h_p: float) -> bool | None:
        """The full laws choose the mode at ``t`` (probes on the scale ``h_p``): whether
        it changed, or ``None`` when the run must stop (``status``, ``message`` set)."""
        old = list(self.modes)
        self.dF_n = None
        if self.stop(self.at_event(self.t, h_p, "guard")):
            return None
        return self.modes != old

    def attempt(self, h: float, iters: int, damped: bool = False
                ) -> tuple[list[float] | None, int, int]:
        """The stage solve of a step of size ``h`` from ``(t, x, v, F)`` in Python (the
        compiled stage Newton when ``compiled=True``; with ``damped``, the line-search
        fallback :meth:`~lumped.solvers.radau.stage.StageSystem.solve_damped`): ``(U or None,
        iterations, factorisations)``; sets ``U``, ``Fref`` and ``F_seen`` for the error
        estimate."""
        t, x, v, F, atol, rtol = self.t, self.x, self.v, self.F, self.atol, self.rtol
        fk = [self.scene.external_forces(t + C[k] * h) for k in range(3)]
        self.U = self.stage_guess(h, damped)  # (v_n, F_n), or on a flat end's branch
        # the force scale: the largest force or load met so far (never shrinks to 0)
        self.F_seen = max([self.F_seen] + [abs(Fe) for Fe in F] + [abs(fi) for fi in fk[2]])
        # ... and at least the force that changes the lightest mass's velocity by its
        # tolerance over the step (a force error below it does not show in x, v)
        self.Fref = max(self.F_seen, self.m_min * (max(abs(vi) for vi in v) + atol / rtol) / h)
        scale = ([atol + rtol * abs(vi) for vi in v]
                 + [rtol * max(abs(Fe), self.Fref) for Fe in F]) * 3
        system, kernels, cones = self.system, self.kernels, self.cones
        # (the stage times t + c_k h of the support offsets; the round-off floor, .roundoff)
        system.t_n, system.after_impact = t, self.ms.after_impact
        if damped:
            return system.solve_damped(self.U, h, x, v, fk, kernels, scale, max_iters=iters)
        if self.stage_solve is None and self.opts["compiled"] is True and self.frame is None:
            self.stage_solve = adaptive_fast.compiled_stage_solver(self.scene, self.modes)
        got = None if self.stage_solve is None or cones else self.stage_solve(
            self.U, h, x, v, fk, scale, iters, system.after_impact)  # (None: singular, ...)
        if got is None:  # (locks in parallel: the cone split)
            return system.solve(self.U, h, x, v, fk, kernels, scale, max_iters=iters,
                                cones=cones or None, least_squares=t == self.infeasible_at
                                and self.modes == self.infeasible_modes)
        self.U = got[0] if got[0] is not None else self.U
        return got

    def state(self) -> dict:
        """The loop's state for the compiled loop (:mod:`lumped.solvers.eventdriven.fast`)."""
        bi, breaks = self.bi, self.breaks
        return {"t": self.t, "h": self.h, "x": self.x, "v": self.v, "F": self.F,
                "dF_n": self.dF_n, "F_seen": self.F_seen, "h_acc": self.h_acc,
                "err_acc": self.err_acc, "h_good": self.h_good, "h_big": self.h_big,
                "stalled": self.stalled, "creeping": self.creeping, "t_stop": self.t_stop(),
                "t_final": self.t_final, "prev_break": breaks[bi - 1] if bi > 0 else math.nan,
                "bi": bi, "breaks": breaks, "kinks": self.kinks, "rtol": self.rtol,
                "atol": self.atol, "m_min": self.m_min,
                "max_steps": self.budget.compiled_cap(self.stats), "group": self.lock_group(),
                "flat": self.flat_reader().table(self.modes), "held": self.held}

    def bridge_over(self) -> bool:
        """Backward Euler over the stop (``status``, ``message``) from the last accepted
        state (:mod:`lumped.solvers.eventdriven.bridge`), its steps in the output; then the mode the
        full laws choose at its end. Whether the run goes on."""
        bridges = self.bridges
        if len(bridges) >= MAX_BRIDGES:
            self.message += (f" (after {len(bridges)} bridges by backward Euler, the most a "
                             "run takes)")
            return False
        t = self.t
        start = self.committed if self.committed[0] == t else (t, self.x, self.v, self.F)
        got = take_bridge(self.source, start, len(bridges), self.rtol, self.h_big,
                          self.t_final, self.settings.options, self.opts["restitution"],
                          self.dense, self.rows, self.ms.events, self.ms.log, self.stats)
        if isinstance(got, str):
            self.message += f"; {got}"
            return False
        t0 = t
        self.t, self.x, self.v, self.F, to_end, delta = got
        while self.bi < len(self.breaks) and self.breaks[self.bi] <= self.t:
            self.bi += 1  # the forcing's breakpoints the bridge passed (its steps took them)
        self.commit(self.t)
        bridges.append(f"[{t0!r}, {self.t!r}] over: {self.message}")
        self.stats["bridges"] = len(bridges)
        self.status, self.message = Status.SUCCESS, ""
        self.target, self.dF_n, self.h_acc = None, None, None
        self.kept, self.floor_tried, self.hold_check = False, False, True
        self.stalled = self.creeping = self.kink_cuts = 0
        self.tangent.clear()
        self.h = max(self.h_good, delta)
        self.ms.recent.clear()
        if not to_end and not self.stop(self.at_event(self.t, self.h, "start")):
            self.v = hold_taut_strings(self.scene, self.lbs, self.modes, self.v)  # (BE's v)
        return True

    # -----------------------------------------------------------------------------------
    # the loop

    def run(self) -> RawRun:
        """Step to the end (or a stop that is not bridged) and return the run."""
        opts = self.opts
        while self.t < self.t_final:
            if self.status is not Status.SUCCESS:
                # a stop mid-run: bridged by backward Euler (.bridge), or the run ends here
                if not (opts["bridge"] and self.status in _BRIDGED
                        and len(self.ms.events) <= opts["max_events"] and self.bridge_over()):
                    break
                continue
            if self.stop(self.budget.check(self.t, self.stats)):
                continue  # the work budget is spent: the run ends (never bridged)
            if self.hold_check and self.target is None and not self.kept and self.frame is None:
                self.hold_check = False
                if self._hold():
                    continue
            stats = self.stats
            if self.fast is None and stats["loop"].startswith(compile_when.WAITING) and \
                    compile_when.due(stats["steps"]):
                # a long run: compile the scene's loop now
                self.fast, stats["loop"] = adaptive_fast.compiled_loop(
                    self.scene, self.plan, None, stats["steps"])
                self.ms.fast = self.fast
                if self.fast is not None:
                    self.fast.setup(self.t_final, self.rtol, self.atol, self.m_min)
            if self.fast is not None and self.target is None and not self.kept and \
                    self.takes_first() and not self.flat_ends() and self._fast_steps():
                continue
            tried = stats["steps"] + stats["rejected"]
            self._step()
            self.budget.redone += tried == stats["steps"] + stats["rejected"]
        return self._result()

    def _hold(self) -> bool:
        """At rest in a mode that locks every node: the static balance up to the
        break-out or the stop, no steps (the same in both loops). Whether it held."""
        seg = hold_interval(self.scene, self.plan, self.ms, self.t, self.t_stop(), self.x,
                            self.v, self.F, self.dense, self.rows)
        if seg is None:
            return False
        self.t, self.F, broke = seg[0], list(seg[1]), seg[2]
        self.commit(self.t)
        self.stats["held_intervals"] += 1
        self.dF_n = self.h_acc = None
        if broke:
            stop = self.at_event(self.t, self.h, "guard")
            # the forces are continuous across a break-out: the balance's exact values,
            # not the probe's (off by O(h_p), which the new branch's guard can read as a
            # return at once)
            self.F[:] = seg[1]
            self.stop(stop)
        elif self.bi < len(self.breaks) and self.t == self.breaks[self.bi]:
            self.time_event(self.h)
        return True

    def _fast_steps(self) -> bool:
        """The held-mode steps compiled (the same numbers as :meth:`_step`); it returns
        before the pass this loop must take (a stop, an event, ...). Whether it took the
        run to the stop (a time event, or the end), where this pass ends."""
        st = self.state()
        stats = self.stats
        before = stats["steps"]
        why = self.fast.run(st, self.modes, self.watched, stats, self.dense, self.rows)
        for key in ("t", "h", "x", "v", "F", "dF_n", "F_seen", "h_acc", "err_acc", "h_good",
                    "h_big", "stalled", "bi", "creeping"):  # (bi: the kinks it stepped onto)
            setattr(self, key, st[key])
        if stats["steps"] > before:  # (as the Python loop's accepted steps set them)
            self.commit(self.t)  # (no step taken: the state a bridge starts from stays)
            self.kink_cuts, self.ms.hint, self.ms.forces_from_probe = 0, None, False
            if why == "creep":  # (its last step stops the run: Python's order)
                self.status, self.message = creep_stop(
                    self.t, self.creeping, creep_floor(st["t_prev"], self.t_final), None)
                return True
            self.floor_tried = False
        if why != "stopped":
            return False
        if self.bi < len(self.breaks) and self.t == self.breaks[self.bi]:
            self.time_event(self.h)
        return True

    def _result(self) -> RawRun:
        """The run's output (raises on a stop when ``settings.throw``)."""
        stats, message, status = self.stats, self.message, self.status
        stats["events"] = len(self.ms.events)
        if self.bridges:
            message = (message + " " if message else "") + (
                f"radau5 bridged {len(self.bridges)} stop(s) by backward Euler: "
                + "; ".join(self.bridges))
        if status is not Status.SUCCESS and self.settings.throw:
            error = BranchError if status is Status.BRANCH_LOST else SolverError
            raise error(message, status=status, t=self.t, where="", residual=math.nan)
        data = output_data(self.rows, self.dense, self.settings.dt, self.settings.t_end,
                           self.t)
        return RawRun(data, stats, status, message, self.ms.events,
                      self.dense if len(self.dense) else None,
                      indeterminate=self.ms.log.result())
