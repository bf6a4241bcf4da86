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

A crossing found inside an accepted step whose end held (``g_hi >= 0``) may be a dip of the
guard that its end-of-step values never show below zero: a stuck lock's load that touches
its bound (a double root, ``g ~ (t - t*)^2``), over which the collocation polynomial of a
long step overshoots. Bisecting towards ``h_hi`` never ends there (issue 29: a load at
exactly the joint yield force of two stuck dashpots redid one step 300 times). After
:data:`DIP_AFTER` tries in a row that held short of such a high end, with no crossing
inside, and end values that dip (the lowest below half of each neighbour's, not at the
high end), the landing *searches the dip* on end-of-step values ``g(h)``
(:meth:`Landing.landed`): successive parabolas through the three lowest values met (as
Brent's minimiser: the vertex of ``g_1 + d_1 (h - h_1) + d_2 (h - h_1)(h - h_2)``, kept
inside the bracket beside the lowest value and off the values known, else a bisection of
the wider gap beside the lowest; not the lowest value's neighbours, which keep a far
value in the parabola and crawl up to a skewed dip from one side). A value below ``-tol`` turns
it into a root bracket (the load beyond its bound by more than round-off: the first root,
the break-out), refined on end values alone by the parabola through the bracket's ends and
the nearest value met, or the Illinois secant; a value within ``tol`` lands (the touch).
The guard's minimum holds (no crossing: the search lands on the lowest value, and the
full laws choose there) only where the lowest value was met at the vertex the last
parabola promised, within half its height above ``tol`` of that promise, and the next
parabola's vertex value exceeds ``tol`` by more than twice what it promises below the
lowest value. (A parabola's vertex value alone is no proof: where the guard is more skewed
than a parabola, the parabola through a dip's far values misses a dip below zero, issue
29.) The search lands on the lowest value too for values flat far from zero, a lowest
value at the step's end with the vertex beyond it, and
:data:`DIP_TRIES` values. Polynomial crossings inside are not followed in a dip search, and
another guard's crossing inside moves the landing to that guard only where its end value
crossed and this guard's held (:meth:`Landing.switches`): twin guards (two locks sharing
one load) crossed in turn by one overshooting polynomial restarted the landing.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import sys

__all__ = ["DIP_AFTER", "DIP_TRIES", "MAX_PASSES", "Landing"]

