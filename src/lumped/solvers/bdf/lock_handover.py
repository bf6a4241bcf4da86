r"""``jit-bdf1``/``jit-bdf2`` on a scene with position locks (taut strings): the compiled
loop for the plain steps, the Python reference across impacts and indeterminate forces.

The compiled loops (:mod:`lumped.solvers.bdf.core_jit`, the faithful port, and the
generated fast loop of :mod:`lumped.solvers.bdf.fast_jit`) have no event model: no
impact located inside a step, no impulse, no minimum-norm split of indeterminate forces.
Most steps of the reference :func:`lumped.solvers.bdf.fixed_step.run_bdf` need none of
it, though: a step that ends with no new lock and with fewer than two force-free
elements on cycles is the plain step the compiled loops take, a taut string held
through the step included (its locking branch ``q = L`` is a branch of its law like any
other). So :func:`run_locked` runs, in turn:

* **compiled**, a chunk of steps from the last good sample ``n`` (the state at ``n`` and
  ``n - 1``, the BDF2 history, are rows of the sample arrays), then the guard
  :func:`lumped.solvers.bdf.lock_guard_jit.first_unkept_row` over the new samples: the
  samples before the first one the reference would not have taken as a plain step (a
  new lock: an impact; two force-free elements on cycles: indeterminate forces) are
  kept (so are all of them, if there is none), and the chunk doubles
  (:data:`FIRST_CHUNK`, 2x, ...) while none is found; a step the compiled Newton cannot
  take, a fold or a bad force also ends the chunk at the sample before it;
* **reference**, a :class:`~lumped.solvers.bdf.step_loop.StepLoop` resumed at the last
  good sample (its locks, BDF2 history and fold-check point are those of the state
  there): it redoes the step the compiled chunk could not keep -- locates the impact in
  the step, applies the impulse, restarts BDF2 with a BDF1 step; splits indeterminate
  forces by minimum norm and logs them -- and goes on until ``handback`` consecutive
  steps were plain (no restart pending, no indeterminate forces possible;
  :data:`HISTORY` = 2, the BDF2 history; doubled, up to :data:`MAX_HANDBACK`, each time
  the compiled loop stops again within ``handback`` steps of taking over, so a
  rattling string does not hand over at every step). A failed step is reported by the
  reference, exactly as ``bdf1``/``bdf2`` report it.

Agreement with ``bdf1``/``bdf2``: the reference's steps are its own; the compiled steps
are those of :func:`lumped.solvers.bdf.fixed_step_jit.run_bdf_jit` from the same state,
so with the faithful port (``fast=False``, systems of at most 8 unknowns) the whole run
is the reference's bit for bit, and with the fast loop it agrees to the Newton
tolerance (the fast loop's own agreement, :mod:`lumped.solvers.bdf.fast_jit`). ``stats``
adds ``compiled_steps``, ``reference_steps`` and ``handovers`` (compiled to reference).
Moving supports are not compiled (the runner sends those scenes whole to the reference).
"""

from __future__ import annotations

import numpy as np

from ...scene import Scene
from ...scene.supports import solver_view
from ..newton.options import NewtonOptions
from ..nonsmooth.impacts import lockable_elements
from ..nonsmooth.locks import cyclic_elements
from ..status import RawRun, Status
from .fixed_step import RunResult
from .fixed_step_jit import JIT_METHODS, loop_arguments, takes_fast_path
from .step_loop import StepLoop

__all__ = ["FIRST_CHUNK", "HISTORY", "MAX_HANDBACK", "run_locked"]

#: Compiled steps of the first chunk after a hand-back (then 2x, 4x, ... while slack).
FIRST_CHUNK = 64
#: Consecutive plain steps (no restart pending, no indeterminate forces possible) before
#: the compiled loop takes over again: the BDF2 history.
HISTORY = 2
#: The most plain steps the reference waits for before handing back.
MAX_HANDBACK = 256

_COUNTERS = ("newton_iterations", "residual_evals", "jacobian_evals", "factorizations")


