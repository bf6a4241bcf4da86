r"""The held intervals of a run at rest under sine bursts, and the time events between them.

A run at rest (:mod:`lumped.solvers.eventdriven.at_rest`) under sine bursts below yield
holds the mode of its start from one time event of the forcing (a burst's end) to the
next, as the driver does (:meth:`~lumped.solvers.eventdriven.run.Radau5Run._hold`): each
interval is the static balance (:class:`~lumped.solvers.modes.stuck.StaticHold`), whose
break-out scan must find no guard crossed (:meth:`~lumped.solvers.modes.stuck.
StaticHold.breakout`, the first failing sample, not refined), with its output rows at
the scan's samples; at each time event the driver's first guess, the mode held, must be
confirmed by its probe (:func:`~lumped.solvers.modes.mode_guess.try_modes`), whose forces
the next interval holds. The scan and the probe run compiled where the driver has its
compiled loop (the same numbers as in Python).

The interval up to the first time event reads nothing of the run but its end: it is kept
on the run's :class:`~lumped.solvers.eventdriven.rest_start.RestStart` (its rows, forces
and verdict). Once every burst has ended the forcing is steady: the balance from a force
state (the probe's) has the same forces at every later time, and its forces and verdict
are kept there too, per force state, bit for bit. A time event's probe reads the start,
its time, the run's first step size ``h``, the forces it starts from and whether it runs
compiled: its forces (or its refusal) are kept there per those; so are the forcing's time
events and the start probe's verdict per end of the run, and ``h`` per tolerances, first
step and end. Repeated runs of one scene make the rows of their own samples.
"""

from __future__ import annotations

import struct

import numpy as np

from ...scene import Scene
from ..modes.mode_guess import lock_rows, try_modes
from ..modes.stuck import StaticHold, forcing_kinds, static_hold
from ..nonsmooth.locks import IntervalLog, indeterminate_elements
from ..radau.dense import DenseOutput
from ..radau.error import initial_step
from ..radau.rows import row_of
from ..status import Event
from .fast import compiled_loop
from .mode_parts import holds_at, mode_parts, rest_mode
from .rest_start import RestStart
from .run import DEFAULT_ATOL, DEFAULT_RTOL
from .setup import time_events

__all__ = ["burst_intervals", "free_names"]

_EPS = 2.220446049250313e-16

#: A held interval: its static balance, output rows (after its start), forces at its
#: end, and the elements whose forces are not unique there.
_Held = tuple[StaticHold, np.ndarray, list[float], list[str]]


