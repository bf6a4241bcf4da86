r"""The mode of the ``radau5`` driver: which branch of its law every element is held on,
and what happens at an event (a guard crossing, a time event, the start).

:class:`ModeState` is the small state object of a ``radau5`` run
(:class:`lumped.solvers.eventdriven.run.Radau5Run`) that owns the held branches (``modes``),
their kernels and guards, the elements whose guards are watched, the force-split cones of locks
in parallel, and the event record. :meth:`ModeState.at_event` chooses the mode after an event by
a vanishing implicit step of the full laws (:func:`lumped.solvers.modes.choice.select_modes`),
applies impacts, records the switches and tests for an accumulation of events.
"""

from __future__ import annotations

import math
from collections import deque

from ...scene import Mass, Scene
from ...scene.supports import support_time
from ..implicit.initial_slip import start_at_known_rates
from ..modes.after_impact import (
    beside_released,
    held_through,
    hold_impacted_locks,
    release_resting_locks,
)
from ..modes.choice import select_modes
from ..modes.finite_stop import take_stop
from ..modes.force_bounds import group_modes, onto_slip_ends
from ..modes.junctions_at import junctions_at
from ..modes.lock_events import (
    apply_impacts,
    hold_rate_locks,
    hold_strung_junctions,
    snap_to_locks,
)
from ..modes.mode_guess import probe_state, try_modes
from ..modes.probe_locks import lock_probe_rates
from ..nonsmooth.locks import IntervalLog, indeterminate_elements
from ..status import Event, Status
from .kept_state import state_stays
from .mode_parts import laws_hold, mode_cones, mode_parts
from .setup import accumulating, too_many

__all__ = ["ModeState"]
_EPS = 2.220446049250313e-16


