r"""``radau5``: adaptive Radau IIA (order 5) with located switching and time events.

The driver of the adaptive method (the step is :mod:`lumped.solvers.radau.stage`, the event
logic :mod:`lumped.solvers.modes.choice` and :mod:`lumped.solvers.modes.lock_events`; the
reasons are in ``docs/theory/radau.md`` and ``docs/theory/events.md``):

1. the consistent initial state, and the initial mode by a vanishing implicit step;
2. steps of Radau IIA with every law held on its mode's branch (a smooth DAE), the step
   size from RADAU5's filtered error estimate on the differential components (``x`` of
   every node, ``v`` of every mass) with Gustafsson's predictive controller;
3. after an accepted step, the branch guards along the collocation polynomial: at the
   first crossing the step is redone to end on it, the next mode is chosen, and the
   event is recorded; a break of the forcing in time (``breakpoints(t0, t1)`` of a
   forcing object) is stepped to exactly and is a time event where the forcing may
   jump; at a kink (``kinks(t0, t1)``: a point of a record, where the forcing is
   continuous) the held mode goes on;
4. more than ``max_events`` events, or ``zeno_events`` events within ``zeno_window``
   seconds, stop the run with :attr:`Status.TOO_MANY_EVENTS`; a step below its floor stops
   it with :attr:`Status.STEP_TOO_SMALL`;
5. the work budget ``max_steps`` (default 1 000 000) counts every step tried (accepted,
   rejected, redone to land on an event, and the backward-Euler steps of bridges): spent,
   or at a pace that cannot reach ``t_end`` within what is left of it, it stops the run
   with :attr:`Status.MAX_ITERS` (:mod:`lumped.solvers.eventdriven.budget`).

The output holds the accepted step points, or (with ``dt``) the dense output on
``t_n = n dt``; ``RawRun.dense(t)`` evaluates the collocation polynomials anywhere.

The loop (:class:`lumped.solvers.eventdriven.run.Radau5Run`, with the checks of a solved
step in :mod:`lumped.solvers.eventdriven.checks`) is the readable reference. By default the
steps between events run in its compiled port (:mod:`lumped.solvers.eventdriven.loop_jit`,
through :mod:`lumped.solvers.eventdriven.fast`), which returns to it for every pass that
needs more than a held-mode step (an event, a stop, a singular matrix) and gives the same
numbers.
"""

from __future__ import annotations

from ...scene import Scene
from ...scene.supports import supported_scene
from ..status import RawRun
from .at_rest import rest_run
from .compile_when import waited
from .run import DEFAULT_ATOL, DEFAULT_RTOL, Radau5Run
from .setup import EXTRA_OPTIONS, scope_error

__all__ = ["run_radau5", "DEFAULT_RTOL", "DEFAULT_ATOL", "EXTRA_OPTIONS"]


def run_radau5(scene: Scene, settings) -> RawRun:
    """The ``radau5`` runner: ``(scene, RunSettings) -> RawRun`` (see the module notes).

    ``settings.rtol`` / ``atol`` default to :data:`DEFAULT_RTOL` / :data:`DEFAULT_ATOL`;
    ``settings.dt`` (optional) samples the dense output on ``t_n = n dt``; the keywords of
    :data:`EXTRA_OPTIONS` come in ``settings.extra``. A scene proven at rest for the
    whole run takes its one held interval directly
    (:func:`lumped.solvers.eventdriven.at_rest.rest_run`, the same solution).

    A scene with moving supports (:mod:`lumped.scene.supports`) runs on the view of its
    :class:`~lumped.scene.supports.SupportFrame` (the laws shifted by ``o_e(t)``, the
    clock set by the driver) in the Python loop; a backward-Euler bridge runs on the
    scene itself (``bdf1`` with its own frame).
    """
    if getattr(scene, "support_ends", ()):
        why = scope_error(scene)
        if why is not None:
            raise ValueError(why)
        return Radau5Run(supported_scene(scene, "radau5").scene, settings, source=scene).run()
    held = rest_run(scene, settings)
    if held is not None:
        return held
    raw = Radau5Run(scene, settings).run()
    waited(raw.stats)  # (its Python steps towards compiling the shared loop)
    return raw
