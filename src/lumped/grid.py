"""The grid of a fixed output step: how many steps of size ``dt`` reach ``t_end``.

Owns :func:`steps_for`, shared by every method family (the closed form, the fixed-step
BDF methods, ``radau5``'s output on ``t_n = n dt``), the sweeps and the reference; it sits
below them all. ``lumped.solvers.steps_for`` and
``lumped.solvers.closed.closed_form.steps_for`` are this function.
"""

from __future__ import annotations

import math

from ._validate import as_positive

__all__ = ["steps_for"]


def steps_for(dt: float, t_end: float) -> int:
    """Number of steps of size ``dt`` that reach ``t_end`` (rounding to the nearest when
    ``t_end / dt`` is an integer up to round-off, upwards otherwise)."""
    dt = as_positive("dt", dt)
    t_end = as_positive("t_end", t_end)
    ratio = t_end / dt
    n = round(ratio)
    if abs(n - ratio) > 1e-9 * max(1.0, ratio):
        n = math.ceil(ratio)
    if n > 500_000_000:
        raise ValueError(f"`t_end / dt` = {ratio:.3g} steps is too many")
    return max(int(n), 1)
