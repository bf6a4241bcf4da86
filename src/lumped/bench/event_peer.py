r"""The event-driven scipy peer: what an expert would write by hand for the Bingham scene.

:func:`scipy.integrate.solve_ivp` on the **exact** Bingham law (no smoothing), switching
between three modes with terminal events:

* **slip** ``s = +1`` or ``s = -1`` (``sign v``): the smooth ODE

  .. math::  x' = v, \qquad m v' = F(t) - k x - (\tau s + v / \gamma),

  integrated until the terminal event ``v = 0``;
* at ``v = 0`` the mass **sticks** when ``|F(t) - k x| <= tau`` (the dashpot can hold
  the net force) and otherwise slips on in the direction of ``F(t) - k x``;
* **stick**: ``x`` stays frozen and ``v = 0``; the break-out is the first root of
  ``F(t) - k x -+ tau`` (``|F(t) - k x| = tau`` crossed), found by sampling the forcing
  at 64 points per period (vectorised) and refining a sign change with
  :func:`scipy.optimize.brentq` to ``1e-15`` relative; with no forcing a stuck mass
  stays stuck.

The run is split at the forcing's switch-off time (a known jump of ``F``): each piece
has its own forcing (``A sin(w t)`` before, ``0`` after), so no step straddles the jump.
The Jacobian of the slip ODE is constant and is passed to the implicit methods.  The
dense output of every slip piece (and the frozen ``x`` of every stick piece) is
evaluated on the common grid, as for the other scipy runs.  A run that exceeds its
budget of right-hand-side evaluations or events raises (the benchmark records it as
failed).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ..scene import SineBurst
from .methods import Solved
from .scenes import GRID_DT, BenchScene, Ladders

__all__ = ["MAX_EVENTS", "event_driven_solver"]

#: Events (stick, reversal, break-out) allowed per run before it is declared chattering.
MAX_EVENTS = 10_000

#: Samples per forcing period when looking for a break-out.
_SAMPLES_PER_PERIOD = 64

class _Piece:
    """One stretch of ``[0, t_end]`` with a smooth forcing ``A sin(omega t)`` (``A = 0``: none)."""

    def __init__(self, t0: float, t1: float, amplitude: float, omega: float) -> None:
        self.t0, self.t1, self.amplitude, self.omega = t0, t1, amplitude, omega

    def force(self, t: float) -> float:
        return self.amplitude * math.sin(self.omega * t)


def _pieces(scene: BenchScene, t_end: float) -> list[_Piece]:
    """The pieces of ``[0, t_end]``: split at the forcing's switch-off time."""
    f = scene.forcing
    if f is None:
        return [_Piece(0.0, t_end, 0.0, 0.0)]
    if not isinstance(f, SineBurst):  # pragma: no cover - every bench scene has one
        raise TypeError(f"the event-driven peer needs a SineBurst forcing, got {f!r}")
    if f.t_off < t_end:
        return [_Piece(0.0, f.t_off, f.amplitude, f.omega), _Piece(f.t_off, t_end, 0.0, 0.0)]
    return [_Piece(0.0, t_end, f.amplitude, f.omega)]


def _breakout(p: _Piece, k: float, tau: float, x: float, t0: float) -> tuple[float, int] | None:
    """First ``t`` in ``(t0, p.t1]`` where ``F(t) - k x`` leaves ``[-tau, tau]``, and the
    direction ``s`` of the slip that follows; ``None`` if the mass stays stuck."""
    from scipy.optimize import brentq

    if p.amplitude == 0.0 or p.omega == 0.0:  # constant forcing: the stick decided at t0 holds
        return None
    n = max(2, math.ceil((p.t1 - t0) * abs(p.omega) / (2.0 * math.pi) * _SAMPLES_PER_PERIOD))
    ts = np.linspace(t0, p.t1, n + 1)
    net = p.amplitude * np.sin(p.omega * ts) - k * x
    best: tuple[float, int] | None = None
    first = len(ts)
    for s in (1, -1):
        hits = np.nonzero(s * (net[1:] - s * tau) > 0.0)[0]
        if not hits.size or hits[0] > first:
            continue
        i = int(hits[0])
        root = brentq(lambda t, s=s: p.force(t) - k * x - s * tau, ts[i], ts[i + 1],
                      xtol=1e-15 * max(1.0, abs(ts[i + 1])), rtol=4.0 * np.finfo(float).eps)
        if best is None or root < best[0]:
            best, first = (root, s), i
    return best


