r"""The event loop of the exact reference: stick or slip at a time, the break-out from
stick, the zero of the velocity that ends a slip arc, and grazing contacts.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import brentq

from .arcs import CHUNK, EPS, SlipArc
from .model import Event, Interval, Params, TooManyEvents

__all__ = []


# ----------------------------------------------------------------------------------------------
# the event loop


def _stick_or_slip(p: Params, t: float, x: float) -> int:
    """At rest at ``(t, x)``: 0 if the mass stays stuck, else the slip direction ``+-1``."""
    forced = p.forced_at(t)
    F = p.force(t, forced)
    G = F - p.k * x
    tol = 8.0 * EPS * (p.tau + abs(F) + abs(p.k * x))
    excess = abs(G) - p.tau
    if excess > tol:
        return 1 if G > 0.0 else -1
    if excess < -tol or not forced:
        return 0
    sigma = 1 if G > 0.0 else -1
    dG = p.dforce(t, forced)
    dtol = 8.0 * EPS * abs(p.A * p.w)
    if sigma * dG > dtol:
        return sigma
    if sigma * dG < -dtol:
        return 0
    # F' = 0: F'' = -w^2 F decides.
    return sigma if sigma * (-p.w * p.w * F) > 0.0 else 0


def phases(p: Params, x0: float, v0: float, horizon: float, max_events: int):
    intervals: list[Interval] = []
    arcs: list[SlipArc | None] = []
    events: list[Event] = []
    t, x, v = 0.0, x0, v0
    if p.tau == 0.0:
        s = 0  # the slip equation does not depend on the direction; no stick, no events
    elif v0 != 0.0:
        s = 1 if v0 > 0.0 else -1
    else:
        s = _stick_or_slip(p, 0.0, x0)
    stuck = s == 0 and p.tau > 0.0
    n_events = 0
    while True:
        forced = p.forced_at(t)
        piece_end = p.t_off if forced else math.inf
        t_stop = min(piece_end, horizon)
        if stuck:
            tb, sigma = _breakout(p, t, x, t_stop, forced)
            t_next = t_stop if tb is None else tb
            if t_next > t or not intervals:
                intervals.append(Interval(t, t_next, "stick", 0, x, 0.0, forced))
                arcs.append(None)
            if tb is not None:
                events.append(Event(tb, "breakout", x, 0.0))
                t, v, s, stuck = tb, 0.0, sigma, False
            elif t_stop < horizon:  # forcing switched off while stuck
                events.append(Event(t_stop, "forcing-off", x, 0.0))
                t = t_stop
                s = _stick_or_slip(p, t, x)
                stuck = s == 0
            else:
                break
        else:
            arc = SlipArc(p, s, forced, t, x, v)
            ts = _zero_of_v(arc, t_stop) if s != 0 else None
            t_next = t_stop if ts is None else ts
            if t_next > t or not intervals:
                intervals.append(Interval(t, t_next, "slip", s, x, v, forced))
                arcs.append(arc)
            if ts is not None:
                x_new = arc.state(ts, math)[0]
                t, x, v = ts, x_new, 0.0
                s_new = _stick_or_slip(p, t, x)
                kind = "stick" if s_new == 0 else ("continue" if s_new == s else "reversal")
                events.append(Event(t, kind, x, 0.0))
                stuck = s_new == 0
                s = s_new
            elif t_stop < horizon:  # forcing switched off while slipping
                x_new, v_new = arc.state(t_stop, math)
                events.append(Event(t_stop, "forcing-off", x_new, v_new))
                t, x, v = t_stop, x_new, v_new
                if v == 0.0 and p.tau > 0.0:
                    s = _stick_or_slip(p, t, x)
                    stuck = s == 0
            else:
                break
        n_events += 1
        if n_events > max_events:
            raise TooManyEvents(
                f"the exact reference met more than max_events = {max_events} events before "
                f"t = {t!r} (of t_end = {horizon!r}); the stick-slip sequence may accumulate "
                "(Zeno-like) or the horizon is too long for this frequency"
            )
    intervals[-1] = _with_end(intervals[-1], horizon)
    return intervals, arcs, events


def _with_end(iv: Interval, t_end: float) -> Interval:
    return Interval(iv.t_start, t_end, iv.phase, iv.direction, iv.x_start, iv.v_start, iv.forced)


def _breakout(p: Params, t0: float, x: float, t_stop: float, forced: bool):
    """First time in ``(t0, t_stop]`` where ``|F(t) - k x|`` exceeds ``tau``, and ``sgn``."""
    if not forced or t_stop <= t0:
        return None, 0
    A, w, kx, tau = p.A, p.w, p.k * x, p.tau
    tol = 8.0 * EPS * (tau + abs(A) + abs(kx))
    # Extrema of sin(w t): w t = pi/2 + n pi.  G = A sin(w t) - k x is monotone between them.
    aw = abs(w)
    n_first = math.floor((aw * t0 - 0.5 * math.pi) / math.pi) + 1
    n_last = math.floor((aw * t_stop - 0.5 * math.pi) / math.pi)
    n = n_first
    prev_t = t0
    while True:
        hi = min(n + CHUNK, n_last + 1)
        ext = (0.5 * math.pi + np.arange(n, hi) * math.pi) / aw
        ext = ext[(ext > t0) & (ext < t_stop)]
        last = hi > n_last
        pts = np.append(ext, t_stop) if last else ext
        G = A * np.sin(w * pts) - kx
        g = np.abs(G) - tau
        hits = np.flatnonzero(g > tol)
        if hits.size:
            i = int(hits[0])
            lo_t = prev_t if i == 0 else float(pts[i - 1])
            hi_t = float(pts[i])
            sigma = 1 if G[i] > 0.0 else -1
            target = sigma * tau + kx

            def f(t, target=target):
                return A * math.sin(w * t) - target

            f_lo, f_hi = sigma * f(lo_t), sigma * f(hi_t)
            if f_lo >= 0.0:
                return lo_t, sigma
            if f_hi <= 0.0:  # cannot happen on a monotone piece, but be safe
                return hi_t, sigma
            root = brentq(f, lo_t, hi_t, xtol=1e-300, rtol=4.0 * EPS, maxiter=200)
            return max(root, t0), sigma
        if last:
            return None, 0
        if pts.size:
            prev_t = float(pts[-1])
        n = hi


def _zero_of_v(arc: SlipArc, t_stop: float) -> float | None:
    """First ``t`` in ``(t0, t_stop]`` with ``v(t) = 0`` on a slip arc, or ``None``.

    A sign change of ``s v`` between samples is refined by ``brentq``.  A sign change
    of the acceleration ``s v'`` from ``-`` to ``+`` between samples means a local
    minimum of ``s v`` in between, which is located and checked (a double root, or two
    roots closer than the sampling).
    """
    s = arc.s
    t0 = arc.t0
    noise = 64.0 * EPS * arc.v_scale
    prev_t, prev_sv, prev_sa = t0, s * arc.v_scalar(t0), s * arc.accel_scalar(t0)
    started = prev_sv > noise  # starting from rest: v must first become clearly positive
    for ts in arc.sample_times(t_stop):
        if ts.size == 0:
            continue
        x, v = arc.state(ts, np)
        sv = s * v
        sa = s * arc.accel(ts, x, v)
        for j in range(ts.size):
            tj, svj, saj = float(ts[j]), float(sv[j]), float(sa[j])
            if not started:
                if svj <= 0.0:
                    # back to v <= 0 before v was clearly positive at a sample: look closer.
                    tp = _first_positive(arc, t0, tj, noise)
                    if tp is None:
                        # The motion is below round-off (e.g. a break-out by a few ulps):
                        # end the arc where s v drops below -noise, so that the event loop
                        # advances without letting v run the wrong way.
                        return _below_noise(arc, t0, tj, noise)
                    return _refine_root(arc, tp, tj)
                started = svj > noise
            elif svj <= 0.0:
                return tj if svj == 0.0 else _refine_root(arc, prev_t, tj)
            elif prev_sa < 0.0 < saj:
                hit = _graze(arc, prev_t, tj, noise)
                if hit is not None:
                    return hit
            prev_t, prev_sv, prev_sa = tj, svj, saj
    return None


def _first_positive(arc: SlipArc, t0: float, t1: float, noise: float) -> float | None:
    """A time in ``(t0, t1)`` where ``s v > noise`` (dense and geometric sampling), or ``None``."""
    span = t1 - t0
    rel = np.unique(np.concatenate([np.geomspace(1e-12, 1.0, 49), np.linspace(0.0, 1.0, 257)]))
    ts = t0 + span * rel[(rel > 0.0) & (rel < 1.0)]
    ts = ts[ts > t0]
    if ts.size == 0:
        return None
    sv = arc.s * arc.state(ts, np)[1]
    hits = np.flatnonzero(sv > noise)
    return float(ts[hits[0]]) if hits.size else None


def _below_noise(arc: SlipArc, t0: float, t1: float, noise: float) -> float:
    s = arc.s

    def f(t):
        return s * arc.v_scalar(t) + noise

    if f(t1) >= 0.0:
        return t1
    return brentq(f, t0, t1, xtol=1e-300, rtol=4.0 * EPS, maxiter=200)


def _refine_root(arc: SlipArc, lo: float, hi: float) -> float:
    f = arc.v_scalar
    if f(lo) * f(hi) > 0.0:
        return hi
    return brentq(f, lo, hi, xtol=1e-300, rtol=4.0 * EPS, maxiter=200)


def _graze(arc: SlipArc, lo: float, hi: float, noise: float) -> float | None:
    """Minimum of ``s v`` on ``[lo, hi]``: the first zero of ``v`` there, if any."""
    s = arc.s

    def sa(t):
        return s * arc.accel_scalar(t)

    a_lo, a_hi = sa(lo), sa(hi)
    if not (a_lo < 0.0 < a_hi):
        return None
    t_min = brentq(sa, lo, hi, xtol=1e-300, rtol=4.0 * EPS, maxiter=200)
    v_min = s * arc.v_scalar(t_min)
    if v_min > noise:
        return None
    if v_min < 0.0:  # two zeros in [lo, hi]: the first one (s v(lo) > 0 here)
        return _refine_root(arc, lo, t_min)
    return t_min  # touching zero within round-off: a grazing contact
