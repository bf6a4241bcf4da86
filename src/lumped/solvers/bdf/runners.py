r"""The runners of the generic fixed-step methods: ``bdf1``, ``bdf2`` (the Python
reference, :func:`lumped.solvers.bdf.fixed_step.run_bdf`) and ``jit-bdf1``, ``jit-bdf2``
(its compiled twin, :mod:`lumped.solvers.bdf.fixed_step_jit`), each
``runner(scene, settings) -> RawRun`` (see :mod:`lumped.solvers.registry`).

A compiled run hands the whole run to the reference where it cannot go on: a scene with
moving supports (:mod:`lumped.scene.supports`), or a step its Newton cannot take;
``stats["fallback"]`` says why. A scene with a position lock (a taut string: impacts,
indeterminate forces) runs its plain steps compiled, a taut string held through a
step included, and the reference's steps across impacts and indeterminate forces
(:mod:`lumped.solvers.bdf.lock_handover`; ``stats`` counts ``compiled_steps``,
``reference_steps`` and ``handovers``).
"""

from __future__ import annotations

from ...scene import Scene
from ..status import RawRun, Runner, RunSettings, Status, fixed_step_grid
from .fixed_step import run_bdf

__all__ = ["RUNNERS"]


def _run_generic(formula: str) -> Runner:
    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        dt, n_steps = fixed_step_grid(formula, settings, ("restitution",))
        out = run_bdf(scene, method=formula, dt=dt, n_steps=n_steps, options=settings.options,
                      throw=settings.throw,
                      restitution=settings.extra.get("restitution", 0.0))
        return RawRun(out.as_array(), out.stats, out.status, out.message,
                      events=out.events, dense=out.dense(scene),
                      indeterminate=out.indeterminate)

    return runner


#: Statuses of a compiled run that send it to the reference solver.
_NEWTON_FAILURES = frozenset({Status.SINGULAR, Status.DIVERGED, Status.MAX_ITERS,
                              Status.NON_FINITE})


def _on_reference(scene: Scene, method: str, dt: float, n_steps: int,
                  settings: RunSettings, why: str) -> RawRun:
    """The run of ``method`` (``jit-bdf1``/``jit-bdf2``) on the reference solver, with
    ``stats["fallback"] = why``."""
    out = run_bdf(scene, method=method.removeprefix("jit-"), dt=dt, n_steps=n_steps,
                  options=settings.options, throw=settings.throw)
    stats = dict(out.stats, fallback=why)
    return RawRun(out.as_array(), stats, out.status, out.message,
                  events=out.events, dense=out.dense(scene), indeterminate=out.indeterminate)


def _run_jit(method: str) -> Runner:
    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        from .fixed_step_jit import position_lock, run_bdf_jit

        dt, n_steps = fixed_step_grid(method, settings, ("fast",))
        fast = settings.extra.get("fast")
        if getattr(scene, "support_ends", ()):  # no compiled offsets: the reference solver
            return _on_reference(scene, method, dt, n_steps, settings,
                                 f"reference solver: method {method!r} does not take "
                                 f"moving supports ({', '.join(sorted(scene.supports))}) "
                                 "compiled")
        if position_lock(scene, method) is not None:
            # the compiled loop for the plain steps, the reference's steps (impact located
            # in the step, indeterminate forces split) across impacts and indeterminacy
            from .lock_handover import run_locked

            return run_locked(scene, method=method, dt=dt, n_steps=n_steps,
                              options=settings.options, throw=settings.throw, fast=fast)
        raw = run_bdf_jit(scene, method=method, dt=dt, n_steps=n_steps,
                          options=settings.options, throw=False, fast=fast)
        if raw.status in _NEWTON_FAILURES:
            # a step the compiled Newton cannot take (indeterminate forces: a singular
            # step matrix; a hard point of a law): the whole run on the reference solver,
            # with its globalised Newton and minimum-norm force split (issue 11)
            return _on_reference(scene, method, dt, n_steps, settings,
                                 f"reference solver after: {raw.message}")
        if raw.status is not Status.SUCCESS and settings.throw:
            return run_bdf_jit(scene, method=method, dt=dt, n_steps=n_steps,
                               options=settings.options, throw=True, fast=fast)
        return raw

    return runner


#: The generic fixed-step methods, name -> runner.
RUNNERS: dict[str, Runner] = {
    "bdf1": _run_generic("bdf1"),
    "bdf2": _run_generic("bdf2"),
    "jit-bdf1": _run_jit("jit-bdf1"),
    "jit-bdf2": _run_jit("jit-bdf2"),
}
