r"""Compiled (numba) closed-form BDF1 (Algorithm 1) and BDF2 steps.

The same model, sign convention and corrector as the pure-Python reference
(:mod:`lumped.solvers.closed.closed_form`), which stays
the readable version::

    m v' = F(t) - F_s - F_d,   x' = v,   F_s = k x,   v = gamma (F_d - clip(F_d, -tau, tau))

One step with effective step ``h`` (``dt`` for BDF1, ``2 dt / 3`` for BDF2) and history
``x_hat, v_hat`` (``x_n, v_n`` for BDF1; ``y_n + (y_n - y_{n-1}) / 3`` for BDF2)::

    c = h / m,   a = 1 + h^2 k / m,   F~ = (m / h) v_hat + F(t_{n+1}) - k x_hat
    |F~| <= tau:  v = 0, F_d = F~                                  (stick)
    otherwise:    |v| = (c / (a + c / gamma)) e,  |F_d| = tau + |v| / gamma,
                  e = |F~| - tau,  sgn(v) = sgn(F_d) = sgn(F~)      (slip, eq. 16)

so ``F_d - sgn(F_d) tau`` is never formed by subtraction (no cancellation as
``gamma -> infinity``). The first BDF2 step is BDF1. ``m / h`` and ``c / (a + c / gamma)``
do not change during a run, so the compiler hoists them: a step has no division.

The step itself is not rewritten here: the reference's ``bdf1_step``, ``bdf2_step`` and
``correct`` are compiled from their own code, and only the loops (forcing, history,
storage or summary) are written for numba. So the compiled loops execute the *same
floating-point operations in the same order* as the Python reference and give the same
numbers bit for bit (numba does not contract ``a * b + c`` into fused multiply-adds unless
``fastmath`` is on, and ``math.sin`` calls the same C library). The tests hold them to
that.

Forcing
-------
The compiled loop takes the forcing as data, a code and three numbers:

* :data:`FORCE_ZERO` -- ``F = 0``;
* :data:`FORCE_CONSTANT` -- ``F = p0``;
* :data:`FORCE_SINE` -- the sine burst ``F = p0 sin(p1 t)`` for ``t <= p2``, ``0`` after
  (:class:`lumped.scene.SineBurst`; ``p2 = inf`` means never switched off);
* :data:`FORCE_SAMPLED` -- any other callable, sampled in Python on the grid
  ``t_n = n dt`` first (one Python call per step: slower, same numbers).

:func:`forcing_code` turns a forcing callable into this form. Compiled code is cached
on disk (``cache=True``), so only the first run on a machine pays for compilation.
"""

from __future__ import annotations

import math
import types
from collections.abc import Callable

import numpy as np
from numba import njit, prange

from ...scene.forcing_jit import (
    FORCE_CONSTANT,
    FORCE_NONE,
    FORCE_SINE,
    FORCE_TABLE,
    forcing_code,
)

__all__ = [
    "FORCE_ZERO",
    "FORCE_CONSTANT",
    "FORCE_SINE",
    "FORCE_SAMPLED",
    "SUMMARY_FIELDS",
    "forcing_code",
    "compiled_columns",
    "run_steps",
    "summary_one",
    "summary_batch",
    "summary_batch_serial",
]

#: The kinds of :mod:`lumped.scene.forcing_jit` (zero and sampled are its none and table).
FORCE_ZERO = FORCE_NONE
FORCE_SAMPLED = FORCE_TABLE

#: Columns of the summary arrays returned by :func:`summary_one` / :func:`summary_batch`.
SUMMARY_FIELDS = (
    "x_end",        # displacement at the last good step
    "v_end",        # velocity at the last good step
    "steps_done",   # steps completed (n unless a non-finite value stopped the run)
    "stick_steps",  # steps n >= 1 with v_n == 0
    "cycles",       # slip -> stick transitions (v_{n-1} != 0, v_n == 0)
    "events",       # changes of the branch (stick, slip +, slip -) between samples
    "dissipated",   # sum over steps of dt F_d,n v_n (dashpot work, right-endpoint rule)
    "F_d_end",      # dashpot force at the last good step
)


@njit(cache=True, nogil=True)
def _force(kind, p0, p1, p2, samples, i, t):
    """``F(t_i)`` for the forcing given as data (see the module notes)."""
    if kind == FORCE_ZERO:
        return 0.0
    if kind == FORCE_CONSTANT:
        return p0
    if kind == FORCE_SINE:
        if t > p2:
            return 0.0
        return p0 * math.sin(p1 * t)
    return samples[i]


