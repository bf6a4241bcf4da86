r"""``radau5`` on a scene at rest for its whole span: held intervals alone, no steps.

A scene whose every node is a mass starting at rest (``v0 = 0``), under forcings that are
absent, constant or sine bursts, whose consistent initial forces hold it still (every
element's law is monotone, every element with more than one branch reads its locking
branch, the locks hold every node on a regular incidence matrix) with each guard above
its round-off tolerance by a margin (:func:`~lumped.solvers.eventdriven.mode_parts.
rest_mode`), at the initial load and, under a sine burst, at the load at the end of the
start's probe, never moves: the adaptive run chooses that mode at ``t = 0`` (its probe
confirms the mode read off the state, the locks keep it) and holds it
(:func:`lumped.solvers.modes.stuck.hold_interval`) up to each time event of the forcing
(a burst's end) and on to ``t_end``, as long as the break-out scan of each held interval
finds no guard crossed and the full laws keep the mode at each time event.

:func:`rest_run` builds that run directly: the same start
(:func:`~lumped.solvers.eventdriven.rest_start.rest_start`, kept per scene), the same
static balance (:func:`~lumped.solvers.modes.stuck.static_hold`: its break-out scan,
dense segments and output rows), the same time events (each with the driver's mode probe
on the mode held, :func:`~lumped.solvers.modes.mode_guess.try_modes`, whose forces the
next interval holds), the same counters; the driver's set-up (stage system, mode state,
compiled loop, first step) is skipped, and ``stats["loop"]`` says that no loop ran.
Anything else returns ``None`` and the general driver runs: a velocity, another kind of
forcing, a force at or near its yield limit, a guard crossed in the scan, a mode the
probe does not confirm at a time event, junctions, laws with folds, locks in parallel.
"""

from __future__ import annotations

import numpy as np

from ...grid import steps_for
from ...scene import Mass, Scene
from ..modes.mode_guess import try_modes
from ..modes.stuck import forcing_kinds, static_hold
from ..nonsmooth.locks import IntervalLog, indeterminate_elements
from ..radau.dense import DenseOutput
from ..radau.error import initial_step
from ..radau.rows import Rows, output_data, row_of
from ..status import Event, RawRun, Status
from .fast import compiled_loop
from .mode_parts import rest_mode
from .rest_start import RestStart, rest_start
from .run import DEFAULT_ATOL, DEFAULT_RTOL
from .setup import read_options, scene_plan, time_events

__all__ = ["REST_LOOP", "rest_run"]

#: ``stats["loop"]`` of a run held at rest throughout (no loop ran).
REST_LOOP = "none: at rest throughout (no steps)"

_EPS = 2.220446049250313e-16


def _candidate(scene: Scene, plan) -> bool:
    """The scene's structure admits a run at rest (kept on ``plan``): every node a mass,
    every law known monotone (the driver then tries the mode read off the state first),
    every forcing absent, constant or a sine burst (the static balance's kinds)."""
    got = plan.__dict__.get("at_rest_candidate")
    if got is None:
        fkind, _ = forcing_kinds(scene, plan)
        got = plan.__dict__["at_rest_candidate"] = (
            plan.refused is None and not plan.checked
            and all(isinstance(nd, Mass) for nd in scene.nodes)
            and fkind is not None)
    return got


def rest_run(scene: Scene, settings) -> RawRun | None:
    """The ``radau5`` run of a scene at rest on ``[0, t_end]`` (see the module notes), or
    ``None`` when the scene is not proven at rest (the general driver,
    :class:`lumped.solvers.eventdriven.run.Radau5Run`, runs it)."""
    plan = scene_plan(scene)
    if not _candidate(scene, plan) or any(nd.v0 != 0.0 for nd in scene.nodes):
        return None
    opts = read_options(settings)  # (its checks: a bad keyword raises as in the driver)
    dt = settings.dt
    t_final = settings.t_end if dt is None else max(settings.t_end,
                                                     steps_for(dt, settings.t_end) * dt)
    start = rest_start(scene, plan, t_final, settings.options)
    if start is None:
        return None
    events: list[Event] = []
    # the elements on cycles whose forces are not unique, logged as the driver does
    log = IntervalLog() if plan.cyclic else None
    if start.varying:
        got = _burst_intervals(scene, plan, settings, opts, start, t_final, events, log)
        if got is None:
            return None
        rows, dense, held = got
    else:  # one held interval; the steady forces of every t > 0
        x, v, F1 = start.x, start.v, start.F_end
        dense = DenseOutput(len(x), len(F1))
        dense.add_static(0.0, t_final, start.hold)
        # (the scan's samples of a steady forcing: t_final / 2 and t_final)
        rows = [row_of(0.0, x, v, start.F), row_of(0.5 * t_final, x, v, F1),
                row_of(t_final, x, v, F1)]
        _mark_free(scene, plan, log, 0.0, t_final, start, F1)
        held = 1
    data = np.array(rows, dtype=float)
    if dt is not None:  # the dense output on t_n = n dt
        out = Rows()
        out.extend(data)
        data = output_data(out, dense, dt, settings.t_end, t_final)
    stats = {"steps": 0, "rejected": 0, "newton_iterations": 0, "factorizations": 0,
             "nfev": 0, "njev": 0, "events": len(events), "max_newton_iterations": 0,
             "initial_newton_iterations": start.newton_iterations, "held_intervals": held,
             "loop": REST_LOOP}
    return RawRun(data, stats, Status.SUCCESS, "", events, dense,
                  indeterminate={} if log is None else log.result())


