r"""Running the closed form over a grid: :func:`integrate` chooses the Python loops of
:mod:`lumped.solvers.closed.closed_form` (the readable reference) or their compiled twin
:mod:`lumped.solvers.closed.closed_form_jit` (the same operations in the same order).
"""

from __future__ import annotations

import sys
from collections.abc import Callable

import numpy as np

from ..._validate import as_finite, as_int_at_least, as_positive
from ...grid import steps_for
from ...scene.forcing import zero_forcing
from ...trajectory import Trajectory
from .closed_form import (
    CLOSED_METHODS,
    BinghamOscillator,
    checked_force,
    initial_dashpot_force,
    initial_velocity,
    run_bdf1_loop,
    run_bdf2_loop,
)

__all__ = ["integrate", "ENGINES", "COMPILED_MIN_STEPS"]

#: Values of ``integrate(engine=...)``.
ENGINES = ("auto", "python", "compiled")

#: ``engine="auto"`` compiles runs of at least this many steps (about 0.7 s of Python
#: steps, the cost of loading the compiled loops from numba's disk cache), and any run once
#: the compiled loops are loaded in this process.
COMPILED_MIN_STEPS = 500_000


def integrate(
    osc: BinghamOscillator,
    *,
    x0: float,
    v0: float = 0.0,
    forcing: Callable[[float], float] = zero_forcing,
    dt: float,
    t_end: float | None = None,
    n_steps: int | None = None,
    method: str = "bdf1",
    engine: str = "auto",
) -> Trajectory:
    """Run the closed-form BDF1 (Algorithm 1) or BDF2 steps on the grid ``t_n = n dt``.

    Parameters
    ----------
    osc : BinghamOscillator
        Mass, spring and dashpot parameters.
    x0, v0 : float
        Initial displacement and velocity; the initial forces are made consistent
        (``F_s = k x0``, ``F_d`` from :func:`initial_dashpot_force` with the limit step
        ``h = 1e-20 dt``).
    forcing : callable
        ``F(t) -> float``.
    dt : float
        Step size.
    t_end, n_steps
        Give exactly one: the final time or the number of steps.
    method : {"bdf1", "bdf2"}
        BDF2 takes its first step with BDF1.
    engine : {"auto", "python", "compiled"}
        ``"python"``: the loops of :mod:`lumped.solvers.closed.closed_form` on Python
        floats (the readable reference);
        ``"compiled"``: their numba twin :mod:`lumped.solvers.closed.closed_form_jit` (the same
        operations in the same order, hence the same numbers bit for bit; compiled once
        per machine and cached on disk); ``"auto"``: compiled when numba is installed
        and either the run has at least :data:`COMPILED_MIN_STEPS` steps or the compiled
        loops are already loaded in this process, else Python (the results are the same;
        only the speed differs).
        A forcing the compiled loop does not evaluate natively (anything but zero, a
        constant or a :class:`~lumped.scene.SineBurst`) is sampled on the grid first.

    Returns
    -------
    Trajectory
        With ``method`` ``"closed-bdf1"`` or ``"closed-bdf2"`` and the predictor
        ``F~`` of each step in ``predictor`` (``nan``-free; row 0 holds ``F_d(0)``).
    """
    if not isinstance(osc, BinghamOscillator):
        raise TypeError(f"`osc` must be a BinghamOscillator, got {type(osc).__name__}")
    if method not in CLOSED_METHODS:
        raise ValueError(f"`method` must be one of {CLOSED_METHODS}, got {method!r}")
    x0 = as_finite("x0", x0)
    v0 = as_finite("v0", v0)
    dt = as_positive("dt", dt)
    if (t_end is None) == (n_steps is None):
        raise ValueError("give exactly one of `t_end` and `n_steps`")
    n = steps_for(dt, t_end) if n_steps is None else as_int_at_least("n_steps", n_steps, 1)
    if not callable(forcing):
        raise TypeError(f"`forcing` must be callable, got {forcing!r}")
    if engine not in ENGINES:
        raise ValueError(f"`engine` must be one of {ENGINES}, got {engine!r}")

    F0 = checked_force(forcing, 0.0)
    v0 = initial_velocity(osc, x0, v0, F0, h=1e-20 * dt)  # (a limit step, as bdf's)
    Fd0 = initial_dashpot_force(osc, x0, v0, F0)
    if engine == "compiled" or (engine == "auto" and _have_numba() and (
            n >= COMPILED_MIN_STEPS or "lumped.solvers.closed.closed_form_jit" in sys.modules)):
        from .closed_form_jit import compiled_columns

        xs, vs, Fds, Fts = compiled_columns(osc.m, osc.k, osc.gamma, osc.tau, forcing,
                                            x0, v0, Fd0, dt, n, method)
    else:
        loop = run_bdf1_loop if method == "bdf1" else run_bdf2_loop
        xs, vs, Fds, Fts = loop(osc, forcing, x0, v0, Fd0, dt, n)
    x_arr = np.array(xs)
    with np.errstate(over="ignore", invalid="ignore"):  # Trajectory reports non-finite values
        F_s = osc.k * x_arr
    return Trajectory(
        t=np.arange(n + 1, dtype=float) * dt, x=x_arr, v=np.array(vs), F_s=F_s,
        F_d=np.array(Fds), method=f"closed-{method}", stats={"steps": n},
        predictor=np.array(Fts),
    )


def _have_numba() -> bool:
    """Whether numba can be imported (checked once)."""
    global _NUMBA
    if _NUMBA is None:
        import importlib.util

        _NUMBA = importlib.util.find_spec("numba") is not None
    return _NUMBA


_NUMBA: bool | None = None
