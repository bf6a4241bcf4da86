r"""``radau5`` on a scene at rest for its whole span: held intervals alone, no steps.

A scene whose every node is a mass starting at rest (``v0 = 0``), under forcings that are
absent, constant or sine bursts, whose consistent initial forces hold it still (every
element's law is monotone, every element with more than one branch reads its locking
branch, the locks hold every node on a regular incidence matrix) with each guard above
its round-off tolerance by a margin, at the initial load and at the load at the end of
the driver's start probe (:func:`~lumped.solvers.eventdriven.mode_parts.rest_mode`):
the adaptive run chooses that mode at ``t = 0`` (its probe confirms the mode read off
the state) and holds it (:func:`lumped.solvers.modes.stuck.hold_interval`) up to each
time event of the forcing (a burst's end) and on to ``t_end``. :func:`rest_run` builds
that run directly: the same consistent initial state, the same static balance
(:func:`~lumped.solvers.modes.stuck.static_hold`: its break-out scan, dense segments and
output rows), the same time events (the full laws choose the mode there by the driver's
own :meth:`~lumped.solvers.eventdriven.mode_state.ModeState.at_event`, whose probe sets
the forces), the same counters; the driver's set-up (stage system, compiled loop) is
skipped, and ``stats["loop"]`` says that no loop ran. Anything else returns ``None`` and
the general driver runs: a velocity, another kind of forcing, a force at or near its
yield limit, a break-out found by the scan, a mode that changes at a time event,
junctions, laws with folds, locks in parallel.
"""

from __future__ import annotations

import numpy as np

from ...grid import steps_for
from ...scene import Mass, Scene
from ..implicit.initial_state import consistent_initial_state
from ..modes.stuck import forcing_kinds, static_hold
from ..radau.dense import DenseOutput
from ..radau.error import initial_step
from ..radau.rows import Rows, output_data, row_of
from ..status import RawRun, Status
from .mode_parts import rest_mode
from .mode_state import ModeState
from .run import DEFAULT_ATOL, DEFAULT_RTOL
from .setup import breakpoints, read_options, scene_plan

__all__ = ["REST_LOOP", "rest_run"]

#: ``stats["loop"]`` of a run held at rest throughout (no loop ran).
REST_LOOP = "none: at rest throughout (no steps)"


def _candidate(scene: Scene, plan) -> bool:
    """The scene's structure admits a run at rest (kept on ``plan``): every node a mass,
    every law known monotone (the driver then tries the mode read off the state first),
    every forcing absent, constant or a sine burst (the static balance's kinds)."""
    got = plan.__dict__.get("at_rest_candidate")
    if got is None:
        got = plan.__dict__["at_rest_candidate"] = (
            plan.refused is None and not plan.checked
            and all(isinstance(nd, Mass) for nd in scene.nodes)
            and forcing_kinds(scene, plan)[0] is not None)
    return got


def rest_run(scene: Scene, settings) -> RawRun | None:
    """The ``radau5`` run of a scene at rest on ``[0, t_end]`` (see the module notes), or
    ``None`` when the scene is not proven at rest (the general driver,
    :class:`lumped.solvers.eventdriven.run.Radau5Run`, runs it)."""
    plan = scene_plan(scene)
    if not _candidate(scene, plan) or any(nd.v0 != 0.0 for nd in scene.nodes):
        return None
    opts = read_options(settings)  # (a bad keyword raises as in the general driver)
    dt = settings.dt
    t_final = settings.t_end if dt is None else max(settings.t_end,
                                                     steps_for(dt, settings.t_end) * dt)
    x = [float(nd.x0) for nd in scene.nodes]
    v, F, ic = consistent_initial_state(scene, time_scale=t_final, options=settings.options)
    q = scene.elongations(x, v)
    got = rest_mode(scene, plan, q, F)
    if got is None:
        return None
    modes, guards = got
    fkind, fpar = forcing_kinds(scene, plan)
    hold = static_hold(scene, plan, modes, x, v, F, fkind, fpar)
    if hold is None:
        return None
    # the start's probe reads the mode at the balance under the load at its end
    F_p = hold.forces(1e-9 * t_final)
    if F_p != F and (rest_mode(scene, plan, q, F_p) or (None,))[0] != modes:
        return None
    rtol = DEFAULT_RTOL if settings.rtol is None else settings.rtol
    atol = DEFAULT_ATOL if settings.atol is None else settings.atol
    stats = {"steps": 0, "rejected": 0, "newton_iterations": 0, "factorizations": 0,
             "nfev": 0, "njev": 0, "events": 0, "max_newton_iterations": 0,
             "initial_newton_iterations": ic["newton_iterations"], "held_intervals": 0,
             "loop": REST_LOOP}
    ms = ModeState(scene, plan, settings, opts, rtol, atol, stats,
                   opts["zeno_window"] or 1e-6 * t_final)
    ms.set_modes(list(modes), F)
    breaks = breakpoints(scene, t_final)
    h = _first_step(scene, x, v, F, opts, rtol, atol, t_final) if breaks else 0.0
    dense = DenseOutput(len(x), len(F))
    rows = [row_of(0.0, x, v, F)]
    t = 0.0
    for t1 in [*breaks, t_final]:
        if t > 0.0:  # a time event at t: the full laws choose the mode (the probe's forces)
            ms.time_event(t)
            if ms.at_event(t, h, "time", x, v, F) or ms.modes != list(modes):
                return None
            hold = static_hold(scene, plan, modes, x, v, F, fkind, fpar)
        F1 = hold.forces(t1)
        if (hold.varying or F1 != F or t > 0.0) and \
                hold.breakout(t, t1, guards, modes, refine=False)[0] is not None:
            return None  # (steady forces equal to the initial ones: checked with the margin)
        dense.add_static(t, t1, hold)
        rows += [row_of(s, x, v, hold.forces(s)) for s in hold.samples(t, t1) if s < t1]
        rows.append(row_of(t1, x, v, F1))
        ms.mark_free(t, t1, x, v, F1)
        stats["held_intervals"] += 1
        t, F = t1, list(F1)
    data = np.array(rows, dtype=float)
    if dt is not None:  # the dense output on t_n = n dt
        out = Rows()
        out.extend(data)
        data = output_data(out, dense, dt, settings.t_end, t_final)
    stats["events"] = len(ms.events)
    return RawRun(data, stats, Status.SUCCESS, "", ms.events, dense,
                  indeterminate=ms.log.result())


def _first_step(scene: Scene, x: list[float], v: list[float], F: list[float], opts: dict,
                rtol: float, atol: float, t_final: float) -> float:
    """The driver's first step size (the scale of its event probes)."""
    net = scene.net_forces(0.0, F)
    masses = scene.masses
    acc0 = [net[i] / masses[i] for i in range(len(x))]
    return opts["first_step"] or initial_step(x, v, acc0, [True] * len(x), rtol, atol,
                                              t_final)
