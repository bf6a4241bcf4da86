"""The benchmark's clock: CPU time of a call, and the yardstick that is its unit of time."""

from __future__ import annotations

import math
import time
from collections.abc import Callable

from .scenes import YARDSTICK_ITERATIONS

__all__ = ["measure_unit", "time_call", "yardstick"]


def yardstick(iterations: int = YARDSTICK_ITERATIONS) -> float:
    """The unit of benchmark time: symplectic Euler on Python floats.

    ``iterations`` updates ``v -= h w^2 x; x += h v`` of a harmonic oscillator
    (``h = 1e-3``, ``w^2 = 100``), a fixed pure-Python float loop that does not depend
    on any library code, so speed-ups of ``lumped`` show up as smaller ratios.
    Returns the final ``x`` (so the loop cannot be optimised away).
    """
    x, v, h, w2 = 1.0, 0.0, 1e-3, 100.0
    for _ in range(iterations):
        v -= h * w2 * x
        x += h * v
    return x


def time_call(
    fn: Callable[[], object], *, min_time: float = 0.05, max_repeats: int = 20,
) -> tuple[object, float, int]:
    """CPU time of ``fn()``: best of several calls when one call is shorter than ``min_time``.

    Returns ``(result of the first call, smallest CPU time in seconds, number of calls)``.
    Calls are repeated until their total reaches ``4 * min_time`` or ``max_repeats``.
    """
    t0 = time.process_time()
    result = fn()
    best = total = time.process_time() - t0
    calls = 1
    if best < min_time:
        while calls < max_repeats and total < 4.0 * min_time:
            t0 = time.process_time()
            fn()
            elapsed = time.process_time() - t0
            best = min(best, elapsed)
            total += elapsed
            calls += 1
    return result, best, calls


def measure_unit(repeats: int = 5) -> float:
    """Smallest CPU time of :func:`yardstick` over ``repeats`` calls (seconds)."""
    best = math.inf
    for _ in range(repeats):
        t0 = time.process_time()
        yardstick()
        best = min(best, time.process_time() - t0)
    return best