def event_driven_solver(
    scene: BenchScene, method: str, rtol: float, atol: float, max_nfev: int, t_end: float,
    grid_dt: float = GRID_DT, max_events: int = MAX_EVENTS,
    log: list[tuple[float, str]] | None = None,
) -> Callable[[], Solved]:
    """A zero-argument callable that runs the event-driven peer and returns ``x`` on the grid.

    Parameters
    ----------
    scene : BenchScene
    method : str
        A :func:`scipy.integrate.solve_ivp` method (``"DOP853"``, ``"LSODA"``, ``"RK45"``...).
    rtol, atol : float
        Tolerances of every slip piece.
    max_nfev : int
        Budget of right-hand-side evaluations over the whole run.
    t_end : float
        End of the run.
    grid_dt : float
        Step of the grid on which ``x`` is returned (``t_i = i grid_dt``).
    max_events : int
        Budget of stick, reversal and break-out events.
    log : list, optional
        If given, every run appends its events ``(t, kind)`` to it, ``kind`` one of
        ``"stick"``, ``"reversal"``, ``"continue"`` (``v`` touches 0, the slip goes on the
        same way) and ``"breakout"``, as the events of :mod:`lumped.reference`.
    """
    from scipy.integrate import solve_ivp

    o = scene.osc
    m, k, tau, inv_gamma = o.m, o.k, o.tau, 1.0 / o.gamma
    pieces = _pieces(scene, t_end)
    implicit = method in ("Radau", "BDF", "LSODA")
    jac_matrix = [[0.0, 1.0], [-k / m, -inv_gamma / m]]

    def jac(t: float, y: Sequence[float]) -> list[list[float]]:
        return jac_matrix  # LSODA refuses a constant matrix given as a list: pass a callable
    n_grid = int(round(t_end / grid_dt))
    t_grid = np.arange(n_grid + 1) * grid_dt

    def run() -> Solved:
        count = [0]
        arcs: list[tuple[float, float, Callable | None, float]] = []
        steps = events = 0

        def mode_at(t: float, x: float, force: Callable[[float], float]) -> int:
            net = force(t) - k * x
            return 0 if abs(net) <= tau else (1 if net > 0.0 else -1)

        x, v = float(scene.x0), float(scene.v0)
        for p in pieces:
            t, t1, force = p.t0, p.t1, p.force
            mode = (1 if v > 0.0 else -1) if v != 0.0 else mode_at(t, x, force)
            while t < t1:
                if events > max_events:
                    raise RuntimeError(f"more than {max_events} events (chattering)")
                if mode == 0:
                    found = _breakout(p, k, tau, x, t)
                    t_next = t1 if found is None else found[0]
                    arcs.append((t, t_next, None, x))
                    t, v = t_next, 0.0
                    if found is not None:
                        mode = found[1]
                        events += 1
                        if log is not None:
                            log.append((t, "breakout"))
                    continue
                s = float(mode)

                def rhs(tt: float, y: Sequence[float], s=s, force=force) -> list[float]:
                    count[0] += 1
                    if count[0] > max_nfev:
                        raise RuntimeError(
                            f"gave up after {max_nfev} right-hand-side evaluations")
                    return [y[1], (force(tt) - k * y[0] - s * tau - y[1] * inv_gamma) / m]

                def stop(tt: float, y: Sequence[float]) -> float:
                    return y[1]

                stop.terminal = True  # type: ignore[attr-defined]
                stop.direction = -s  # type: ignore[attr-defined]
                extra = {"jac": jac} if implicit else {}
                sol = solve_ivp(rhs, (t, t1), [x, v], method=method, rtol=rtol, atol=atol,
                                events=stop, dense_output=True, **extra)
                if sol.status < 0:
                    raise RuntimeError(f"solve_ivp status {sol.status}: {sol.message}")
                steps += len(sol.t) - 1
                t_stop = float(sol.t[-1])
                arcs.append((t, t_stop, sol.sol, math.nan))
                x, v = float(sol.y[0, -1]), float(sol.y[1, -1])
                t = t_stop
                if sol.status == 1:  # v = 0: stick, or slip on in the direction of the net force
                    v = 0.0
                    mode = mode_at(t, x, force)
                    events += 1
                    if log is not None:
                        log.append((t, "stick" if mode == 0 else
                                    "reversal" if mode != s else "continue"))
            # the forcing jumps at t1: the next piece decides its own mode from (x, v)
        if events > max_events:
            raise RuntimeError(f"more than {max_events} events (chattering)")
        x_grid = np.empty_like(t_grid)
        lo = 0
        for _a, b, dense, xc in arcs:
            hi = int(np.searchsorted(t_grid, b, side="right"))
            if hi > lo:
                x_grid[lo:hi] = xc if dense is None else dense(t_grid[lo:hi])[0]
            lo = max(lo, hi)
        if lo < len(t_grid):  # pragma: no cover - arcs cover [0, t_end]
            raise RuntimeError(f"the arcs end at t = {arcs[-1][1]!r} < t_end = {t_end!r}")
        return Solved(t_grid, x_grid, steps, count[0])

    return run


def event_peer_methods(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    """The bench entry ``scipy-events-<method>``: one run per ``(rtol, atol)`` setting."""

    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        return event_driven_solver(scene, method, setting["rtol"], setting["atol"],
                                   ladders.max_nfev, scene.t_end,
                                   grid_dt=setting.get("grid_dt", GRID_DT))

    return solve
