r"""The scipy peers: :func:`scipy.integrate.solve_ivp` on the tanh-regularised model
``F_d = v / gamma + tau tanh(v / eps)`` with its analytic Jacobian.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

import numpy as np

from ..solvers.closed.closed_form import BinghamOscillator
from .methods import Solved
from .scenes import GRID_DT, BenchScene, Ladders

__all__ = [
    "regularised_rhs",
    "regularised_jacobian",
]


def regularised_rhs(
    osc: BinghamOscillator, forcing: Callable[[float], float], eps: float,
) -> Callable[[float, Sequence[float]], list[float]]:
    r"""Right-hand side of the tanh-regularised model for :func:`scipy.integrate.solve_ivp`.

    .. math::  x' = v, \qquad m v' = F(t) - k x - v/\gamma - \tau \tanh(v/\varepsilon).

    ``tanh`` saturates at ``+-1`` so the force never overflows.
    """
    m, k, tau, inv_gamma = osc.m, osc.k, osc.tau, 1.0 / osc.gamma
    tanh = math.tanh

    def rhs(t: float, y: Sequence[float]) -> list[float]:
        x, v = y[0], y[1]
        return [v, (forcing(t) - k * x - v * inv_gamma - tau * tanh(v / eps)) / m]

    return rhs


def regularised_jacobian(
    osc: BinghamOscillator, eps: float,
) -> Callable[[float, Sequence[float]], list[list[float]]]:
    r"""Analytic Jacobian of :func:`regularised_rhs`, free of overflow.

    .. math::  \frac{d}{dv}\tanh(v/\varepsilon) = \frac{\operatorname{sech}^2(v/\varepsilon)}
               {\varepsilon}, \qquad \operatorname{sech}^2 u = \frac{4 e^{-2|u|}}
               {(1 + e^{-2|u|})^2},

    evaluated with ``e^{-2|u|} <= 1`` so neither ``cosh`` nor ``exp`` can overflow
    (``e^{-2|u|}`` underflows harmlessly to 0 for large ``|u|``).
    """
    m, k, tau, inv_gamma = osc.m, osc.k, osc.tau, 1.0 / osc.gamma
    exp = math.exp
    row0 = [0.0, 1.0]

    def jac(t: float, y: Sequence[float]) -> list[list[float]]:
        e = exp(-2.0 * abs(y[1]) / eps)
        sech2 = 4.0 * e / ((1.0 + e) * (1.0 + e))
        return [row0, [-k / m, -(inv_gamma + tau * sech2 / eps) / m]]

    return jac


class _BudgetExceeded(RuntimeError):
    pass


def scipy_method(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        return scipy_solver(scene, method, setting["eps"], setting["rtol"],
                             setting["atol"], ladders.max_nfev, scene.t_end)

    return solve


def scipy_solver(
    scene: BenchScene, method: str, eps: float, rtol: float, atol: float,
    max_nfev: int, t_end: float, grid_dt: float = GRID_DT,
) -> Callable[[], Solved]:
    from scipy.integrate import solve_ivp

    base = regularised_rhs(scene.osc, scene.force, eps)
    jac = regularised_jacobian(scene.osc, eps)
    t_off = math.inf if scene.forcing is None else scene.forcing.t_off
    # Integrate up to the forcing's jump, then restart from there.
    breaks = [0.0] + ([t_off] if 0.0 < t_off < t_end else []) + [t_end]
    n_grid = int(round(t_end / grid_dt))
    t_grid = np.arange(n_grid + 1) * grid_dt

    def run() -> Solved:
        count = [0]

        def rhs(t: float, y: Sequence[float]) -> list[float]:
            count[0] += 1
            if count[0] > max_nfev:
                raise _BudgetExceeded(f"gave up after {max_nfev} right-hand-side evaluations")
            return base(t, y)

        y0 = [scene.x0, scene.v0]
        pieces = []
        steps = 0
        for a, b in zip(breaks[:-1], breaks[1:], strict=True):
            sol = solve_ivp(rhs, (a, b), y0, method=method, rtol=rtol, atol=atol, jac=jac,
                            dense_output=True)
            if sol.status < 0:
                raise RuntimeError(f"solve_ivp status {sol.status}: {sol.message}")
            pieces.append((b, sol.sol))
            steps += len(sol.t) - 1
            y0 = [float(sol.y[0, -1]), float(sol.y[1, -1])]
        x = np.empty_like(t_grid)
        lo = 0
        for b, dense in pieces:
            hi = int(np.searchsorted(t_grid, b, side="right"))
            x[lo:hi] = dense(t_grid[lo:hi])[0]
            lo = hi
        return Solved(t_grid, x, steps, count[0])

    return run