def run_locked(scene: Scene, *, method: str, dt: float, n_steps: int,
               options: NewtonOptions | None = None, throw: bool = True,
               fast: bool | None = None) -> RawRun:
    """Run ``scene`` (a spring law with a locking branch, no moving supports) by
    ``method`` (``jit-bdf1``/``jit-bdf2``) for ``n_steps`` steps of ``dt``: the compiled
    loop for the plain steps, the reference across impacts and indeterminate forces (see
    the module notes).

    ``fast`` as in :func:`lumped.solvers.bdf.fixed_step_jit.run_bdf_jit`. On a failed
    step: raise (``throw=True``) or return the samples so far with the status, as
    ``bdf1``/``bdf2`` do (restitution 0).
    """
    from .core_jit import compiled_run_bdf_core
    from .lock_guard_jit import compiled_first_unkept_row

    if method not in JIT_METHODS:
        raise ValueError(f"`method` must be one of {tuple(JIT_METHODS)}, got {method!r}")
    options = options or NewtonOptions()
    formula = JIT_METHODS[method]
    js, port, args, ic_stats = loop_arguments(scene, formula, dt, n_steps, options)
    fast = takes_fast_path(scene, n_steps, fast, port)
    x0, v0, F0 = args[5:8]
    xs, vs, Fs, info = args[19:23]
    N, E = xs.shape[1], Fs.shape[1]
    xs[0], vs[0], Fs[0] = x0, v0, F0
    view, clock, law_q = solver_view(scene, formula, 0.0)
    ref = StepLoop(scene, view, clock, law_q, method=formula, dt=dt, options=options,
                   throw=throw, restitution=0.0, t0=0.0, x=x0.tolist(), v=v0.tolist(),
                   F=F0.tolist())
    guard = compiled_first_unkept_row()
    lockable = np.array(lockable_elements(scene), dtype=np.int64)
    cyclic = np.array(cyclic_elements(scene), dtype=np.int64)
    was_locked = np.zeros(len(lockable), dtype=np.bool_)
    evaluate, law = port.callbacks()  # (the guard below reads the laws on every chunk)
    lawc = port.consts
    counts = dict.fromkeys(_COUNTERS, 0)
    max_it = compiled = handovers = fast_steps = 0
    chunk, handback, since = FIRST_CHUNK, HISTORY, 0
    row, on_ref = 0, False
    while row < n_steps:
        if on_ref:
            if ref.step != row:
                ref.resume(row, xs[row - 1].tolist(), vs[row - 1].tolist(), xs[row].tolist(),
                           vs[row].tolist(), Fs[row].tolist())
            ref.xs, ref.vs, ref.Fs = [], [], []
            last = ref.advance(n_steps, handback)
            if last > row:
                xs[row + 1:last + 1] = np.reshape(ref.xs, (-1, N))
                vs[row + 1:last + 1] = np.reshape(ref.vs, (-1, N))
                Fs[row + 1:last + 1] = np.reshape(ref.Fs, (-1, E))
            row, on_ref, since = last, False, 0
            if ref.status is not Status.SUCCESS:
                break
            continue
        stop = min(n_steps, row + chunk)
        if fast:
            from .fast_jit import run_fast_path

            filled, st = run_fast_path(scene, js, port, args, row, stop)
            fast_steps += st["fast_steps"]
            for key in _COUNTERS:
                counts[key] += st[key]
            max_it = max(max_it, st["max_newton_iterations"])
        else:  # (the faithful port: compiled only where it runs, as in run_fast_path)
            filled = compiled_run_bdf_core()(evaluate, law, *args[:5], xs[row].copy(),
                          vs[row].copy(), Fs[row].copy(), *args[8:], row, stop)
            for k, key in enumerate(_COUNTERS):
                counts[key] += int(info[4 + k])
            max_it = max(max_it, int(info[8]))
        good = guard(law, lawc, js.ea, js.eb, js.spring, lockable, cyclic, was_locked, xs,
                     vs, Fs, row + 1, filled) - 1
        compiled += good - row
        since += good - row
        row = good
        if row < stop:  # a new lock, indeterminate forces, a step it could not take
            # a lock again soon after the hand-back: wait longer on the reference
            handback = min(2 * handback, MAX_HANDBACK) if since < handback else HISTORY
            chunk = FIRST_CHUNK
            handovers += 1
            on_ref = True
        else:
            chunk *= 2
    rows = row + 1
    for k, key in enumerate(_COUNTERS):
        counts[key] += ref.counts[k]
    stats = {"steps": rows - 1, **counts,
             "max_newton_iterations": max(max_it, ref.counts[4]),
             "initial_newton_iterations": ic_stats["newton_iterations"],
             "impacts": ref.n_impacts, "compiled_steps": compiled,
             "reference_steps": rows - 1 - compiled, "handovers": handovers}
    if fast:
        stats["fast_steps"] = fast_steps
    out = RunResult(dt, N, E, xs[:rows].ravel(), vs[:rows].ravel(), Fs[:rows].ravel(),
                    stats, ref.status, ref.message, ref.events, ref.log.result(), ref.knots)
    return RawRun(out.as_array(), stats, out.status, out.message, events=out.events,
                  dense=out.dense(scene), indeterminate=out.indeterminate)
