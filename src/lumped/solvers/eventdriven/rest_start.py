r"""The start of a run at rest, made once per scene content (:func:`rest_start`).

A run at rest (:mod:`lumped.solvers.eventdriven.at_rest`) starts from the consistent
initial state, reads the mode off it (:func:`~lumped.solvers.eventdriven.mode_parts.
rest_mode`) and builds the static balance of that mode
(:func:`~lumped.solvers.modes.stuck.static_hold`). When every node is a mass at rest and
the initial forces need no Newton (the forces fixed by the laws and the static balance,
or a yield dashpot's edge,
:func:`lumped.solvers.implicit.initial_rest.initial_rest_forces`: the initial state's
counters are all zero), none of these reads the run's arguments: not ``t_end`` (the
initial state's time scale only sizes the vanishing step of its Newton system), not the
Newton options, not the tolerances. They are then kept on the scene's
:class:`~lumped.solvers.eventdriven.setup.ScenePlan`, which is made again whenever the
scene's nodes, elements or forcing objects are other objects (all immutable: frozen
dataclasses and bound laws) of another content, and shared by the scene objects of one
content (:func:`lumped.codegen.scene_key.scene_key`: the bits of every number, the names,
ends, law objects and forcings), so that a scene with other numbers never reads them and
a new scene object with the same numbers does. An initial state that took Newton (its
counters not zero) is made again for every run.

Under a steady forcing (absent or constant) the forces of the static balance are the
same at every time, so the balance's verdict is kept too: whether the scene stays at rest
for any span (every guard above its round-off tolerance by
:data:`~lumped.solvers.eventdriven.mode_parts.MARGIN` at the initial forces, and none
crossed at the balance's forces when a user's ``F0`` lies off the balance).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from ...scene import Scene
from ..implicit.initial_state import consistent_initial_state
from ..modes.lock_events import hold_rate_locks
from ..modes.stuck import StaticHold, forcing_kinds, static_hold
from ..radau.rows import row_of
from .mode_parts import rest_mode

__all__ = ["RestStart", "rest_start"]


@dataclass(frozen=True, eq=False)
class RestStart:
    """The start of a run at rest (see the module notes; the lists are only read).

    Attributes
    ----------
    x, v, F, q : list of float
        The consistent initial state and the elongations (rates of the dashpots).
    newton_iterations : int
        The initial state's Newton iterations (``stats["initial_newton_iterations"]``).
    modes : tuple of int
        The mode read off the state, which locks every node.
    guards : list
        Its guards in the stage solve's form, per element.
    hold : StaticHold
        Its static balance from ``t = 0``. Under a steady forcing it is shared by the runs
        that read this start (its forces are the same at every time); under a sine burst
        every run makes its own (:meth:`fresh_hold`), as its memo of the forces grows with
        the times asked.
    varying : bool
        A forcing is a sine burst.
    F_end : list of float or None
        Under a steady forcing, the balance's forces at every ``t > 0``; else ``None``.
    acc0 : list of float
        The masses' accelerations at ``t = 0`` from the balance of the initial forces
        (the driver's first step size reads them).
    row0 : numpy.ndarray
        The first output row, ``(1, 1 + 2N + E)`` (copied into each run's ``data``).
    row_end : numpy.ndarray or None
        Under a steady forcing, the output row of every ``t > 0`` (its time aside).
    may_be_free : bool
        Two or more elements on cycles have a branch whose ``dR/dF`` is not a nonzero
        constant: only then can forces be indeterminate
        (:func:`~lumped.solvers.nonsmooth.locks.indeterminate_elements` needs two
        force-free elements on a cycle), and the run logs them.
    last_off : float
        Under a sine burst, the latest time a burst is switched off: from there on the
        forcing is steady.
    kept : dict
        Under a sine burst, what the runs share (:meth:`kept_interval`): the held interval
        up to the first time event, and the balance after every burst has ended per force
        state.
    """

    x: list[float]
    v: list[float]
    F: list[float]
    q: list[float]
    newton_iterations: int
    modes: tuple[int, ...]
    guards: list
    hold: StaticHold
    varying: bool
    F_end: list[float] | None
    acc0: list[float]
    row0: np.ndarray
    row_end: np.ndarray | None
    may_be_free: bool
    last_off: float
    kept: dict = field(default_factory=dict)

    def fresh_hold(self, scene: Scene, plan) -> StaticHold:
        """The static balance from the initial state, made anew (a run's own)."""
        fkind, fpar = forcing_kinds(scene, plan)
        return static_hold(scene, plan, self.modes, self.x, self.v, self.F, fkind, fpar)

    def kept_interval(self, key: tuple, make: Callable[[], object]) -> object:
        """What ``make`` gives, made once per ``key`` (which holds everything it reads
        besides this start; its verdict included: ``None`` when a guard crosses)."""
        got = self.kept.get(key, False)
        if got is False:
            got = make()
            if len(self.kept) >= 64:  # (runs to many ends, or many probe sizes)
                self.kept.clear()
            self.kept[key] = got
        return got


def rest_start(scene: Scene, plan, time_scale: float, options) -> RestStart | None:
    """The :class:`RestStart` of ``scene`` (``plan`` its
    :class:`~lumped.solvers.eventdriven.setup.ScenePlan`), or ``None`` when its initial
    state does not hold it at rest beyond round-off; kept on ``plan`` when the initial
    state took no Newton (see the module notes). ``time_scale`` and ``options`` are those
    of :func:`~lumped.solvers.implicit.initial_state.consistent_initial_state`.

    Raises
    ------
    ValueError, InconsistentInitialForce, SolverError
        As :func:`~lumped.solvers.implicit.initial_state.consistent_initial_state`
        (nothing is kept then)."""
    got = plan.__dict__.get("rest_start", False)
    if got is not False:
        return got
    x = [float(nd.x0) for nd in scene.nodes]
    v, F, ic = consistent_initial_state(scene, time_scale=time_scale, options=options)
    start = _start(scene, plan, x, v, F, ic["newton_iterations"])
    if not any(ic.values()):  # no Newton: nothing here read the run's arguments
        plan.__dict__["rest_start"] = start
    return start


def _start(scene: Scene, plan, x: list[float], v: list[float], F: list[float],
           newton_iterations: int) -> RestStart | None:
    """The start from the consistent initial state ``(x, v, F)``, or ``None``."""
    if any(vi != 0.0 for vi in v):
        return None
    net = scene.net_forces(0.0, F)
    if _accelerates(net, F) and all(el.F0 is None for el in scene.elements):
        return None  # (a released spring, a dashpot at its yield force: it moves)
    q = scene.elongations(x, v)
    got = rest_mode(scene, plan, q, F)
    if got is None:
        return None
    modes, guards = got
    # the velocities the start's mode choice sets exactly (a v0 of -0.0 reads 0.0)
    v = list(v)
    hold_rate_locks(scene, plan.branches, modes, v)
    fkind, fpar = forcing_kinds(scene, plan)
    hold = static_hold(scene, plan, modes, x, v, F, fkind, fpar)
    if hold is None:
        return None
    F_end = None
    if not hold.varying:
        F_end = hold.forces(1.0)  # (the forcing is steady: the forces of every time)
        # (F: a user's F0 off the balance; F_end itself is checked by the scan)
        if F_end != F and hold.breakout(0.0, 1.0, guards, modes)[0] is not None:
            return None
    acc0 = [net[i] / nd.m for i, nd in enumerate(scene.nodes)]
    return RestStart(x, v, F, q, newton_iterations, modes, guards, hold, hold.varying,
                     F_end, acc0, np.array([row_of(0.0, x, v, F)], dtype=float),
                     None if F_end is None else np.array(row_of(0.0, x, v, F_end)),
                     len(plan.structure["free_cyclic"]) > 1,
                     max([float(p[2]) for k, p in zip(fkind, fpar, strict=True) if k == 2],
                         default=0.0))


#: A net force on a mass above this part of the largest force of the initial state (the
#: elements' and the load's) is no round-off: the mass accelerates at ``t = 0``.
ACCELERATES = 1e-3


def _accelerates(net: list[float], F: list[float]) -> bool:
    """Some mass's net force at ``t = 0``, ``f_i(0) + sum F_e`` (``net``), is beyond
    :data:`ACCELERATES` of the initial state's largest force: the consistent initial
    state gives a stuck element the force that keeps its mass at rest when its law
    admits one, so such a mass starts to move and the scene is not at rest (the general
    driver runs it, as it does when the mode read off the state is no rest mode). Not
    asked where a user's ``F0`` may lie off the balance (the static balance decides)."""
    scale = max([abs(f) for f in F] + [abs(f) for f in net], default=0.0)
    return any(abs(f) > ACCELERATES * scale for f in net)
