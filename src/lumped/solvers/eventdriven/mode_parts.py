r"""What a mode of the ``radau5`` driver holds, and whether a state at rest stays in it.

A mode (the branch every element is held on) has parts that depend on the scene's laws
alone (:func:`mode_parts`: the stage kernels and guards, the watched elements, the locks
on cycles, kept on the scene's plan), force-split cones when locks in parallel share a
load (:func:`mode_cones`), and a test of the laws at a state (:func:`laws_hold`).

:func:`rest_mode` reads the mode of a state at rest and says whether it holds the scene
still beyond round-off: every element with more than one branch on a locking branch,
each guard above :data:`MARGIN` times its round-off tolerance, the laws holding, no
cones. The vanishing implicit step that chooses the mode at the start
(:meth:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode`) confirms such a
mode (every node locked: the probe's velocities are zero, its forces the static balance
under the load at its end, where the guards are checked as well), and the run at rest
(:mod:`lumped.solvers.eventdriven.at_rest`) holds it to the end.
"""

from __future__ import annotations

from ...scene import Scene
from ..modes.guards import guard_tolerance
from ..modes.lock_events import lock_cones
from ..nonsmooth.locks import cycles_among

__all__ = ["MARGIN", "holds_at", "laws_hold", "mode_cones", "mode_parts", "rest_mode"]

#: How far above its round-off tolerance every guard must sit in a mode read off a state
#: at rest (:func:`rest_mode`), in units of that tolerance
#: (:func:`~lumped.solvers.modes.guards.guard_tolerance`): the mode probe's forces differ
#: from the state's by round-off, and must read the same branches.
MARGIN = 4.0


def rest_mode(scene: Scene, plan, q: list[float], F: list[float]
              ) -> tuple[tuple[int, ...], list] | None:
    """``(modes, guards)``: the mode read off ``(q, F)`` (a state at rest; ``plan`` the
    scene's :class:`~lumped.solvers.eventdriven.setup.ScenePlan`) and its guards, if it
    holds the scene still beyond round-off (see the module notes), else ``None``. Whether
    its locks hold every node is the static balance's question
    (:func:`lumped.solvers.modes.stuck.static_hold`)."""
    lbs = plan.branches
    modes = tuple(lb.branch(qe, Fe) for lb, qe, Fe in zip(lbs, q, F, strict=True))
    parts = mode_parts(plan, modes)
    if mode_cones(scene, plan, list(modes), F, parts):  # locks in parallel share a load
        return None
    if any(not lbs[e].info[modes[e]].locks for e in parts[2]):
        return None  # an element that could switch is not on a lock
    held = holds_at(plan, modes, q, F, range(len(F)), read=False)
    return (modes, parts[1]) if held else None


def holds_at(plan, modes: tuple[int, ...], q: list[float], F: list[float], elements,
             read: bool = True) -> bool:
    """The element by element part of :func:`rest_mode` for ``elements`` under the forces
    ``F``: each reads its branch of ``modes`` (with ``read``), its guards sit above
    :data:`MARGIN` times their round-off tolerance and its law holds (:func:`laws_hold`).
    With ``modes`` from :func:`rest_mode` at other forces and fewer than two locks on
    cycles (no cones), these elements' checks are all that :func:`rest_mode` would read
    anew where only their forces changed."""
    lbs = plan.branches
    kernels, guards = mode_parts(plan, modes)[:2]
    for e in elements:
        qe, Fe = q[e], F[e]
        if read and lbs[e].branch(qe, Fe) != modes[e]:
            return False
        margin = MARGIN * guard_tolerance(qe, Fe)
        if any(not g > margin for g in guards[e](qe, Fe)):
            return False
        if not law_holds(kernels[e], qe, Fe):
            return False
    return True


def laws_hold(kernels: list, q: list[float], F: list[float]) -> bool:
    """Whether every element's law holds at ``(q_e, F_e)`` on its branch (``kernels``:
    the stage kernels of the mode, :func:`mode_parts`), to ``1e-8`` relative to the size
    of its terms."""
    return all(law_holds(kernel, qe, Fe) for kernel, qe, Fe in zip(kernels, q, F, strict=True))


def law_holds(kernel, qe: float, Fe: float) -> bool:
    """Whether one element's law holds at ``(q_e, F_e)`` on its branch (``kernel``), to
    ``1e-8`` relative to the size of its terms: the test of :func:`laws_hold`."""
    R, Rq, RF = kernel(qe, Fe)
    return abs(R) <= 1e-8 * (1.0 + abs(Rq * qe) + abs(RF * Fe))


def mode_parts(plan, modes: tuple[int, ...]) -> tuple[list, list, list[int], int]:
    """What :meth:`~lumped.solvers.eventdriven.mode_state.ModeState.set_modes` holds for
    ``modes``, which depends only on the scene's laws, kept on ``plan`` (the scene's
    :class:`~lumped.solvers.eventdriven.setup.ScenePlan`; the lists are only read): the
    branch kernels and guards in the stage solve's form, the elements with more than one
    branch (their guards are watched), and how many elements on cycles are held on a lock
    with a known value (:func:`~lumped.solvers.modes.lock_events.lock_cones` takes them;
    with fewer than two there are no cones)."""
    cache = plan.__dict__.setdefault("mode_parts", {})
    parts = cache.get(modes)
    if parts is None:
        parts = _mode_parts(plan.branches, modes, plan.cyclic)
        if len(cache) >= 4096:  # (a network with very many modes)
            cache.clear()
        cache[modes] = parts
    return parts


def mode_cones(scene: Scene, plan, modes: list[int], F: list[float], parts: tuple
               ) -> dict[int, tuple[float, float, float, float]]:
    """The force-split cones of ``modes`` (``parts``: its :func:`mode_parts`): element ->
    ``(centre, half-width, lo, hi)`` of the locks in parallel with each other, whose
    split is free; empty when there are none."""
    if parts[3] < 2:  # a cone needs two locks on cycles: with fewer, none is read
        return {}
    locked = lock_cones(plan.branches, modes, F, plan.cyclic)
    # only locks in parallel with each other leave their split free (a stuck link in
    # series with another keeps its exact LU solve, and so its exact zero rate)
    parallel = cycles_among(scene, tuple(locked)) if len(locked) > 1 else ()
    return {e: locked[e] for e in parallel} if len(parallel) > 1 else {}


def _mode_parts(lbs: list, modes: tuple[int, ...], cyclic: tuple[int, ...]
                ) -> tuple[list, list, list[int], int]:
    E = len(lbs)
    return ([lbs[e].stage_kernel_for(modes[e]) for e in range(E)],
            [lbs[e].stage_guards_for(modes[e]) for e in range(E)],
            [e for e in range(E) if lbs[e].count > 1],
            sum(1 for e in cyclic if lbs[e].info[modes[e]].locks
                and lbs[e].info[modes[e]].lock_value is not None))