def burst_intervals(scene: Scene, plan, settings, opts: dict, start: RestStart,
                    t_final: float, events: list[Event], log: IntervalLog | None
                    ) -> tuple[np.ndarray, DenseOutput, int] | None:
    """The held intervals of a run at rest under sine bursts (see the module notes), the
    time events appended to ``events``, the elements whose forces are not unique to
    ``log``: ``(data, dense output, intervals)``, or ``None`` when the general driver
    must run (a guard crossed in a scan, a mode not confirmed at a time event, a kink of
    the forcing, as many time events as ``zeno_events``)."""
    # (the forcing's time events and the start probe's verdict read the start and the
    # run's end only: kept on the start per end)
    breaks, kinks = start.kept_interval(("events", t_final),
                                        lambda: time_events(scene, t_final))
    if any(kinks) or len(breaks) >= opts["zeno_events"]:
        return None
    x, v, modes = start.x, start.v, start.modes
    # the start's probe reads the mode at the balance under the load at its end (the
    # probe's forces are those to round-off, which the margin covers)
    if not start.kept_interval(("start probe", t_final), lambda: _start_probe_holds(
            scene, plan, start, start.hold.balance(1e-9 * t_final))):
        return None
    fast = _rest_loop(scene, plan, opts["compiled"])
    dense = DenseOutput(len(x), len(start.F))
    blocks = [start.row0]
    t, F, h = 0.0, start.F, 0.0
    for t1 in [*breaks, t_final]:
        if t > 0.0:  # a time event: the full laws choose the mode (the probe's forces)
            events.append(Event(t, "", "time", -1, -1))
            h = h or start.kept_interval(
                ("h", settings.rtol, settings.atol, opts["first_step"], t_final),
                lambda: _first_step(settings, opts, start, t_final))
            # (the probe reads the start, t, h, F and which probe runs: kept per those)
            F = start.kept_interval(
                ("probe", t, h, struct.pack(f"{len(F)}d", *F), fast is not None),
                lambda t=t, h=h, F=F: _kept_at_time_event(scene, plan, modes, t, h, x, v,
                                                          F, fast))
            if F is None:
                return None
            if log is not None:
                log.mark(t, t, free_names(scene, plan, start, F))
            seg = (_after_bursts(scene, plan, start, F, t, t1) if t >= start.last_off
                   else _held(scene, plan, start, _hold_of(scene, plan, start, F), t, t1,
                              fast))
        elif breaks:  # up to the first time event: the same in every run that reaches it
            seg = start.kept_interval(("first", t1, fast is not None), lambda t1=t1: _held(
                scene, plan, start, start.fresh_hold(scene, plan), 0.0, t1, fast))
        else:
            seg = _held(scene, plan, start, start.fresh_hold(scene, plan), 0.0, t1, fast)
        if seg is None:
            return None
        hold, block, F1, free = seg
        dense.add_static(t, t1, hold)
        blocks.append(block)
        if log is not None:
            log.mark(t, t1, free)
        t, F = t1, F1
    return np.concatenate(blocks), dense, len(breaks) + 1


def free_names(scene: Scene, plan, start: RestStart, F: list[float]) -> list[str]:
    """The elements whose forces are not unique at rest under the forces ``F`` (as
    :meth:`~lumped.solvers.eventdriven.mode_state.ModeState.mark_free` logs them)."""
    return [scene.element_names[e]
            for e in indeterminate_elements(scene, start.q, F, plan.cyclic)]


def _hold_of(scene: Scene, plan, start: RestStart, F: list[float]) -> StaticHold | None:
    """The static balance of the start's mode from the forces ``F``."""
    fkind, fpar = forcing_kinds(scene, plan)
    return static_hold(scene, plan, start.modes, start.x, start.v, F, fkind, fpar)


def _after_bursts(scene: Scene, plan, start: RestStart, F: list[float], t: float,
                  t1: float) -> _Held | None:
    """The held interval ``[t, t1]`` from the forces ``F`` once every burst has ended
    (``t >= start.last_off``): the forcing is steady, so every sample of the scan has the
    same forces, those of the balance (its verdict and those forces kept on ``start`` per
    ``F``, bit for bit: the balance reads nothing else); the rows at the scan's samples
    (:meth:`~lumped.solvers.modes.stuck.StaticHold.samples`) are kept there per ``F``,
    ``t`` and ``t1`` (only read: the run's ``data`` is a copy)."""
    key = ("after", struct.pack(f"{len(F)}d", *F))
    got = start.kept_interval(key, lambda: _held(scene, plan, start,
                                                 _hold_of(scene, plan, start, F), t, t1, None))
    if got is None:
        return None
    hold, block, F1, free = got
    return hold, start.kept_interval((*key, t, t1), lambda: _rows(hold, block, t, t1)), F1, free


def _rows(hold: StaticHold, block: np.ndarray, t: float, t1: float) -> np.ndarray:
    """The rows of a steady held interval ``[t, t1]`` at its scan's samples: the last row
    of ``block`` at each sample's time."""
    times = [s for s in hold.samples(t, t1) if s < t1] + [t1]
    rows = np.empty((len(times), block.shape[1]))
    rows[:] = block[-1]
    rows[:, 0] = times
    return rows


