r"""The landing of a ``radau5`` step on a guard's root: the bracket of step sizes.

When a guard turns negative inside an accepted step (:mod:`lumped.solvers.modes.crossing_root`),
the driver (:mod:`lumped.solvers.eventdriven.step`) retries the step from the same state with
the size that puts the step's end on the root, and brackets that size by the guard's value
at the end of each retried step:

- ``h_lo``: the longest step whose end still held the guard (``g_end >= 0``, no crossing
  of that guard inside);
- ``h_hi``: the shortest step whose end had crossed (or that crossed inside, or that
  Newton could not take), with ``g_hi``.

The next size is the Illinois secant between the two ends (the value kept at an end that
stayed twice in a row halved: superlinear, without the one-sided stall of plain regula
falsi); a crossing inside the step moves to the crossing itself, and bisection takes over
where the root sits a hair past the end that held again and again (a guard flat at its
root, ``g ~ (t* - t)^2``). The landing ends when the end's guard is within its round-off
tolerance, the bracket is a few ulps of ``t`` wide, or after :data:`MAX_PASSES` passes.
"""

from __future__ import annotations

import dataclasses
import sys

__all__ = ["MAX_PASSES", "Landing"]

#: Retried steps of one landing at the most.
MAX_PASSES = 40
_EPS = sys.float_info.epsilon


@dataclasses.dataclass
class Landing:
    """One landing: the guard ``which = (w, j)`` (watched element ``w``, its guard ``j``)
    and the bracket of step sizes (see the module notes); ``h_found``: the step in which
    the crossing was first found (the event's record keeps it)."""

    which: tuple[int, int]
    h_hi: float
    g_hi: float
    h_found: float
    h_lo: float = 0.0
    count: int = 0
    side: int = 0  # +1: the low end moved last, -1: the high end

    def landed(self, g_end: float, tol: float, t: float) -> bool:
        """Whether the step just solved ends on the root: its end's guard ``g_end`` is
        within ``tol``, the bracket is closed to a few ulps of ``t``, or the passes are
        spent."""
        return (abs(g_end) <= tol or self.h_hi - self.h_lo <= 8.0 * _EPS * max(1.0, abs(t))
                or self.count >= MAX_PASSES)

    def next_size(self, h: float, g_end: float, inside: float | None) -> float:
        """The next step size after a step of size ``h`` that did not land: its end's
        guard ``g_end``; ``inside``, the ``s`` where the same guard crossed inside the
        step while its end is back above 0 (a stuck dashpot's balance force leaving its
        cone and returning within the step: the step is too long), else None."""
        self.count += 1
        h_lo = self.h_lo
        if g_end < 0.0 or inside is not None:
            self.h_hi, self.g_hi, self.side = h, g_end, -1
            h = inside * h if inside is not None and inside > 0.0 else 0.5 * (h_lo + h)
            if h - h_lo <= 1e-2 * (self.h_hi - h_lo):
                # the step's polynomial puts the root a hair past the end that held, again
                # and again where the guard is flat at its root (a junction's
                # Herschel-Bulkley n < 1 dashpot stopping, g ~ (t* - t)^2): the bracket did
                # not shrink in 40 passes. Bisect.
                h = 0.5 * (h_lo + self.h_hi)
        else:
            if self.side == 1:  # Illinois: the far end stayed twice, halve its value
                self.g_hi *= 0.5
            self.h_lo, self.side = h, 1
            g_hi, h_hi = self.g_hi, self.h_hi
            h = (h + (h_hi - h) * g_end / (g_end - g_hi) if g_hi < 0.0 else 0.5 * (h + h_hi))
        if not self.h_lo < h < self.h_hi:
            h = 0.5 * (self.h_lo + self.h_hi)
        return h

    def failed_stage(self, h: float, t: float) -> float | None:
        """The next size after a landing step of size ``h`` that Newton could not take
        (no solution that far: the bracket ends there), or None when no step that held
        is known yet (``h_lo = 0``: the driver halves as for any failed step)."""
        if not self.h_lo > 0.0:
            return None
        self.h_hi, self.count = h, self.count + 1
        if h - self.h_lo <= 8.0 * _EPS * max(1.0, abs(t)):
            # the bracket is closed (a guard that jumps, the laws' solution ending inside
            # it): land on its lower end, which held
            self.h_hi = self.h_lo
            return self.h_lo
        return 0.5 * (self.h_lo + h)
