r"""The fast path of ``jit-bdf1``/``jit-bdf2`` and its hand-over to the faithful port.

:func:`run_fast_path` runs the scene's generated loop (:mod:`lumped.solvers.bdf.fast_codegen`)
for as many steps as it takes; a step it cannot take (its Newton does not settle on one
smooth branch in :data:`~lumped.solvers.bdf.fast_codegen.MAX_FAST_ITERATIONS` iterations, a
singular or non-finite system, a fold, a non-finite force) goes to the faithful port,
:func:`lumped.solvers.bdf.core_jit.run_bdf_core`, started from the stored state of the
step before, which takes it (with the reference's globalised Newton, round-off row
scales and directional retries) or reports the failure exactly as the reference would.
If the fast loop fails again at once, the faithful port takes twice as many steps the
next time (1, 2, 4, ...), so a scene the fast loop cannot handle costs at most about
twice the faithful port's time; after a step the fast loop took, the count starts again
at 1.

Agreement with ``bdf1``/``bdf2`` (tested in ``tests/solvers/bdf/test_bdf_fast_jit.py``):

* both solve the same step system (the same unrolled residual, term for term) with the
  same convergence tests at the same point: an iterate ``u`` is converged when
  ``|G_i| <= rtol S_i + atol`` for every row and its correction ``d = J(u)^{-1} G(u)``
  satisfies ``|d_j| <= rtol |u_j| + atol``. The reference returns ``u - d``; the fast
  path returns ``u`` when ``d`` is round-off by construction (a zero residual, or ``u``
  from a correction on an unchanged smooth branch with no element stuck) and ``u - d``
  otherwise (see :mod:`lumped.solvers.bdf.fast_codegen`);
* on a smooth branch of a piecewise-linear law the step system is affine, and both
  results are its solution up to round-off (the fast path applies ``J^{-1}`` as a matrix,
  the reference a triangular solve); elsewhere the two solutions of one step differ by
  at most about ``rtol |u| + atol`` (``1e-10 |u| + 1e-12`` by default). The difference
  is carried on by the (stable) steps that follow, not amplified. Measured over 4000
  steps of the paper scenes, Maxwell, two masses and a quadratic drag: at most 1e-11
  relative to each column's size;
* exact properties survive: a stuck dashpot's row ``v = 0`` is a singleton pivot of 1,
  so its row of ``J^{-1}`` is exact and the velocity is exactly 0, and a step with a
  stuck element returns ``u - d`` like the reference, the second correction that makes
  the forces of eq. (19) exact.
"""

from __future__ import annotations

import numpy as np

__all__ = ["run_fast_path"]


def run_fast_path(scene, js, port, args: tuple, start: int = 0,
                  stop: int | None = None) -> tuple[int, dict]:
    """Fill ``xs, vs, Fs, info, finfo`` of ``args`` (the arguments of
    :func:`~lumped.solvers.bdf.core_jit.run_bdf_core` after its callbacks, from
    :func:`lumped.solvers.bdf.fixed_step_jit.loop_arguments`, with ``js`` and ``port``)
    by the fast path with hand-over to the faithful port on ``port``'s callbacks; return
    the rows filled and the counters (the reference's names, plus ``fast_steps`` and
    ``handovers``).

    Steps ``start + 1 .. stop`` (``stop=None``: to the last step), from the state at row
    ``start`` (and ``start - 1``, the BDF2 history) of ``xs, vs, Fs``; ``start = 0``
    writes the initial state ``x0, v0, F0`` of ``args`` there first."""
    from ...codegen.jit import scene_source
    from ...codegen.module_cache import module_name
    from .core_jit import compiled_run_bdf_core
    from .fast_codegen import MAX_FAST_ITERATIONS, fast_module

    (masses, ea, eb, spring, checked, x0, v0, F0, dt, n_steps, bdf2, rtol, atol, max_iters,
     max_backtracks, free_steps, fkind, fpar, ftab, xs, vs, Fs, info, finfo) = args[:24]
    # what the generated source depends on: the laws and topology (the hash of the
    # structure's module text, kept per structure), the massless nodes and the
    # fold-checked elements
    key = (module_name(scene_source(scene).source), (masses != 0.0).tobytes(),
           ea.tobytes(), eb.tobytes(), spring.tobytes(), np.asarray(checked).tobytes())
    fm = fast_module(scene, key)
    # the faithful port is compiled (or loaded from numba's disk cache) at the first
    # hand-over only: a run the fast loop takes whole never pays for it
    loop = None
    work = args[24:]
    N, E = xs.shape[1], Fs.shape[1]
    n = N + E
    if start == 0:
        xs[0], vs[0], Fs[0] = x0, v0, F0
    last = n_steps if stop is None else stop
    Jm = np.zeros((n, n))
    Inv = np.zeros((n, n))
    key = np.zeros(2 * E)
    LU = np.zeros((n, n))
    P = np.zeros(n, dtype=np.int64)
    b = np.zeros(n)
    counts = np.zeros(6, dtype=np.int64)
    slow = np.zeros(5, dtype=np.int64)  # the faithful port's counters, summed
    info[:] = 0
    # never more iterations than the caller's budget allows the reference (plus the
    # confirming evaluation)
    max_it = min(MAX_FAST_ITERATIONS, max_iters + 1)
    step, chunk, handovers = start, 1, 0
    rows = start + 1
    while True:
        nxt = fm.run_fast(masses, dt, last, bdf2, step, rtol, atol, max_it, fkind, fpar, ftab,
                          xs, vs, Fs, Jm, Jm.reshape(-1), LU, P, Inv, Inv.reshape(-1), key,
                          b, np.zeros(n), counts, js.consts)
        rows = nxt
        if nxt > last:
            break
        chunk = chunk * 2 if nxt == step + 1 and handovers else 1
        begin = nxt - 1
        end = min(last, begin + chunk)
        if loop is None:
            loop = compiled_run_bdf_core()
        rows = loop(*port.callbacks(), masses, ea, eb, spring,
                    checked, xs[begin].copy(), vs[begin].copy(), Fs[begin].copy(), dt,
                    n_steps, bdf2, rtol, atol, max_iters, max_backtracks, free_steps, fkind,
                    fpar, ftab, xs, vs, Fs, info, finfo, *work, begin, end)
        handovers += 1
        slow[:4] += info[4:8]
        slow[4] = max(slow[4], info[8])
        if info[0] != 0 or end >= last:
            break
        step = end
    stats = {
        "steps": rows - 1 - start,
        "newton_iterations": int(counts[0] + slow[0]),
        "residual_evals": int(counts[1] + slow[1]),
        "jacobian_evals": int(counts[2] + slow[2]),
        "factorizations": int(counts[3] + slow[3]),
        "max_newton_iterations": int(max(counts[4], slow[4])),
        "fast_steps": int(counts[5]),
        "handovers": handovers,
    }
    return rows, stats