def _held(scene: Scene, plan, start: RestStart, hold: StaticHold | None, t: float,
          t1: float, fast) -> _Held | None:
    """The held interval ``[t, t1]`` of ``hold``, or ``None`` when there is none or its
    scan finds a guard crossed (as :func:`lumped.solvers.modes.stuck.hold_interval`)."""
    if hold is None:
        return None
    x, v = start.x, start.v
    t_b, samples = hold.breakout(t, t1, start.guards, start.modes, fast, refine=False)
    if t_b is not None:
        return None
    F1 = hold.forces(t1)
    block = np.array([row_of(s, x, v, hold.forces(s)) for s in samples if s < t1]
                     + [row_of(t1, x, v, F1)], dtype=float)
    return hold, block, F1, free_names(scene, plan, start, F1) if start.may_be_free else []


def _start_probe_holds(scene: Scene, plan, start: RestStart, F_probe: list[float]
                       ) -> bool:
    """Whether the mode read off the start holds at the probe's load, ``F_probe``, beyond
    round-off (:func:`~lumped.solvers.eventdriven.mode_parts.rest_mode`): read anew only
    for the elements whose forces differ from the start's, when there are no cones (fewer
    than two locks on cycles: the rest of :func:`rest_mode` reads the mode alone)."""
    modes = start.modes
    if F_probe == start.F:
        return True
    if mode_parts(plan, modes)[3] >= 2:
        return (rest_mode(scene, plan, start.q, F_probe) or (None,))[0] == modes
    changed = [e for e, (a, b) in enumerate(zip(F_probe, start.F, strict=True)) if a != b]
    return holds_at(plan, modes, start.q, F_probe, changed)


def _kept_at_time_event(scene: Scene, plan, modes: tuple[int, ...], t: float, h: float,
                        x: list[float], v: list[float], F: list[float], fast
                        ) -> list[float] | None:
    """The forces after a time event at ``t`` if the driver keeps ``modes`` there, else
    ``None``: its first guess at a time event is the mode held
    (:meth:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode`), confirmed by
    the probe of size ``max(1e-7 h, 1e3 eps max(1, t))`` (``h`` the run's first step),
    whose forces it takes. (Its locks' corrections, ``prefer_locks`` and
    ``lock_parallel_rates``, change only dashpots off a lock, and every element of
    ``modes`` with more than one branch is on one; the probe's velocities are those of
    the masses at rest.) With ``fast``, the compiled probe of
    :func:`~lumped.solvers.modes.mode_guess.try_modes` with one candidate and one size
    (a scene at rest has no moving supports to set the time of)."""
    h_p = max(1e-7 * h, 1e3 * _EPS * max(1.0, abs(t)))
    if fast is None or not fast.can_probe():  # (the compiled probe: once compiled)
        got = try_modes(scene, plan.branches, [list(modes)], t, x, v, F, h_p)
        return None if got is None else got[2]
    f = scene.external_forces(t + h_p)
    with plan.lock:  # (the loop's probe workspace is shared by the runs at rest)
        k, out = fast.probe_modes([list(modes)], None, f, x, v, F, h_p,
                                  lock_rows(scene, plan.branches, [modes], x))
        return out[len(x):].tolist() if k >= 0 else None


def _rest_loop(scene: Scene, plan, option: bool | None):
    """The compiled loop the driver would run (:func:`~lumped.solvers.eventdriven.fast.
    compiled_loop` with the ``compiled`` keyword ``option``), or ``None``; kept on ``plan``
    for the runs at rest, which use its scan and its probe only."""
    if option is False:
        return None
    got = plan.__dict__.get("rest_loop")
    if got is None:
        got = compiled_loop(scene, plan, option)[0]
        if got is not None:
            plan.__dict__["rest_loop"] = got
    return got


def _first_step(settings, opts: dict, start: RestStart, t_final: float) -> float:
    """The driver's first step size (the scale of its event probes)."""
    rtol = DEFAULT_RTOL if settings.rtol is None else settings.rtol
    atol = DEFAULT_ATOL if settings.atol is None else settings.atol
    return opts["first_step"] or initial_step(start.x, start.v, start.acc0,
                                              [True] * len(start.x), rtol, atol, t_final)