class ModeState:
    """The held branches of a run and its events (see the module notes).

    Parameters
    ----------
    scene : Scene
    plan : ScenePlan
        The scene's :func:`~lumped.solvers.eventdriven.setup.scene_plan` (branches, cycles).
    settings : RunSettings
        ``options`` (the Newton options of the probe step) are read from it.
    opts : dict
        The ``radau5`` keywords (:func:`~lumped.solvers.eventdriven.setup.read_options`).
    rtol, atol : float
        The run's tolerances (the rate scale below which a rate snaps onto a lock).
    stats : dict
        The run's counters (``events`` is kept up to date).
    """

    def __init__(self, scene: Scene, plan, settings, opts: dict, rtol: float, atol: float,
                 stats: dict, zeno_window: float) -> None:
        self.scene, self.lbs, self.settings, self.opts = scene, plan.branches, settings, opts
        self.rtol, self.atol, self.stats = rtol, atol, stats
        self.names = scene.element_names
        self.N, self.E = len(scene.nodes), len(scene.elements)
        self.is_mass = [isinstance(nd, Mass) for nd in scene.nodes]
        self.m_min = min((nd.m for nd in scene.nodes if isinstance(nd, Mass)), default=1.0)
        self.cyclic = plan.cyclic if plan.structure["free_cycles"] else ()  # (none free)
        self.zeno_window = zeno_window
        self.modes = [0] * self.E
        self.kernels: list = [None] * self.E
        self.guards: list = [None] * self.E
        self.watched: list[int] = []
        # locks in parallel: force split (centre, half-width, lo, hi)
        self.cones: dict[int, tuple[float, float, float, float]] = {}
        self.events: list[Event] = []
        self.recent: deque = deque(maxlen=opts["zeno_events"])
        self.time_events = 0  # of the events, the forcing's time events
        self.kept_at_step = -2  # the accepted steps at the last kept choice at a guard
        # the modes held at one t and left there, each with the number of events when it
        # was first held there and the times it was (``left_at``: that t and the accepted
        # steps then; :meth:`_note_left`)
        self.left_at: tuple[float, int] = (math.nan, -1)
        self.left: dict[tuple[int, ...], list[int]] = {}
        self.returned = False  # the last choice returned to a mode held at t (_choose)
        self.log = IntervalLog()
        self.fast = None  # the compiled loop (told when x, v, F change in place)
        # a guessed mode is tried first when every law is monotone (lumped.solvers.
        # mode_guess); ``hint``: the element whose guard the driver landed on
        self.guessing = not plan.checked
        self.hint: int | None = None
        self.forces_from_probe = False  # the forces at t are an event probe's
        self.impacted = False  # ... and that event applied an impact (velocities jumped)
        self.decided = [0.0]  # the sizes of the probes of the last choice, the deciding last
        self.plan = plan

    def set_modes(self, new: list[int], F: list[float]) -> None:
        """Hold every element on branch ``new[e]`` (the list ``modes`` is kept)."""
        self.modes[:] = new
        parts = mode_parts(self.plan, tuple(new))
        # (in place: the driver holds these lists)
        self.kernels[:], self.guards[:], self.watched[:] = parts[0], parts[1], parts[2]
        self.cones.clear()
        self.cones.update(mode_cones(self.scene, self.plan, new, F, parts))

    @property
    def after_impact(self) -> bool:
        """The next step is the first after an impact (a junction may jump within it)."""
        return self.forces_from_probe and self.impacted

    def change_mode(self, t: float, h_probe: float, cause: str, x: list[float],
                    v: list[float], F: list[float]) -> str:
        """Choose the mode after ``t`` and record the switches (``x, v, F`` in place);
        '' or a failure message."""
        scene, lbs, modes, names, events = self.scene, self.lbs, self.modes, self.names, self.events
        rtol, atol, options = self.rtol, self.atol, self.settings.options
        support_time(scene, t)  # (moving supports: the laws at t; a probe at t + h_p sets t back)
        if self.fast is not None:
            self.fast.forget()  # x, v, F may change in place here
        h0 = h_probe
        v_free, held = list(v), []
        if cause == "guard":  # rates within the tolerance of a lock: exactly on it
            held = snap_to_locks(scene, lbs, x, v, F, atol + rtol * max(abs(vi) for vi in v),
                                 atol + rtol * max(abs(xi) for xi in x))
        hint = self.hint
        self._note_left(t)
        sel = self._choose(t, h_probe, cause, x, v, F)
        if isinstance(sel, str):
            return sel
        new = sel[0]
        if held and v != v_free and not any(lbs[e].info[new[e]].locks for e in held) \
                and any(new[e] != modes[e] for e in range(self.E) if e not in held):
            # the snap's premise failed (no element it held stays locked) and another
            # switched, by a rate the snap flipped (a Bingham dashpot sent to its other slip
            # branch and back 50 times, 1e-9 s apart): choose from the state as it was
            v_snapped, v[:], self.hint = list(v), v_free, hint
            again = self._choose(t, h0, cause, x, v, F)
            if isinstance(again, str):
                v[:] = v_snapped
            else:
                sel = again
        new, v_p, F_p = group_modes(scene, lbs, sel[0], t, F, rtol), sel[1], sel[2]
        got = probe_state(scene, lbs, new, t, x, v, F, h0) if self.decided[-1] > h0 and \
            not self.cones and not all(self.is_mass) else None  # (a long probe's junctions)
        if got:  # (... at t + h0; a lock's force stays the long probe's, not m ulp / h0^2)
            v_p, F_p = got[0], [F_p[e] if lbs[e].info[new[e]].locks else f
                                for e, f in enumerate(got[1])]
        scale_v = atol + rtol * max(abs(vi) for vi in v)
        if hint in held and new == modes:  # a finite-time stop within tolerance: take it
            new, v_p, F_p = take_stop(scene, lbs, new, hint, t, x, v, F, v_p, F_p, rtol, atol)
        hit = apply_impacts(scene, lbs, modes, new, x, v, scale_v, self.opts["restitution"],
                            F)
        if isinstance(hit, str):
            return f"impact at t = {t!r}: {hit}"
        self.impacted = bool(hit[0])
        if hit[0]:
            for e, impulse in hit[0]:
                events.append(Event(t, names[e], "impact", modes[e], new[e], impulse=impulse,
                                    energy_lost=hit[1] if e == hit[0][0][0] else 0.0))
                self.recent.append(t)
            self.left.clear()  # (the velocities jumped: a new state at t)
            self.returned = False
            # the mode after the impact, from the velocities after it (the probe's guess:
            # the forces before it; a failed probe is tried longer, as above)
            for k in range(3):
                sel = select_modes(scene, lbs, t, x, v, F, h0 * 1000.0 ** k, options)
                if not isinstance(sel, str):
                    break
            if isinstance(sel, str):
                return sel
            new, v_p, F_p = sel
            hold_impacted_locks(scene, lbs, t, held_through(scene, lbs, modes, hit[0]),
                                scale_v, x, v, F, new, F_p, rtol)
            chosen, h_p = list(new), h0 * 1000.0 ** k
            new, v_p, F_p = self._locked((new, v_p, F_p), h_p, x)  # (at rate 0)
        was = list(new)
        released = release_resting_locks(scene, lbs, t, modes, scale_v, x, v, F, new, F_p)
        for e in released:
            if any(e == k for k, _ in hit[0]):  # (impacted, then slack at once: recorded)
                events.append(Event(t, names[e], "switch", was[e], new[e]))
        again = beside_released(scene, lbs, t, x, v, F, h_p, chosen, new, released) \
            if released and hit[0] else None  # (a lock added beside a released string)
        if again is not None:
            new, v_p, F_p = again
        if not self.state_stays(t, cause, new, bool(hit[0]), x, v, F):
            # the probe's junction velocities, at t = 0 those of t itself (junctions_at),
            # where the initial forces stay unless they miss a law (a junction between two
            # slipping dashpots), and dashpots at known rates take their laws' at t
            got = junctions_at(scene, lbs, new, t, x, v, v_p, F_p) if cause == "start" else None
            v_t, F_t = got or (v_p, F_p)
            v[:] = [vi if mass else w for vi, w, mass in zip(v, v_t, self.is_mass, strict=True)]
            if hit[0]:  # (a junction taut strings tie to a mass: that mass's velocity)
                hold_strung_junctions(scene, lbs, new, v, scale_v)
            taken = cause != "start" or not laws_hold(mode_parts(self.plan, tuple(new))[0],
                                                      scene.elongations(x, v), F)
            F[:] = F_t if taken else F
            if cause == "start":  # (a mass a rate lock holds: at that rate in row 0 too)
                hold_rate_locks(scene, lbs, new, v)
                v[:], F[:] = start_at_known_rates(scene, v, F, v_p, F_p, [
                    lbs[e].info[k].locks for e, k in enumerate(new)], (t, x) if taken else None)
            elif cause == "guard":  # (a yield dashpot at rate ~0 switching: at its edge)
                F[:] = onto_slip_ends(scene, modes, new, v, F, scale_v, rtol)
        back = self.left.get(tuple(new))
        if back is not None and back[0] <= len(events):
            # back to a mode held at t (no accepted step since): the switches since then
            # took no time, none stays (a mode whose own switches a return to an earlier
            # mode cut is recorded anew: a break-out of e1 beside e0 was lost)
            del events[back[0]:]
        for e in range(self.E if back is None or back[0] > len(events) else 0):
            if new[e] != modes[e] and not any(ev.t == t and ev.element == names[e] and
                                              ev.kind == "impact" for ev in events[-self.E:]):
                events.append(Event(t, names[e], "switch", modes[e], new[e]))
                self.recent.append(t)
        now = [e for e in range(self.E) if lbs[e].info[new[e]].locks > lbs[e].info[modes[e]].locks]
        self.set_modes(new, F)
        hold_rate_locks(scene, lbs, modes, v, now)  # (the locks that hold now: exactly)
        return ""

    def state_stays(self, t: float, cause: str, new: list[int], impact: bool,
                    x: list[float], v: list[float], F: list[float]) -> bool:
        """:func:`~lumped.solvers.eventdriven.kept_state.state_stays` of this state."""
        return state_stays(self, t, cause, new, impact, x, v, F)

    def _note_left(self, t: float) -> None:
        """Record that the mode held now is left (or kept) at ``t``: the modes held at one
        ``t`` with no accepted step between them, how often, and the events before the
        first time (a return drops the switches since, :meth:`change_mode`; a mode left
        twice is one :meth:`_choose` does not return to)."""
        key = (t, self.stats["steps"])
        if key != self.left_at:
            self.left_at, self.left = key, {}
        self.left.setdefault(tuple(self.modes), [len(self.events), 0])[1] += 1

    def _choose(self, t: float, h_probe: float, cause: str, x: list[float], v: list[float],
                F: list[float]):
        """The full laws' mode after ``t`` from ``(x, v, F)``: ``(modes, v_p, F_p)`` of the
        probe that decided (a guessed mode first, then the full search, longer probes when
        one fails, keeps the mode at a guard or returns to a mode left twice at ``t``),
        the elements held at rate 0 put on their locks; or the failure message.

        A mode held at ``t`` twice and left there twice (no accepted step between: each
        step in it crossed a guard at ``t`` itself, :meth:`_note_left`) is not chosen again
        at ``t``: the choice cycles, and the probe that reads that mode is too short to
        decide (issue 29). One return is left alone (a string that goes taut at ``t`` and
        slack again at once is kept slack, its guard read as a tangency).

        Two dashpots reach their yield forces together under a load that grows past
        their joint yield force (a Herschel-Bulkley ``n = 0.8`` dashpot to ground beside
        a Bingham one to a junction held by a third): over a probe of ``2e-12`` s the
        load beyond it is ``1e-11``, below the round-off of the Bingham force, which
        reads stuck, while the Herschel-Bulkley one, flat in its inverse form, reads
        slipping at a rate of ``1e-17``. Held, that mode put the whole load on the
        Bingham dashpot, whose guard crossed at ``t``, and the next probe read both stuck
        (the locks in parallel hold the slipping one at its rate of ``1e-23``), whose
        guard crossed at ``t`` too: 50 events at one ``t`` and a backward-Euler bridge.
        A probe of ``2e-6`` s reads both slipping.

        When no probe up to ``10^6`` times the first reads another mode, the shortest
        probe's mode and state are taken (the longest one's gave a junction hung on a
        loaded mass by stuck dashpots its velocity ``2e-7`` s later: the step's start off
        its stages, whose dense output crossed a guard at ``c_1 h``, 12 bridges); where no
        probe reads a mode not left twice at ``t``, as a kept one (``returned``: the driver
        reads its guards crossed at ``t`` as a tangency's round-off). A mass stuck by two
        dashpots in parallel, one at its yield force, below their joint yield load: probes of
        ``6e-9`` and ``6e-6`` s keep it stuck, one of ``6e-3`` s looks past the time the load
        reaches it and reads both slipping, and a short one from there both stuck again."""
        scene, lbs, modes = self.scene, self.lbs, self.modes
        h0 = h_probe
        left = {m for m, (_, n) in self.left.items() if n >= 2} - {tuple(modes)}
        self.returned = False

        def undecided(got: tuple) -> bool:
            # the mode kept at a guard, or one left twice at t before
            return (cause == "guard" and got[0] == modes) or tuple(got[0]) in left

        guess, used = self._guesses(cause, x, v, F), self.decided
        used[:] = [h0]
        sel = (try_modes(scene, lbs, guess, t, x, v, F, h_probe,
                         modes if cause == "guard" else None, 3, self.fast, used=used)
               if guess else None) or ""
        if sel:
            sel = self._locked(sel, h_probe, x)
            if undecided(sel):  # the locks undid the guess, or a mode left twice at t
                sel = ""
        first, h_first = None, h0  # the shortest probe's mode and size
        for _ in range(0 if sel else 3):
            sel = select_modes(scene, lbs, t, x, v, F, h_probe, self.settings.options)
            if not isinstance(sel, str):
                # (a mode the locks below turn back into the old one is undecided too: a
                # slow break-out of locks in parallel under a load just past their joint
                # yield force moves the probe by less than its round-off, issue 11)
                sel = self._locked(sel, h_probe, x)
                if first is None:
                    first, h_first = sel, h_probe
                if not undecided(sel):
                    used.append(h_probe)
                    break
            h_probe *= 1000.0  # a failed or undecided probe: a longer one
        if first is not None and not isinstance(sel, str) and undecided(sel):
            used.append(h_first)  # no probe reads another mode: the shortest probe's
            self.returned = bool(left)
            return first
        if isinstance(sel, str):
            # every probe failed: shorter ones (Newton diverged from 4e-9 s on and converged
            # at 1e-10 s at a junction's HB n = 0.3 dashpot beside locks; issue 11)
            for k in (1, 2):
                h_short = max(h0 * 1e-2**k, 1e2 * _EPS * max(1.0, abs(t)))
                got = select_modes(scene, lbs, t, x, v, F, h_short, self.settings.options)
                if not isinstance(got, str):
                    return self._locked(got, h_short, x)
        if isinstance(sel, str) and cause == "guard" and self.cones:
            # ... and the guessed modes, locks in parallel by the minimum-norm correction
            # (a junction's HB n = 0.3 dashpot stopping at its kink beside two stuck links:
            # the full laws' Newton diverged at every probe size from 1e-12 to 1e-6 s)
            guess = self._guesses(cause, x, v, F, cones=True)
            got = try_modes(scene, lbs, guess, t, x, v, F, h0, modes, 3, None,
                            min_norm=True) if guess else None
            if got is not None:
                return self._locked(got, h0, x)
        return sel

    def _locked(self, sel: tuple, h_probe: float,
                x: list[float]) -> tuple[list[int], list[float], list[float]]:
        """The probe's ``(modes, v_p, F_p)`` (``h_probe`` its size, from positions ``x``)
        with the dashpots it leaves at rate 0 on their locks
        (:func:`~lumped.solvers.modes.probe_locks.lock_probe_rates`)."""
        new, F_p = lock_probe_rates(self.scene, self.lbs, sel[0], sel[1], sel[2], x, h_probe,
                                    self.m_min)
        return new, sel[1], F_p

    def _guesses(self, cause: str, x: list[float], v: list[float], F: list[float],
                 cones: bool = False) -> list[list[int]]:
        """The modes to try before the full search: at the start the branches the laws
        read at the initial state; after a guard crossing, the landed element on each of
        its other branches (every watched element when the driver gave no hint and there
        are at most 3); at a time event the mode kept first. None with locks in parallel
        (their probe is singular), unless ``cones`` (the minimum-norm fallback)."""
        if not self.guessing or (self.cones and not cones):
            return []
        if cause == "start":  # (then each element with branches on its others: a force
            q = self.scene.elongations(x, v)  # at a yield limit reads as the lock)
            read = [self.lbs[e].branch(q[e], F[e]) for e in range(self.E)]
            multi = [e for e in range(self.E) if self.lbs[e].count > 1]
            return [read] + [[b if k == e else m for k, m in enumerate(read)] for e in
                             (multi if len(multi) <= 3 else []) for b in
                             range(self.lbs[e].count) if b != read[e]]
        hint, self.hint = self.hint, None
        elements = [hint] if hint is not None else (
            list(self.watched) if len(self.watched) <= 3 else [])
        out = [list(self.modes)] if cause == "time" else []
        for e in elements:
            for b in range(self.lbs[e].count):
                if b != self.modes[e]:
                    out.append([b if k == e else m for k, m in enumerate(self.modes)])
        return out

    def at_event(self, t: float, h: float, cause: str, x: list[float], v: list[float],
                 F: list[float]) -> tuple[Status, str] | None:
        """The mode after an event at ``t``; ``(status, message)`` if the run must stop."""
        msg = self.change_mode(t, max(1e-7 * h, 1e3 * _EPS * max(1.0, abs(t))), cause,
                               x, v, F)
        self.forces_from_probe = True
        if not msg:  # forces not unique from the event on (locks on cycles)
            self.mark_free(t, t, x, v, F)
        self.stats["events"] = len(self.events)
        if msg:
            return Status.INCONSISTENT, msg
        if accumulating(self.recent, self.zeno_window) or \
                len(self.events) - self.time_events > self.opts["max_events"]:
            return too_many(self.events, self.recent, t, self.opts, self.time_events)
        return None

    def time_event(self, t: float) -> None:
        """Record a time event of the forcing at ``t`` (not counted in ``max_events``:
        the forcing's own jumps are as many as it has)."""
        self.time_events += 1
        self.events.append(Event(t, "", "time", -1, -1))
        self.recent.append(t)

    def mark_free(self, t0: float, t1: float, x: list[float], v: list[float],
                  F: list[float]) -> None:
        """Log the elements whose forces are not unique on ``[t0, t1]`` (locks on cycles)."""
        if self.cyclic:
            free = indeterminate_elements(self.scene, self.scene.elongations(x, v), F,
                                          self.cyclic)
            self.log.mark(t0, t1, [self.names[e] for e in free])
