r"""Exact, event-driven, piecewise-analytic solution of the Bingham oscillator.

This is the yardstick for accuracy: one mass ``m``, a linear spring ``k`` and a
Bingham dashpot ``(gamma, tau = mu_s N_f)`` (or its Coulomb limit
``gamma -> infinity``, Remark 2.1), driven by no force or by a sine burst
``F(t) = A sin(w t)`` for ``t <= t_off`` and ``0`` after (:class:`~lumped.forcing.SineBurst`).

Model and sign convention (as in :mod:`lumped.bingham`)::

    m v' = F(t) - F_s - F_d,    x' = v,    F_s = k x,
    v = gamma (F_d - clip(F_d, -tau, tau)).

The solution alternates between two phases.

*Slip* with direction ``s = sgn(v)`` in ``{+1, -1}``: ``F_d = s tau + v / gamma``, so

.. math::  m x'' + c x' + k x = F(t) - s \tau, \qquad c = 1/\gamma \;(= 0 \text{ for Coulomb}),

a linear ODE with constant coefficients.  With ``u = x - x_eq``, ``x_eq = -s tau / k``,
``u'' + 2 a u' + w0^2 u = F(t) / m`` (``a = c / 2m``, ``w0^2 = k / m``) and

.. math::  u(t) = \Phi(t - t_0) \, (u_0 - u_p(t_0),\; u_0' - u_p'(t_0)) + u_p(t),

where ``Phi`` is the 2x2 propagator of the homogeneous equation written in a form
that is stable in each regime (under-, critically, over-damped; ``expm1`` near
critical damping, the slow root ``-w0^2 / (a + beta)`` for heavy damping) and
``u_p = P sin(w t) + Q cos(w t)`` is the steady sinusoidal response.  Near resonance
(light damping, ``w`` close to ``w0``) ``u_p`` would be huge and cancel against the free
motion, so the forced part is then written as a Duhamel integral from rest at ``t0``,
evaluated with ``expm1`` of complex arguments (exact resonance included).
The slip ends when ``v`` returns to zero: the mass then sticks if
``|F(t) - k x| <= tau``, otherwise it reverses.

*Stick*: ``x`` frozen, ``v = 0``, ``F_d = F(t) - k x``; it ends when
``|F(t) - k x|`` exceeds ``tau`` (break-out) and the mass slips with
``s = sgn(F(t) - k x)``.

Switching the forcing off at ``t_off`` is a breakpoint where a new phase starts
from the same ``(x, v)``.

Events are located by bracketing on a sampling fine enough that a sign change
cannot be missed (see :func:`exact_solution` for the rules and the limitations)
and then :func:`scipy.optimize.brentq` to a relative accuracy of a few ulps.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Literal

import numpy as np
from scipy.optimize import brentq

from ._validate import as_finite, as_int_at_least, as_nonnegative, as_positive
from .bingham import BinghamOscillator, steps_for
from .forcing import SineBurst, zero_forcing
from .trajectory import Trajectory

__all__ = [
    "ExactSolution",
    "Interval",
    "Event",
    "exact_solution",
    "reference_for_grid",
    "ReferenceNotApplicable",
    "TooManyEvents",
]

_EPS = np.finfo(float).eps
#: Samples per half period of the homogeneous motion / per forcing period used to bracket roots.
_SAMPLES_PER_HALF_PERIOD = 16
_SAMPLES_PER_FORCING_PERIOD = 32
_CHUNK = 512
#: Resonance magnification above which the forced response is written as a Duhamel integral.
_NEAR_RESONANCE = 8.0


class ReferenceNotApplicable(ValueError):
    """The exact reference does not cover this problem (e.g. another kind of forcing)."""


class TooManyEvents(RuntimeError):
    """More stick/slip events than ``max_events``: a Zeno-like accumulation or a runaway."""


@dataclass(frozen=True)
class Interval:
    """One phase of the exact solution on ``[t_start, t_end]``.

    Attributes
    ----------
    t_start, t_end : float
        The phase's time span.
    phase : {"stick", "slip"}
        ``"stick"``: ``v = 0`` and ``|F_d| <= tau``; ``"slip"``: the linear ODE above.
    direction : int
        ``s = sgn(v)`` during a slip (``+1`` or ``-1``; ``0`` when ``tau = 0``, where
        the direction does not enter the equations), ``0`` while stuck.
    x_start, v_start : float
        State at ``t_start``.
    forced : bool
        Whether the sine forcing is on during the interval.
    """

    t_start: float
    t_end: float
    phase: Literal["stick", "slip"]
    direction: int
    x_start: float
    v_start: float
    forced: bool


@dataclass(frozen=True)
class Event:
    """A change of phase (or a forcing breakpoint) at time ``t`` and position ``x``.

    ``kind`` is one of ``"stick"`` (slip -> stick, ``v = 0``), ``"reversal"`` (``v``
    passes through zero and the slip continues the other way), ``"breakout"``
    (stick -> slip), ``"forcing-off"`` (the sine burst is switched off), or
    ``"continue"`` (``v`` touches zero and the slip continues the same way).
    """

    t: float
    kind: Literal["stick", "reversal", "breakout", "forcing-off", "continue"]
    x: float
    v: float


@dataclass(frozen=True)
class _Params:
    m: float
    k: float
    c: float  # 1 / gamma, 0 for Coulomb
    tau: float
    A: float
    w: float
    t_off: float

    def force(self, t: float, forced: bool) -> float:
        return self.A * math.sin(self.w * t) if forced else 0.0

    def dforce(self, t: float, forced: bool) -> float:
        return self.A * self.w * math.cos(self.w * t) if forced else 0.0

    def forced_at(self, t: float) -> bool:
        """Whether the forcing is on just *after* ``t`` (the dynamics' point of view)."""
        return self.A != 0.0 and self.w != 0.0 and t < self.t_off


class _SlipArc:
    r"""Closed-form solution of ``m x'' + c x' + k x = F(t) - s tau`` from ``(t0, x0, v0)``."""

    def __init__(self, p: _Params, s: int, forced: bool, t0: float, x0: float, v0: float):
        self.p, self.s, self.forced, self.t0, self.v0 = p, s, forced, t0, v0
        m, k, c = p.m, p.k, p.c
        self.x_eq = -s * p.tau / k
        a = c / (2.0 * m)
        w0 = math.sqrt(k / m)
        self.a, self.w0, self.w0sq = a, w0, k / m
        if a < w0:
            self.regime = "under"
            self.wd = math.sqrt((w0 - a) * (w0 + a))
        elif a == w0:
            self.regime = "critical"
        else:
            self.regime = "over"
            beta = math.sqrt((a - w0) * (a + w0))
            self.beta = beta
            self.r1 = -self.w0sq / (a + beta)  # slow root, without cancellation
            self.r2 = -(a + beta)
        # Forced response.  Away from resonance: the steady sinusoid
        # u_p = P sin(w t) + Q cos(w t).  Near resonance (magnification
        # (k + m w^2) / sqrt(D) > _NEAR_RESONANCE, only possible when under-damped) u_p is
        # huge and cancels against the free motion, so the response from rest at t0 is
        # written as a Duhamel integral instead (see _duhamel).
        self.P = self.Q = 0.0
        self.w = p.w if forced else 0.0
        self.duhamel = False
        amp_p = 0.0
        if forced:
            w = p.w
            det = k - m * w * w
            D = det * det + (c * w) ** 2
            if self.regime == "under" and (k + m * w * w) > _NEAR_RESONANCE * math.sqrt(D):
                self.duhamel = True
                self.lam = complex(-a, self.wd)
                amp_p = abs(p.A) / (k + m * w * w)
            else:
                self.P = p.A * det / D
                self.Q = -p.A * c * w / D
                amp_p = math.hypot(self.P, self.Q)
        up0, dup0 = self._particular(t0, math)
        self.u0 = x0 - self.x_eq - up0
        self.du0 = v0 - dup0
        self.v_scale = max(abs(v0), abs(self.du0), w0 * abs(self.u0),
                           amp_p * max(abs(self.w), w0), 1e-300)

    # -- formulas, generic over ``xp`` in {math, numpy} -------------------------------------
    def _particular(self, t, xp):
        """Steady response ``(u_p, u_p')`` (zero on unforced or Duhamel arcs)."""
        w = self.w
        if w == 0.0 or self.duhamel:
            return 0.0 * t, 0.0 * t
        sn, cs = xp.sin(w * t), xp.cos(w * t)
        return self.P * sn + self.Q * cs, w * (self.P * cs - self.Q * sn)

    def _duhamel(self, h: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        r"""Response ``(u_f, u_f')`` at ``t0 + h`` to ``A sin(w t) / m`` from rest at ``t0``.

        With ``lambda = -a + i w_d`` and ``g(s) = Im(e^{lambda s}) / w_d`` the impulse
        response, ``u_f = (A/m) Im(e^{i w t0} J)``, ``J = (K(lambda) - K(conj lambda)) /
        (2 i w_d)`` and ``K(mu) = int_0^h e^{mu (h - s)} e^{i w s} ds
        = h e^{mu h} phi1((i w - mu) h)``, ``phi1(z) = expm1(z) / z``: no cancellation
        however close ``i w`` is to ``lambda`` (exact undamped resonance included, where
        ``phi1(0) = 1`` gives the secular term).  ``u_f' = (A/m) Im(e^{i w t0} J')`` with
        ``J' = (lambda K(lambda) - conj(lambda) K(conj lambda)) / (2 i w_d)``.
        """
        h = np.asarray(h, dtype=float)
        lam, lamc, w = self.lam, self.lam.conjugate(), self.w

        def K(mu):
            z = (1j * w - mu) * h
            safe = np.where(z == 0, 1.0, z)
            phi1 = np.where(z == 0, 1.0, np.expm1(safe) / safe)
            return h * np.exp(mu * h) * phi1

        k1, k2 = K(lam), K(lamc)
        scale = self.p.A / self.p.m * np.exp(1j * w * self.t0) / (2j * self.wd)
        return (scale * (k1 - k2)).imag, (scale * (lam * k1 - lamc * k2)).imag

    def _propagator(self, h, xp):
        """Entries of ``Phi(h)`` for ``u'' + 2a u' + w0^2 u = 0``."""
        a, w0sq = self.a, self.w0sq
        if self.regime == "under":
            wd = self.wd
            e = xp.exp(-a * h)
            cs = e * xp.cos(wd * h)
            sw = e * xp.sin(wd * h) / wd
            return cs + a * sw, sw, -w0sq * sw, cs - a * sw
        if self.regime == "critical":
            e = xp.exp(-a * h)
            return e * (1.0 + a * h), e * h, -w0sq * e * h, e * (1.0 - a * h)
        beta, r1 = self.beta, self.r1
        e1 = xp.exp(r1 * h)
        e2 = xp.exp(self.r2 * h)
        phi12 = -e1 * xp.expm1(-2.0 * beta * h) / (2.0 * beta)  # (e1 - e2) / (2 beta)
        return e2 + (a + beta) * phi12, phi12, -w0sq * phi12, e2 + r1 * phi12

    def state(self, t, xp=np):
        """``(x, v)`` at ``t`` (array with ``xp=numpy`` or float with ``xp=math``)."""
        h = t - self.t0
        p11, p12, p21, p22 = self._propagator(h, xp)
        if self.duhamel:
            up, dup = self._duhamel(h)
            if xp is math:
                up, dup = float(up), float(dup)
        else:
            up, dup = self._particular(t, xp)
        u = p11 * self.u0 + p12 * self.du0 + up
        du = p21 * self.u0 + p22 * self.du0 + dup
        return u + self.x_eq, du

    def v_scalar(self, t: float) -> float:
        return self.state(t, math)[1]

    def accel(self, t: np.ndarray, x: np.ndarray, v: np.ndarray) -> np.ndarray:
        """``v'`` from the balance of momentum at the samples ``(t, x, v)`` of this arc."""
        p = self.p
        F = p.A * np.sin(p.w * t) if self.forced else 0.0
        return (F - p.k * x - self.s * p.tau - p.c * v) / p.m

    def accel_scalar(self, t: float) -> float:
        x, v = self.state(t, math)
        p = self.p
        return (p.force(t, self.forced) - p.k * x - self.s * p.tau - p.c * v) / p.m

    # -- sampling for root brackets -------------------------------------------------------------
    def sample_times(self, t_stop: float):
        """Yield chunks of increasing sample times in ``(t0, t_stop]``, ending at ``t_stop``.

        Spacing: 1/16 of the homogeneous half period ``pi / w_d`` and 1/32 of the forcing
        period, preceded by a geometric ramp from 1/16 of the fastest time scale (a fast
        over-damped transient).  Unforced and not oscillating, ``v`` is a sum of two
        exponentials (at most one sign change) and the geometric ramp alone suffices.
        """
        span = t_stop - self.t0
        if span <= 0.0:
            yield np.array([t_stop])
            return
        fast_rate = {"under": self.w0, "critical": self.a}.get(self.regime)
        if fast_rate is None:
            fast_rate = -self.r2
        h_fast = 1.0 / (_SAMPLES_PER_HALF_PERIOD * fast_rate)
        a0 = self.accel_scalar(self.t0)
        if self.v0 * a0 < 0.0:  # decelerating: v may reach 0 after about |v0 / a0|
            h_fast = min(h_fast, 0.25 * abs(self.v0 / a0))
        steps = []
        if self.regime == "under":
            steps.append(math.pi / self.wd / _SAMPLES_PER_HALF_PERIOD)
        if self.w != 0.0:
            steps.append(2.0 * math.pi / abs(self.w) / _SAMPLES_PER_FORCING_PERIOD)
        h = min(steps) if steps else span
        h_fast = max(h_fast, h * 2.0**-64)
        if h_fast < h:
            ramp = np.geomspace(h_fast, h, int(math.ceil(math.log2(h / h_fast))) + 1)[:-1]
            ramp = ramp[ramp < span]
            if ramp.size:
                yield self.t0 + ramp
        n_uniform = int(math.ceil(span / h))
        for start in range(0, n_uniform, _CHUNK):
            stop = min(start + _CHUNK, n_uniform)
            rel = np.arange(start + 1, stop + 1) * h
            ts = self.t0 + rel[rel < span]
            if stop == n_uniform:
                ts = np.append(ts, t_stop)
            yield ts


@dataclass(frozen=True)
class ExactSolution:
    """The exact solution: its phases, its events, and its values on ``t_eval``.

    Attributes
    ----------
    trajectory : Trajectory
        ``x, v, F_s = k x, F_d`` on ``t_eval`` with ``method = "exact"``.
    intervals : list of Interval
        The stick and slip phases covering ``[0, t_end]`` in order.
    events : list of Event
        Phase changes and forcing breakpoints, in order.
    t_end : float
        The solution is known on ``[0, t_end]``.
    """

    trajectory: Trajectory
    intervals: list[Interval]
    events: list[Event]
    t_end: float
    _params: _Params = field(repr=False)
    _arcs: list[_SlipArc | None] = field(repr=False)

    def evaluate(self, t: Sequence[float] | np.ndarray) -> Trajectory:
        """``x, v, F_s, F_d`` at the times ``t`` (non-decreasing, within ``[0, t_end]``).

        At an event time the state after the event is returned (``x`` and ``v`` are
        continuous; ``F_d`` may jump), except at ``t_off``, where, as in
        :class:`~lumped.forcing.SineBurst`, the forcing is still on.
        """
        t = _as_times(t, "t")
        if t[-1] > self.t_end * (1.0 + 4.0 * _EPS):
            raise ValueError(f"`t` = {t[-1]!r} is beyond the solution's t_end = {self.t_end!r}")
        return _evaluate(self._params, self.intervals, self._arcs, t)

    def rest_position(self) -> float | None:
        """``x`` if the mass is stuck at ``t_end``, else ``None``."""
        last = self.intervals[-1]
        return last.x_start if last.phase == "stick" else None


def exact_solution(
    osc: BinghamOscillator | None = None,
    *,
    m: float | None = None,
    k: float | None = None,
    gamma: float | None = None,
    tau: float | None = None,
    x0: float,
    v0: float = 0.0,
    forcing=None,
    t_eval: Sequence[float] | np.ndarray,
    t_end: float | None = None,
    coulomb: bool = False,
    max_events: int = 100_000,
) -> ExactSolution:
    r"""Exact solution of the Bingham (or Coulomb) oscillator on ``t_eval``.

    Parameters
    ----------
    osc : BinghamOscillator, optional
        The parameters ``m, k, gamma, tau``.  Alternatively give ``m, k, gamma, tau``
        as keywords (not both).  With ``coulomb=True`` ``gamma`` is ignored and may be
        omitted.
    x0, v0 : float
        Initial state.  ``v0 = 0``: the mass starts stuck if ``|F(0) - k x0| <= tau``
        (``F_d(0) = F(0) - k x0``, as in :func:`lumped.bingham.initial_dashpot_force`),
        otherwise it slips in the direction of ``F(0) - k x0``.  ``v0 != 0``: slip
        with ``sgn(v0)``.
    forcing : None, zero_forcing or SineBurst
        The only forcings the reference covers; anything else raises
        :class:`ReferenceNotApplicable` (a ``ValueError``).
    t_eval : array_like
        Non-decreasing times in ``[0, inf)`` at which to sample the solution.
    t_end : float, optional
        Compute the phases up to ``max(t_end, t_eval[-1])`` (default ``t_eval[-1]``).
    coulomb : bool
        ``True``: the Coulomb limit ``gamma -> infinity`` (``F_d = s tau`` in slip).
    max_events : int
        Stop with :class:`TooManyEvents` beyond this many phase changes.

    Returns
    -------
    ExactSolution

    Notes
    -----
    *Slip -> stick.*  The zeros of ``v`` are bracketed on samples spaced at most
    1/16 of the half period ``pi / w_d`` of the homogeneous motion and 1/32 of the
    forcing period, after a geometric ramp that resolves a fast over-damped transient
    and the stopping time ``|v0 / v'(t0)|``; then ``brentq`` refines them to a few
    ulps.  Unforced, ``v`` changes sign at each of its (evenly spaced, or at most one)
    zeros, so none is missed.  With forcing, a sign change of the acceleration
    ``s v'`` from ``-`` to ``+`` between two samples reveals a local minimum of
    ``s v``, which is located and checked: this catches a double root (grazing, taken
    as a zero when ``|v|`` is within round-off) and two zeros between samples.
    What can still be missed: two zeros of ``v`` *and* two zeros of ``v'`` between two
    samples, i.e. structure faster than 1/32 of the forcing period or 1/16 of the
    homogeneous half period.  A slip whose velocity never rises above round-off (a
    break-out by a few ulps) is ended where ``s v`` falls below round-off.

    *Stick -> slip.*  ``F(t) - k x`` is monotone between the extrema of the sine,
    which are used as sample points, so the first crossing of ``+-tau`` is bracketed
    exactly; a tangency (``|F - k x|`` touching ``tau`` to within a few ulps) is not a
    break-out.

    *Stick -> slip.*  ``F(t) - k x`` is monotone between the extrema of the sine,
    which are used as sample points, so the first crossing of ``+-tau`` is bracketed
    exactly; a tangency (``|F - k x|`` touching ``tau`` to within a few ulps) is not a
    break-out.

    *Ties.*  When ``|F - k x|`` equals ``tau`` to within a few ulps at a zero of
    ``v`` or at the start, the sign of its time derivative decides (then of the
    second derivative).

    *Accuracy.*  ``x`` is exact up to round-off of order
    ``eps (|x| + tau / k + |A| / sqrt(D) (1 + |w| t))`` with
    ``D = (k - m w^2)^2 + (w / gamma)^2`` away from resonance (the steady sinusoid is
    evaluated at the phase ``w t``); near resonance the Duhamel form has no such
    amplification.  Event times are found to a relative accuracy of a few ulps of the
    residual (``v`` or ``|F - k x| - tau``) divided by its slope.
    """
    p = _params_from(osc, m, k, gamma, tau, coulomb, forcing)
    x0 = as_finite("x0", x0)
    v0 = as_finite("v0", v0)
    t_eval = _as_times(t_eval, "t_eval")
    horizon = float(t_eval[-1])
    if t_end is not None:
        horizon = max(horizon, as_positive("t_end", t_end))
    max_events = as_int_at_least("max_events", max_events, 1)
    intervals, arcs, events = _phases(p, x0, v0, horizon, max_events)
    traj = _evaluate(p, intervals, arcs, t_eval)
    return ExactSolution(
        trajectory=traj, intervals=intervals, events=events, t_end=horizon,
        _params=p, _arcs=arcs,
    )


def reference_for_grid(
    osc: BinghamOscillator,
    *,
    x0: float,
    v0: float = 0.0,
    forcing=None,
    dt: float,
    t_end: float,
    coulomb: bool = False,
) -> Trajectory:
    """The exact solution on the grid ``t_n = n dt`` used by the numerical methods.

    The grid is that of :func:`lumped.bingham.integrate` (``steps_for(dt, t_end)``
    steps), so ``traj.to_csv(path)`` writes the same columns and rows as a numerical
    run.  ``stats`` holds the number of grid points, events and intervals.
    Raises :class:`ReferenceNotApplicable` (a ``ValueError``) for a forcing the
    reference does not cover.
    """
    n = steps_for(dt, t_end)
    t = np.arange(n + 1, dtype=float) * as_positive("dt", dt)
    sol = exact_solution(osc, x0=x0, v0=v0, forcing=forcing, t_eval=t, coulomb=coulomb)
    tr = sol.trajectory
    stats = {"steps": n, "events": len(sol.events), "intervals": len(sol.intervals)}
    return Trajectory(t=tr.t, x=tr.x, v=tr.v, F_s=tr.F_s, F_d=tr.F_d, method="exact",
                      stats=stats)


# ----------------------------------------------------------------------------------------------
# input checking


def _params_from(osc, m, k, gamma, tau, coulomb, forcing) -> _Params:
    if not isinstance(coulomb, bool):
        raise TypeError(f"`coulomb` must be True or False, got {coulomb!r}")
    given = {"m": m, "k": k, "gamma": gamma, "tau": tau}
    if osc is not None:
        if not isinstance(osc, BinghamOscillator):
            raise TypeError(f"`osc` must be a BinghamOscillator, got {type(osc).__name__}")
        extra = [name for name, val in given.items() if val is not None]
        if extra:
            raise ValueError(f"give either `osc` or the keywords m, k, gamma, tau, not both "
                             f"(got `osc` and {', '.join(extra)})")
        m, k, gamma, tau = osc.m, osc.k, osc.gamma, osc.tau
    else:
        missing = [name for name, val in given.items()
                   if val is None and not (name == "gamma" and coulomb)]
        if missing:
            raise ValueError(f"missing parameter(s) {', '.join(missing)} (or pass `osc`)")
        m = as_positive("m", m)
        k = as_positive("k", k)
        tau = as_nonnegative("tau", tau)
        if gamma is not None:
            gamma = as_positive("gamma", gamma)
    c = 0.0 if coulomb else 1.0 / gamma
    if forcing is None or forcing is zero_forcing:
        A, w, t_off = 0.0, 0.0, math.inf
    elif isinstance(forcing, SineBurst):
        A = as_finite("forcing.amplitude", forcing.amplitude)
        w = as_finite("forcing.omega", forcing.omega)
        t_off = float(forcing.t_off)
    else:
        raise ReferenceNotApplicable(
            "the exact reference covers only forcing=None, lumped.forcing.zero_forcing or a "
            f"lumped.forcing.SineBurst, got `forcing` = {forcing!r}"
        )
    return _Params(m=m, k=k, c=c, tau=tau, A=A, w=w, t_off=t_off)


def _as_times(t, name: str) -> np.ndarray:
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"`{name}` must be an array of real times, got {t!r}") from None
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"`{name}` must be a non-empty 1-D array of times, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = float(arr[~np.isfinite(arr)][0])
        raise ValueError(f"`{name}` must be finite, got {bad!r}")
    if arr[0] < 0.0:
        raise ValueError(f"`{name}` must be non-negative, got {float(arr[0])!r}")
    if arr.size > 1 and np.any(np.diff(arr) < 0.0):
        i = int(np.flatnonzero(np.diff(arr) < 0.0)[0])
        raise ValueError(f"`{name}` must be non-decreasing, got {float(arr[i])!r} "
                         f"before {float(arr[i + 1])!r}")
    return arr


# ----------------------------------------------------------------------------------------------
# the event loop


def _stick_or_slip(p: _Params, t: float, x: float) -> int:
    """At rest at ``(t, x)``: 0 if the mass stays stuck, else the slip direction ``+-1``."""
    forced = p.forced_at(t)
    F = p.force(t, forced)
    G = F - p.k * x
    tol = 8.0 * _EPS * (p.tau + abs(F) + abs(p.k * x))
    excess = abs(G) - p.tau
    if excess > tol:
        return 1 if G > 0.0 else -1
    if excess < -tol or not forced:
        return 0
    sigma = 1 if G > 0.0 else -1
    dG = p.dforce(t, forced)
    dtol = 8.0 * _EPS * abs(p.A * p.w)
    if sigma * dG > dtol:
        return sigma
    if sigma * dG < -dtol:
        return 0
    # F' = 0: F'' = -w^2 F decides.
    return sigma if sigma * (-p.w * p.w * F) > 0.0 else 0


def _phases(p: _Params, x0: float, v0: float, horizon: float, max_events: int):
    intervals: list[Interval] = []
    arcs: list[_SlipArc | None] = []
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
            arc = _SlipArc(p, s, forced, t, x, v)
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


def _breakout(p: _Params, t0: float, x: float, t_stop: float, forced: bool):
    """First time in ``(t0, t_stop]`` where ``|F(t) - k x|`` exceeds ``tau``, and ``sgn``."""
    if not forced or t_stop <= t0:
        return None, 0
    A, w, kx, tau = p.A, p.w, p.k * x, p.tau
    tol = 8.0 * _EPS * (tau + abs(A) + abs(kx))
    # Extrema of sin(w t): w t = pi/2 + n pi.  G = A sin(w t) - k x is monotone between them.
    aw = abs(w)
    n_first = math.floor((aw * t0 - 0.5 * math.pi) / math.pi) + 1
    n_last = math.floor((aw * t_stop - 0.5 * math.pi) / math.pi)
    n = n_first
    prev_t = t0
    while True:
        hi = min(n + _CHUNK, n_last + 1)
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
            root = brentq(f, lo_t, hi_t, xtol=1e-300, rtol=4.0 * _EPS, maxiter=200)
            return max(root, t0), sigma
        if last:
            return None, 0
        if pts.size:
            prev_t = float(pts[-1])
        n = hi


def _zero_of_v(arc: _SlipArc, t_stop: float) -> float | None:
    """First ``t`` in ``(t0, t_stop]`` with ``v(t) = 0`` on a slip arc, or ``None``.

    A sign change of ``s v`` between samples is refined by ``brentq``.  A sign change
    of the acceleration ``s v'`` from ``-`` to ``+`` between samples means a local
    minimum of ``s v`` in between, which is located and checked (a double root, or two
    roots closer than the sampling).
    """
    s = arc.s
    t0 = arc.t0
    noise = 64.0 * _EPS * arc.v_scale
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


def _first_positive(arc: _SlipArc, t0: float, t1: float, noise: float) -> float | None:
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


def _below_noise(arc: _SlipArc, t0: float, t1: float, noise: float) -> float:
    s = arc.s

    def f(t):
        return s * arc.v_scalar(t) + noise

    if f(t1) >= 0.0:
        return t1
    return brentq(f, t0, t1, xtol=1e-300, rtol=4.0 * _EPS, maxiter=200)


def _refine_root(arc: _SlipArc, lo: float, hi: float) -> float:
    f = arc.v_scalar
    if f(lo) * f(hi) > 0.0:
        return hi
    return brentq(f, lo, hi, xtol=1e-300, rtol=4.0 * _EPS, maxiter=200)


def _graze(arc: _SlipArc, lo: float, hi: float, noise: float) -> float | None:
    """Minimum of ``s v`` on ``[lo, hi]``: the first zero of ``v`` there, if any."""
    s = arc.s

    def sa(t):
        return s * arc.accel_scalar(t)

    a_lo, a_hi = sa(lo), sa(hi)
    if not (a_lo < 0.0 < a_hi):
        return None
    t_min = brentq(sa, lo, hi, xtol=1e-300, rtol=4.0 * _EPS, maxiter=200)
    v_min = s * arc.v_scalar(t_min)
    if v_min > noise:
        return None
    if v_min < 0.0:  # two zeros in [lo, hi]: the first one (s v(lo) > 0 here)
        return _refine_root(arc, lo, t_min)
    return t_min  # touching zero within round-off: a grazing contact


# ----------------------------------------------------------------------------------------------
# evaluation


def _evaluate(p: _Params, intervals: list[Interval], arcs: list, t: np.ndarray) -> Trajectory:
    starts = np.array([iv.t_start for iv in intervals])
    idx = np.searchsorted(starts, t, side="right") - 1
    idx = np.maximum(idx, 0)
    if math.isfinite(p.t_off):
        # At t_off the forcing is still on (SineBurst): use the interval that ends there.
        at_off = (t == p.t_off) & (idx > 0)
        if np.any(at_off):
            moved = idx[at_off] - 1
            ok = np.array([intervals[i].t_end == p.t_off for i in moved])
            sel = np.flatnonzero(at_off)[ok]
            idx[sel] -= 1
    x = np.empty_like(t)
    v = np.empty_like(t)
    F_d = np.empty_like(t)
    cuts = np.flatnonzero(np.diff(idx)) + 1
    for lo, hi in zip(np.r_[0, cuts], np.r_[cuts, t.size], strict=True):
        sel = slice(int(lo), int(hi))
        iv, arc = intervals[int(idx[lo])], arcs[int(idx[lo])]
        ti = t[sel]
        if iv.forced and p.A != 0.0:
            F = p.A * np.sin(p.w * ti)
        else:
            F = np.zeros_like(ti)
        if arc is None:
            x[sel] = iv.x_start
            v[sel] = 0.0
            F_d[sel] = F - p.k * iv.x_start
        else:
            xi, vi = arc.state(ti, np)
            x[sel] = xi
            v[sel] = vi
            F_d[sel] = arc.s * p.tau + p.c * vi
    return Trajectory(t=t.copy(), x=x, v=v, F_s=p.k * x, F_d=F_d, method="exact",
                      stats={"intervals": len(intervals)})