def _mark_free(scene: Scene, plan, log: IntervalLog | None, t0: float, t1: float,
               start: RestStart, F: list[float]) -> None:
    """Log the elements whose forces are not unique on ``[t0, t1]`` at the forces ``F``
    (as :meth:`~lumped.solvers.eventdriven.mode_state.ModeState.mark_free`)."""
    if log is not None:
        free = indeterminate_elements(scene, start.q, F, plan.cyclic)
        log.mark(t0, t1, [scene.element_names[e] for e in free])


def _burst_intervals(scene: Scene, plan, settings, opts: dict, start: RestStart,
                     t_final: float, events: list[Event], log: IntervalLog | None
                     ) -> tuple[list[list[float]], DenseOutput, int] | None:
    """The held intervals of a run at rest under sine bursts, between the forcing's time
    events (appended to ``events``; the elements whose forces are not unique in ``log``):
    ``(rows, dense output, intervals)``, or ``None`` when
    the general driver must run (a guard crossed in a scan, a mode not confirmed at a time
    event, a kink of the forcing, as many time events as ``zeno_events``)."""
    breaks, kinks = time_events(scene, t_final)
    if any(kinks) or len(breaks) >= opts["zeno_events"]:
        return None
    x, v, modes, guards = start.x, start.v, start.modes, start.guards
    hold = start.fresh_hold(scene, plan)
    # the start's probe reads the mode at the balance under the load at its end (the
    # probe's forces are those to round-off, which the margin covers)
    F_probe = hold.forces(1e-9 * t_final)
    if F_probe != start.F and (rest_mode(scene, plan, start.q, F_probe) or (None,))[0] \
            != modes:
        return None
    h = _first_step(scene, settings, opts, start, t_final) if breaks else 0.0
    # the driver's compiled loop where it has one (its scan and probes, the same numbers)
    fast = compiled_loop(scene, plan, opts["compiled"])[0]
    fkind, fpar = forcing_kinds(scene, plan)
    dense = DenseOutput(len(x), len(start.F))
    rows = [row_of(0.0, x, v, start.F)]
    t, F = 0.0, start.F
    for t1 in [*breaks, t_final]:
        if t > 0.0:  # a time event: the full laws choose the mode (the probe's forces)
            events.append(Event(t, "", "time", -1, -1))
            F = _kept_at_time_event(scene, plan, modes, t, h, x, v, F, fast)
            if F is None:
                return None
            _mark_free(scene, plan, log, t, t, start, F)
            hold = static_hold(scene, plan, modes, x, v, F, fkind, fpar)
            if hold is None:
                return None
        t_b, samples = hold.breakout(t, t1, guards, modes, fast, refine=False)
        if t_b is not None:
            return None
        dense.add_static(t, t1, hold)
        F1 = hold.forces(t1)
        rows += [row_of(s, x, v, hold.forces(s)) for s in samples if s < t1]
        rows.append(row_of(t1, x, v, F1))
        _mark_free(scene, plan, log, t, t1, start, F1)
        t, F = t1, F1
    return rows, dense, len(breaks) + 1


def _kept_at_time_event(scene: Scene, plan, modes: tuple[int, ...], t: float, h: float,
                        x: list[float], v: list[float], F: list[float], fast=None
                        ) -> list[float] | None:
    """The forces after a time event at ``t`` if the driver keeps ``modes`` there, else
    ``None``: its first guess at a time event is the mode held
    (:meth:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode`), confirmed by
    the probe of size ``max(1e-7 h, 1e3 eps max(1, t))`` (``h`` the run's first step),
    whose forces it takes. (Its locks' corrections, ``prefer_locks`` and
    ``lock_parallel_rates``, change only dashpots off a lock, and every element of
    ``modes`` with more than one branch is on one; the probe's velocities are those of
    the masses at rest.)"""
    h_p = max(1e-7 * h, 1e3 * _EPS * max(1.0, abs(t)))
    got = try_modes(scene, plan.branches, [list(modes)], t, x, v, F, h_p, fast=fast)
    return None if got is None else got[2]


def _first_step(scene: Scene, settings, opts: dict, start: RestStart,
                t_final: float) -> float:
    """The driver's first step size (the scale of its event probes)."""
    rtol = DEFAULT_RTOL if settings.rtol is None else settings.rtol
    atol = DEFAULT_ATOL if settings.atol is None else settings.atol
    net = scene.net_forces(0.0, start.F)
    acc0 = [net[i] / nd.m for i, nd in enumerate(scene.nodes)]
    return opts["first_step"] or initial_step(start.x, start.v, acc0,
                                              [True] * len(start.x), rtol, atol, t_final)

