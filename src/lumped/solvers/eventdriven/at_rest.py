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
(:func:`~lumped.solvers.eventdriven.rest_start.rest_start`, kept per scene content), the
same static balance (:func:`~lumped.solvers.modes.stuck.static_hold`: its break-out scan,
dense segments and output rows), the same time events (each with the driver's mode probe
on the mode held, :func:`~lumped.solvers.modes.mode_guess.try_modes`, whose forces the
next interval holds; :mod:`lumped.solvers.eventdriven.rest_bursts`), the same counters;
the driver's set-up (stage system, mode state, compiled loop, first step) is skipped, and
``stats["loop"]`` says that no loop ran.
Anything else returns ``None`` and the general driver runs: a velocity, another kind of
forcing, a force at or near its yield limit, a guard crossed in the scan, a mode the
probe does not confirm at a time event, junctions, laws with folds, locks in parallel.
"""

from __future__ import annotations

import numpy as np

from ...grid import steps_for
from ...scene import Mass, Scene
from ..modes.stuck import forcing_kinds
from ..nonsmooth.locks import IntervalLog
from ..radau.dense import DenseOutput
from ..radau.rows import Rows, output_data
from ..status import Event, RawRun, Status
from .rest_bursts import burst_intervals, free_names
from .rest_start import rest_start
from .setup import read_options, scene_plan

__all__ = ["REST_LOOP", "rest_run"]

#: ``stats["loop"]`` of a run held at rest throughout (no loop ran).
REST_LOOP = "none: at rest throughout (no steps)"


def _candidate(scene: Scene, plan) -> bool:
    """The scene's structure admits a run at rest (kept on ``plan``): every node a mass
    starting at rest (``v0 = 0``), every law known monotone (the driver then tries the
    mode read off the state first), every forcing absent, constant or a sine burst (the
    static balance's kinds)."""
    got = plan.__dict__.get("at_rest_candidate")
    if got is None:
        fkind, _ = forcing_kinds(scene, plan)
        got = plan.__dict__["at_rest_candidate"] = (
            plan.refused is None and not plan.checked
            and all(isinstance(nd, Mass) and nd.v0 == 0.0 for nd in scene.nodes)
            and fkind is not None)
    return got


def rest_run(scene: Scene, settings) -> RawRun | None:
    """The ``radau5`` run of a scene at rest on ``[0, t_end]`` (see the module notes), or
    ``None`` when the scene is not proven at rest (the general driver,
    :class:`lumped.solvers.eventdriven.run.Radau5Run`, runs it)."""
    plan = scene_plan(scene)
    if not _candidate(scene, plan):
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
    log = IntervalLog() if start.may_be_free else None
    if start.varying:
        got = burst_intervals(scene, plan, settings, opts, start, t_final, events, log)
        if got is None:
            return None
        data, dense, held = got
    else:  # one held interval; the steady forces of every t > 0
        F1 = start.F_end
        dense = DenseOutput(len(start.x), len(F1))
        dense.add_static(0.0, t_final, start.hold)
        # (the scan's samples of a steady forcing, t_final / 2 and t_final: the row of
        # every t > 0 but its time)
        data = np.empty((3, start.row0.shape[1]))
        data[0] = start.row0[0]
        data[1:] = start.row_end
        data[1:, 0] = 0.5 * t_final, t_final
        if log is not None:
            log.mark(0.0, t_final, free_names(scene, plan, start, F1))
        held = 1
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