def _compile_reference_steps():
    """numba-compile the reference's own :func:`~lumped.solvers.closed.closed_form.bdf1_step` and
    :func:`~lumped.solvers.closed.closed_form.bdf2_step` (with their :func:`correct`).

    The compiled steps are built from the reference's code objects, so there is one
    source for the arithmetic of a step; only the loops around it live here.
    """
    from . import closed_form as reference

    namespace = dict(vars(reference))
    # inline="always": the step is inlined into the loops at numba's IR level, so that
    # LLVM sees its loop-invariant quotients (m / h, c / (a + c / gamma)) and hoists them
    namespace["correct"] = njit(cache=True, nogil=True, inline="always")(reference.correct)

    def compile_step(fn):
        twin = types.FunctionType(fn.__code__, namespace, fn.__name__)
        return njit(cache=True, nogil=True, inline="always")(twin)

    return compile_step(reference.bdf1_step), compile_step(reference.bdf2_step)


_bdf1_step, _bdf2_step = _compile_reference_steps()


def _compile_reference_rule():
    """numba-compile the reference's own
    :func:`~lumped.solvers.closed.closed_form.limit_step_velocity` (a ``v0`` the limit
    step reverses or stops starts at rest): one source for the rule."""
    from . import closed_form as reference

    return njit(cache=True, nogil=True, inline="always")(reference.limit_step_velocity)


_limit_step_velocity = _compile_reference_rule()


@njit(cache=True, nogil=True, inline="always")
def _step(m, k, inv_gamma, tau, dt, bdf2, x, v, x_prev, v_prev, F_next):
    """One step: BDF2 from ``(x, v)`` and ``(x_prev, v_prev)`` if ``bdf2``, else BDF1.

    Returns ``(x, v, F_d, F~)`` at the new time level.
    """
    if bdf2:
        return _bdf2_step(m, k, inv_gamma, tau, dt, x, v, x_prev, v_prev, F_next)
    return _bdf1_step(m, k, inv_gamma, tau, dt, x, v, F_next)


@njit(cache=True, nogil=True)
def run_steps(m, k, inv_gamma, tau, dt, bdf2, kind, p0, p1, p2, samples,
              x_out, v_out, Fd_out, Ft_out):
    """Fill ``x_out[1:], v_out[1:], Fd_out[1:], Ft_out[1:]`` (row 0 holds the initial state).

    ``n = len(x_out) - 1`` steps; BDF2 (``bdf2 = True``) starts with one BDF1 step.
    Returns the number of steps completed: ``n``, or fewer if a non-finite force or state
    appeared (the rows after it are left untouched).
    """
    n = x_out.shape[0] - 1
    x = x_out[0]
    v = v_out[0]
    x_prev = x
    v_prev = v
    for i in range(1, n + 1):
        t = i * dt
        F = _force(kind, p0, p1, p2, samples, i, t)
        use2 = bdf2 and i >= 2
        x_new, v_new, F_d, F_t = _step(m, k, inv_gamma, tau, dt, use2, x, v, x_prev, v_prev, F)
        if not math.isfinite(k * x_new):  # k > 0: also catches x, v, F_d, F not finite
            return i - 1
        x_prev = x
        v_prev = v
        x = x_new
        v = v_new
        x_out[i] = x
        v_out[i] = v
        Fd_out[i] = F_d
        Ft_out[i] = F_t
    return n


