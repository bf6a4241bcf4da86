r"""``radau5`` on a scene at rest for its whole span: the held interval ``[0, t_end]`` alone.

A scene whose every node is a mass starting at rest (``v0 = 0``), under no forcing or
constant forces only, whose consistent initial forces hold it still (every element's law
is monotone, every element with more than one branch reads its locking branch, the
locks hold every node on a regular incidence matrix) with each guard above its
round-off tolerance by a margin (:func:`~lumped.solvers.eventdriven.mode_parts.
rest_mode`), never moves: the adaptive run would choose that mode at
``t = 0`` (its probe confirms the mode read off the state, the locks keep it) and take
one held interval (:func:`lumped.solvers.modes.stuck.hold_interval`) to ``t_end``, whose
scan finds no break-out. :func:`rest_run` builds that run directly: the same consistent
initial state, the same static balance (:func:`~lumped.solvers.modes.stuck.static_hold`,
its break-out scan, dense segment and output rows), the same counters; the run's
set-up (stage system, mode state, compiled loop, first step) is skipped, and
``stats["loop"]`` says that no loop ran. Anything else (a velocity, a varying or
switched forcing, a force at or near its yield limit, junctions, laws with folds, locks
in parallel) returns ``None`` and the general driver runs.
"""

from __future__ import annotations

import numpy as np

from ...grid import steps_for
from ...scene import Mass, Scene
from ..implicit.initial_state import consistent_initial_state
from ..modes.stuck import forcing_kinds, static_hold
from ..nonsmooth.locks import IntervalLog, indeterminate_elements
from ..radau.dense import DenseOutput
from ..radau.rows import Rows, output_data, row_of
from ..status import RawRun, Status
from .mode_parts import rest_mode
from .setup import read_options, scene_plan

__all__ = ["REST_LOOP", "rest_run"]

#: ``stats["loop"]`` of a run held at rest throughout (no loop ran).
REST_LOOP = "none: at rest throughout (no steps)"


def _candidate(scene: Scene, plan) -> bool:
    """The scene's structure admits a run at rest (kept on ``plan``): every node a mass,
    every law known monotone (the driver then tries the mode read off the state first),
    the forcing absent or constant."""
    got = plan.__dict__.get("at_rest_candidate")
    if got is None:
        fkind, _ = forcing_kinds(scene, plan)
        got = plan.__dict__["at_rest_candidate"] = (
            plan.refused is None and not plan.checked
            and all(isinstance(nd, Mass) for nd in scene.nodes)
            and fkind is not None and bool((fkind <= 1).all()))
    return got


def rest_run(scene: Scene, settings) -> RawRun | None:
    """The ``radau5`` run of a scene at rest on ``[0, t_end]`` (see the module notes), or
    ``None`` when the scene is not proven at rest (the general driver,
    :class:`lumped.solvers.eventdriven.run.Radau5Run`, runs it)."""
    plan = scene_plan(scene)
    if not _candidate(scene, plan) or any(nd.v0 != 0.0 for nd in scene.nodes):
        return None
    read_options(settings)  # (its checks: a bad keyword raises as in the general driver)
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
    F1 = hold.forces(t_final)  # (the forcing is steady: the forces of every time)
    if F1 != F and hold.breakout(0.0, t_final, guards, modes)[0] is not None:
        return None  # (F: a user's F0 off the balance; F1 itself is checked by the scan)
    samples = hold.samples(0.0, t_final)
    dense = DenseOutput(len(x), len(F))
    dense.add_static(0.0, t_final, hold)
    data = np.array([row_of(0.0, x, v, F)]
                    + [row_of(s, x, v, hold.forces(s)) for s in samples if s < t_final]
                    + [row_of(t_final, x, v, F1)], dtype=float)
    if dt is not None:  # the dense output on t_n = n dt
        rows = Rows()
        rows.extend(data)
        data = output_data(rows, dense, dt, settings.t_end, t_final)
    indeterminate: dict = {}
    if plan.cyclic:  # locks on cycles whose forces are not unique
        log = IntervalLog()
        free = indeterminate_elements(scene, q, F1, plan.cyclic)
        log.mark(0.0, t_final, [scene.element_names[e] for e in free])
        indeterminate = log.result()
    stats = {"steps": 0, "rejected": 0, "newton_iterations": 0, "factorizations": 0,
             "nfev": 0, "njev": 0, "events": 0, "max_newton_iterations": 0,
             "initial_newton_iterations": ic["newton_iterations"], "held_intervals": 1,
             "loop": REST_LOOP}
    return RawRun(data, stats, Status.SUCCESS, "", [], dense, indeterminate=indeterminate)

