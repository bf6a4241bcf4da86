"""Run the generic Newton path and the closed form on the same scene and compare them.

Both paths run in the same process, interleaved; the time per step of each is the best
of ``repeat`` runs, and the report gives their ratio (generic / closed), which is the
project's speed yardstick (target: at most 3).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from .result import Solution
from .scene import Scene
from .simulate import simulate
from .solvers.bdf.fixed_step import GENERIC_METHODS
from .solvers.registry import closed_form_oscillator

__all__ = ["CompareReport", "compare"]


@dataclass(frozen=True)
class CompareReport:
    """Largest differences per column and the time per step of each path.

    Attributes
    ----------
    method : str
        The generic method (``bdf1`` or ``bdf2``), compared with ``closed-<method>``.
    steps : int
    max_abs_diff : dict
        ``column -> max_n |generic - closed|``.
    max_rel_diff : dict
        ``column -> max_abs_diff / max(1, max_n |closed|)``.
    generic_time_per_step, closed_time_per_step, ratio : float
        Seconds per step (best of the repeats) and generic / closed.
    generic, closed : Solution
    """

    method: str
    steps: int
    max_abs_diff: dict
    max_rel_diff: dict
    generic_time_per_step: float
    closed_time_per_step: float
    ratio: float
    generic: Solution
    closed: Solution

    def format(self) -> str:
        lines = [f"generic {self.method} vs closed-{self.method}, {self.steps} steps",
                 f"{'column':<16} {'max |diff|':>12} {'relative':>12}"]
        for col, d in self.max_abs_diff.items():
            lines.append(f"{col:<16} {d:12.3e} {self.max_rel_diff[col]:12.3e}")
        lines.append(
            f"time per step: generic {self.generic_time_per_step * 1e6:.3f} us, closed "
            f"{self.closed_time_per_step * 1e6:.3f} us, ratio {self.ratio:.2f}"
        )
        return "\n".join(lines)


def compare(scene: Scene, *, dt: float, t_end: float, method: str = "bdf2",
            repeat: int = 3) -> CompareReport:
    """Run ``method`` (generic) and ``closed-<method>`` on ``scene`` and compare.

    Raises ValueError if the closed form does not cover ``scene`` or ``method`` is not
    ``bdf1``/``bdf2``.
    """
    if method not in GENERIC_METHODS:
        raise ValueError(f"`method` must be one of {GENERIC_METHODS}, got {method!r}")
    why = closed_form_oscillator(scene)
    if isinstance(why, str):
        raise ValueError(f"the closed form does not cover this scene: {why}")
    if isinstance(repeat, bool) or not isinstance(repeat, int) or repeat < 1:
        raise ValueError(f"`repeat` must be a positive integer, got {repeat!r}")

    # interleave the runs so that both paths see the same machine load; keep the best
    times = {method: float("inf"), f"closed-{method}": float("inf")}
    sols: dict[str, Solution] = {}
    for _ in range(repeat):
        for m in times:
            t0 = time.perf_counter()
            sols[m] = simulate(scene, method=m, dt=dt, t_end=t_end)
            times[m] = min(times[m], time.perf_counter() - t0)
    gen, closed = sols[method], sols[f"closed-{method}"]
    t_gen, t_closed = times[method], times[f"closed-{method}"]
    steps = gen.stats["steps"]
    diff = np.abs(gen.data - closed.data).max(axis=0)
    scale = np.maximum(1.0, np.abs(closed.data).max(axis=0))
    cols = gen.columns[1:]
    return CompareReport(
        method=method, steps=steps,
        max_abs_diff={c: float(d) for c, d in zip(cols, diff[1:], strict=True)},
        max_rel_diff={c: float(d) for c, d in zip(cols, (diff / scale)[1:], strict=True)},
        generic_time_per_step=t_gen / steps, closed_time_per_step=t_closed / steps,
        ratio=t_gen / t_closed, generic=gen, closed=closed,
    )