@njit(cache=True, nogil=True)
def summary_one(m, k, inv_gamma, tau, dt, n, bdf2, x0, v0, kind, p0, p1, p2, out):
    """Run ``n`` steps without storing them and write the :data:`SUMMARY_FIELDS` to ``out``.

    A non-finite value stops the run; ``out`` then holds the values up to the last good
    step (``steps_done < n`` says so).

    Rest to the end: once a step maps a state at rest onto itself (``x_new == x``, ``v_new
    == v == 0``, and for BDF2 also ``x == x_prev``, ``v_prev == 0``) under a force that
    no longer changes (zero, constant, or a sine burst after its switch-off), every later
    step receives the same inputs and returns the same outputs, bit for bit; the loop
    stops there and counts the remaining steps as stuck (no events, no work). The
    summary is exactly the one of stepping to the end; only the time differs.

    ``kind`` is never :data:`FORCE_SAMPLED` here: the summary has no samples (the
    sweep's plan, :func:`lumped.sweep.closed.plan_closed`, refuses such a forcing).
    """
    empty = np.empty(0)
    x = x0
    v = v0
    if v0 != 0.0:  # a v0 the limit step 1e-20 dt reverses or stops starts at rest, as in
        # integrate (closed_form.initial_velocity: the same compiled rule)
        v = _limit_step_velocity(m, k, inv_gamma, tau, x0, v0,
                                 _force(kind, p0, p1, p2, empty, 0, 0.0), 1e-20 * dt)
    x_prev = x
    v_prev = v
    F_d_last = 0.0
    stick = 0
    cycles = 0
    events = 0
    work = 0.0
    done = n
    for i in range(1, n + 1):
        t = i * dt
        F = _force(kind, p0, p1, p2, empty, i, t)
        use2 = bdf2 and i >= 2
        x_new, v_new, F_d, _ = _step(m, k, inv_gamma, tau, dt, use2, x, v, x_prev, v_prev, F)
        if not math.isfinite(k * x_new):
            done = i - 1
            break
        if v_new == 0.0:
            stick += 1
            if v != 0.0:
                cycles += 1
                events += 1
        elif v == 0.0 or (v_new > 0.0) != (v > 0.0):
            events += 1
        work += dt * F_d * v_new
        if (v_new == 0.0 and v == 0.0 and x_new == x
                and (not use2 or (x_prev == x and v_prev == 0.0))
                and (kind != FORCE_SINE or t > p2) and kind != FORCE_SAMPLED
                and (not bdf2 or use2)):
            stick += n - i  # the fixed point of every remaining step
            F_d_last = F_d
            break
        x_prev = x
        v_prev = v
        x = x_new
        v = v_new
        F_d_last = F_d
    out[0] = x
    out[1] = v
    out[2] = done
    out[3] = stick
    out[4] = cycles
    out[5] = events
    out[6] = work
    out[7] = F_d_last


@njit(cache=True, parallel=True)
def summary_batch(params, dt, n, bdf2, out):
    """:func:`summary_one` for every row of ``params``, in parallel over the rows (prange).

    ``params[j] = (m, k, 1/gamma, tau, x0, v0, kind, p0, p1, p2)``; ``out`` has shape
    ``(len(params), len(SUMMARY_FIELDS))``.
    """
    for j in prange(params.shape[0]):
        p = params[j]
        summary_one(p[0], p[1], p[2], p[3], dt, n, bdf2, p[4], p[5], int(p[6]),
                    p[7], p[8], p[9], out[j])


@njit(cache=True, nogil=True)
def summary_batch_serial(params, dt, n, bdf2, out):
    """:func:`summary_batch` on one thread, without the GIL (for Dask workers and pools)."""
    for j in range(params.shape[0]):
        p = params[j]
        summary_one(p[0], p[1], p[2], p[3], dt, n, bdf2, p[4], p[5], int(p[6]),
                    p[7], p[8], p[9], out[j])



def compiled_columns(
    m: float, k: float, gamma: float, tau: float,
    forcing: Callable[[float], float] | None,
    x0: float, v0: float, Fd0: float, dt: float, n: int, method: str,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The columns ``x, v, F_d, F~`` (``n + 1`` samples, row 0 the initial state) of ``n``
    closed-form steps, compiled; the drop-in twin of the reference's Python loops.

    ``method`` is ``"bdf1"`` or ``"bdf2"``. A forcing the loop cannot evaluate natively
    (see :func:`forcing_code`) is sampled on the grid first.

    Raises
    ------
    ValueError
        If the forcing returns a non-finite value (naming the time), as the reference does.
    FloatingPointError
        If the state overflows (naming the step and time).
    """
    kind, p0, p1, p2 = forcing_code(forcing)
    samples = np.empty(0)
    if kind == FORCE_SAMPLED:
        samples = np.empty(n + 1)
        for i in range(1, n + 1):
            F = forcing(i * dt)
            if not math.isfinite(F):
                raise ValueError(f"`forcing` returned {F!r} at t = {i * dt!r}")
            samples[i] = F
    x = np.empty(n + 1)
    v = np.empty(n + 1)
    Fd = np.empty(n + 1)
    Ft = np.empty(n + 1)
    x[0], v[0], Fd[0], Ft[0] = x0, v0, Fd0, Fd0
    done = run_steps(m, k, 1.0 / gamma, tau, dt, method == "bdf2", kind, p0, p1, p2,
                     samples, x, v, Fd, Ft)
    if done < n:
        raise FloatingPointError(
            f"non-finite state at t = {(done + 1) * dt!r} (step {done + 1}) of the "
            f"closed-form {method} steps"
        )
    return x, v, Fd, Ft
