r"""Exact, event-driven, piecewise-analytic solution of the Bingham oscillator.

This is the yardstick for accuracy: one mass ``m``, a linear spring ``k`` and a
Bingham dashpot ``(gamma, tau = mu_s N_f)`` (or its Coulomb limit
``gamma -> infinity``, Remark 2.1), driven by no force or by a sine burst
``F(t) = A sin(w t)`` for ``t <= t_off`` and ``0`` after (:class:`~lumped.scene.SineBurst`).

Model and sign convention (as in :mod:`lumped.solvers.closed.closed_form`)::

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

import numpy as np

from .._validate import as_finite, as_int_at_least, as_positive
from ..solvers.closed.closed_form import BinghamOscillator, steps_for
from ..trajectory import Trajectory
from .arcs import _EPS, _SlipArc
from .events import _phases
from .model import Event, Interval, _as_times, _Params, _params_from

__all__ = ["ExactSolution", "exact_solution", "reference_for_grid"]


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
        :class:`~lumped.scene.SineBurst`, the forcing is still on.
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
        (``F_d(0) = F(0) - k x0``, as in
        :func:`lumped.solvers.closed.closed_form.initial_dashpot_force`),
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

    The grid is that of :func:`lumped.solvers.closed.closed_form.integrate`
    (``steps_for(dt, t_end)``
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