#: Retried steps of one landing at the most.
MAX_PASSES = 40
#: End-of-step values of a dip search at the most (it lands on the lowest).
DIP_TRIES = 12
#: Held tries in a row towards a high end that held, after which the dip is searched.
DIP_AFTER = 2
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
    g_lo: float = math.inf
    count: int = 0
    side: int = 0  # +1: the low end moved last, -1: the high end
    #: the end-of-step values ``(h, g)`` met, in ascending ``h``
    seen: list[tuple[float, float]] = dataclasses.field(default_factory=list)
    #: the guard's dip is searched (see the module notes); ``toward``: held tries in a
    #: row towards a high end that held, ``lo0`` the low end before them, ``dip_at``: the
    #: values met when the search began; ``after``: the size it tries next, ``final``:
    #: that try lands
    dip: bool = False
    toward: int = 0
    lo0: float = 0.0
    dip_at: int = 0
    after: float | None = None
    final: bool = False
    #: the vertex ``(h, g)`` of the search's last parabola, which ``after`` tries
    promised: tuple[float, float] = (math.nan, math.nan)
    #: the steps' polynomial roots are tried (not after a dip: they overshoot there)
    poly: bool = True

    def __post_init__(self) -> None:
        self.seen.append((self.h_hi, self.g_hi))

    def switches(self, g_end: float, g_other: float) -> bool:
        """Whether a landing step in which another guard crossed first (its end value
        ``g_other``; this guard's ``g_end``) lands on that guard instead: always while the
        steps' polynomials are trusted, else only when the other guard's end crossed
        and this one's held (an overshooting polynomial crosses guards it does not)."""
        return self.poly or g_other < 0.0 <= g_end

    def landed(self, g_end: float, tol: float, t: float, h: float | None = None,
               inside: float | None = None) -> bool:
        """Whether the step just solved (of size ``h``, this guard crossed at ``inside``
        within it, or not: None) ends on the root: its end's guard ``g_end`` is within
        ``tol``, the bracket is closed to a few ulps of ``t``, the passes are spent, or a
        dip search ends (see the module notes)."""
        if (abs(g_end) <= tol or self.final or self.count >= MAX_PASSES
                or self.h_hi - self.h_lo <= 8.0 * _EPS * max(1.0, abs(t))):
            return True
        if h is None:
            return False
        seen, tiny = self.seen, 8.0 * _EPS * max(1.0, abs(t))
        if not self.dip:
            held = g_end > 0.0 and inside is None and self.g_hi >= 0.0
            self.toward = self.toward + 1 if held else 0
            if self.toward == 1:
                self.lo0 = self.h_lo
            bisect.insort(seen, (h, g_end))
            k = min(range(len(seen)), key=lambda i: seen[i][1])
            if self.toward < DIP_AFTER or k + 1 == len(seen) or not seen[k][1] < 0.5 * min(
                    seen[k + 1][1], seen[k - 1][1] if k > 0 else math.inf):
                return False
            # held again short of a high end that held too, the end values dip between
            # (the polynomials' crossing is a dip, or their overshoot): search it
            self.dip, self.poly, self.h_lo, self.dip_at = True, False, self.lo0, len(seen)
            return self._search(h, tol, tiny)
        if g_end < 0.0:  # the end values cross: a root bracket from here, low end the
            self.dip = False  # last value below h that held (a guard noisier than its
            # tolerance met one below zero there before: Illinois divided by g_lo - g_hi = 0)
            below = [(hk, gk) for hk, gk in seen if hk < h and gk >= 0.0]
            if below:
                self.h_lo, self.g_lo = below[-1]
        bisect.insort(seen, (h, g_end))
        return self.dip and self._search(h, tol, tiny)

    def _search(self, h: float, tol: float, tiny: float) -> bool:
        """The dip search after the value at ``h`` (see the module notes): whether ``h``
        lands, else the next size in ``after``."""
        seen = self.seen
        k = min(range(len(seen)), key=lambda i: seen[i][1])
        hk, gk = seen[k]
        if len(seen) >= 3 and gk - tol > 2.0 * (max(g for _, g in seen) - gk):
            hk, k = seen[-1][0], len(seen) - 1  # no dip: the values are flat, far from 0
            self.after, self.final = hk, True
            return hk == h
        if len(seen) - self.dip_at >= DIP_TRIES:
            self.after, self.final = hk, True
            return hk == h
        left = seen[k - 1][0] if k > 0 else self.h_lo
        right = seen[k + 1][0] if k + 1 < len(seen) else hk
        u = g_v = math.nan
        if len(seen) >= 3:  # the parabola through the three lowest values (as Brent's)
            (h1, g1), (h2, g2), (h3, g3) = sorted(sorted(seen, key=lambda p: p[1])[:3])
            d1 = (g2 - g1) / (h2 - h1)
            d2 = ((g3 - g2) / (h3 - h2) - d1) / (h3 - h1)
            if d2 > 0.0:
                u = 0.5 * (h1 + h2) - 0.5 * d1 / d2
                g_v = g1 + (u - h1) * (d1 + d2 * (u - h2))
                h_p, g_p = self.promised
                if (k + 1 == len(seen) and u >= hk) or (
                        h_p == hk and gk - tol > 2.0 * abs(gk - g_p)
                        and g_v - tol > 2.0 * (gk - g_v)):
                    # the lowest value, met where the last parabola put its vertex, is
                    # what it promised, and the next one promises little below: the
                    # guard's minimum holds (or the values fall to the step's end)
                    u = hk
        elif k == 0:
            left = hk  # the polynomial crossed down at the first try: the dip is after it
        if u == hk or (hk - left <= tiny and right - hk <= tiny):
            self.after, self.final = hk, True
            return hk == h
        vertex = left + tiny < u < right - tiny and min(abs(u - hj) for hj, _ in seen) > tiny
        if not vertex:
            u = 0.5 * (left + hk) if hk - left > right - hk else 0.5 * (hk + right)
        self.promised = (u, g_v) if vertex else (math.nan, math.nan)
        self.after = u
        return False

    def _quadratic(self) -> float:
        """The root in the bracket of the parabola through its two ends and the nearest
        other end-of-step value met, or NaN (the end values alone, near a double root,
        where a secant crawls: a load a hair beyond a lock's bound at its peak)."""
        a, b = self.h_lo, self.h_hi
        ends = dict(self.seen)  # (the values themselves, not Illinois's halved ones)
        rest = [(hk, gk) for hk, gk in self.seen if hk != a and hk != b]
        if not rest or a not in ends or b not in ends:
            return math.nan
        h3, g3 = min(rest, key=lambda p: min(abs(p[0] - a), abs(p[0] - b)))
        ga, gb = ends[a], ends[b]
        d1 = (gb - ga) / (b - a)
        d2 = ((g3 - gb) / (h3 - b) - d1) / (h3 - a)
        # g(a + x) = ga + x (d1 + d2 (x - (b - a))) = d2 x^2 + (d1 - d2 (b - a)) x + ga
        p = d1 - d2 * (b - a)
        disc = p * p - 4.0 * d2 * ga
        if d2 == 0.0 or disc < 0.0:
            return a - ga / d1
        q = -0.5 * (p + math.copysign(math.sqrt(disc), p))
        roots = [r for r in (q / d2, ga / q if q != 0.0 else math.nan) if 0.0 < r < b - a]
        return a + min(roots) if roots else math.nan

    def next_size(self, h: float, g_end: float, inside: float | None) -> float:
        """The next step size after a step of size ``h`` that did not land: its end's
        guard ``g_end``; ``inside``, the ``s`` where the same guard crossed inside the
        step while its end is back above 0 (a stuck dashpot's balance force leaving its
        cone and returning within the step: the step is too long), else None."""
        self.count += 1
        if self.after is not None:  # the dip search's next size
            h, self.after = self.after, None
            return h
        h_lo, g_lo = self.h_lo, self.g_lo
        if not self.poly:  # the end values alone: a parabola, or Illinois
            if g_end < 0.0:
                if self.side == -1:
                    self.g_lo = g_lo = 0.5 * g_lo
                self.h_hi, self.g_hi, self.side = h, g_end, -1
            else:
                if self.side == 1:
                    self.g_hi *= 0.5
                self.h_lo, self.g_lo, self.side = h, g_end, 1
            h = self._quadratic()
            if not self.h_lo < h < self.h_hi and self.g_lo < math.inf:
                g_lo, g_hi = self.g_lo, self.g_hi
                h = self.h_lo + (self.h_hi - self.h_lo) * g_lo / (g_lo - g_hi)
        elif g_end < 0.0 or inside is not None:
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
            self.h_lo, self.g_lo, self.side = h, g_end, 1
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
