r"""Closed-form steps for one mass, a linear spring and a Bingham dashpot.

The model (paper eqs. 5, 6, 8a-8c), with ``tau = mu_s N_f``::

    m v' = F(t) - F_s - F_d,     x' = v,     F_s = k x,
    v = gamma (F_d - clip(F_d, -tau, tau))          (Bingham law, eq. 6)

Sign convention: ``x`` and ``v`` are positive in the same direction as ``F``;
``F_s`` and ``F_d`` are the forces the spring and the dashpot exert *against*
that direction, so a stretched spring (``x > 0``) has ``F_s > 0``.

One step of BDF1 (backward Euler) or BDF2 reduces to one piecewise-linear scalar
equation in ``F_d`` (see ``docs/theory/bdf_steps.md``).  Write ``h`` for the effective step
(``dt`` for BDF1, ``2 dt / 3`` for BDF2) and ``x_hat, v_hat`` for the history
(``x_n, v_n`` for BDF1, ``(4 x_n - x_{n-1}) / 3`` etc. for BDF2).  Then::

    a v = c (F~ - F_d),     a = 1 + h^2 k / m,    c = h / m,
    F~  = (m / h) v_hat + F(t_{n+1}) - k x_hat      (predictor, eq. 15b)

and ``sgn(F~) = sgn(F_d)`` (eq. 16).  The corrector (Algorithm 1) follows:
stick (``v = 0, F_d = F~``) when ``|F~| <= tau``, otherwise slip with::

    |v| = (c / (a + c / gamma)) e,   |F_d| = tau + |v| / gamma,   e = |F~| - tau > 0.

This is Algorithm 1's line 8-9 rearranged so that ``F_d - sgn(F_d) tau`` is never
formed by subtraction: the excess ``e`` is computed once from the known predictor,
so no digits are lost as ``gamma -> infinity`` (the Coulomb limit, Remark 2.1),
where the same formulas hold with ``1 / gamma = 0``.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

from ..._validate import as_finite, as_nonnegative, as_positive
from ...grid import steps_for  # (public here too: lumped.grid holds it)

__all__ = [
    "BinghamOscillator",
    "correct",
    "bdf1_step",
    "bdf2_step",
    "initial_dashpot_force",
    "initial_velocity",
    "limit_step_velocity",
    "steps_for",
    "CLOSED_METHODS",
    "run_bdf1_loop",
    "run_bdf2_loop",
    "checked_force",
]

#: Step formulas of the closed form, by the name used on the command line.
CLOSED_METHODS = ("bdf1", "bdf2")



@dataclass(frozen=True)
class BinghamOscillator:
    """Mass ``m``, linear spring ``k``, Bingham dashpot ``(gamma, tau = mu_s N_f)``.

    Examples
    --------
    >>> from lumped.solvers.closed.integrate import integrate
    >>> osc = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)
    >>> traj = integrate(osc, x0=0.5, dt=1e-4, t_end=5.0)
    >>> bool(traj.v[-1] == 0.0 and 0.0 < abs(traj.x[-1]) <= osc.tau / osc.k)
    True
    """

    m: float
    k: float
    gamma: float
    tau: float

    def __post_init__(self) -> None:
        for name in ("m", "k", "gamma"):
            object.__setattr__(self, name, as_positive(name, getattr(self, name)))
        object.__setattr__(self, "tau", as_nonnegative("mu_s N_f (tau)", self.tau))


def correct(
    F_tilde: float, tau: float, c: float, a: float, inv_gamma: float
) -> tuple[float, float]:
    """Solve ``a v = c (F~ - F_d)`` together with the Bingham law for ``(v, F_d)``.

    Parameters
    ----------
    F_tilde : float
        The predictor ``F~`` (eq. 15b, or its BDF2 twin).
    tau : float
        Yield force ``mu_s N_f >= 0``.
    c, a : float
        ``h / m`` and ``1 + h^2 k / m`` for the effective step ``h``.
    inv_gamma : float
        ``1 / gamma``; ``0.0`` gives the Coulomb limit.

    Returns
    -------
    v, F_d : float
        With ``sgn(F_d) = sgn(F~)`` (eq. 16) and ``|F_d| <= tau`` when ``v = 0``.
    """
    excess = abs(F_tilde) - tau
    if excess <= 0.0:
        return 0.0, F_tilde
    # c / (a + c / gamma) and m / h (below) are the same in every step of a run: a
    # compiled loop (lumped.solvers.closed.closed_form_jit) hoists them, leaving no division
    # in the step; the compiled twin does these operations in this order, bit for bit.
    speed = c / (a + c * inv_gamma) * excess
    if F_tilde > 0.0:
        return speed, tau + speed * inv_gamma
    return -speed, -(tau + speed * inv_gamma)


def bdf1_step(
    m: float, k: float, inv_gamma: float, tau: float, dt: float,
    x_n: float, v_n: float, F_next: float,
) -> tuple[float, float, float, float]:
    """Algorithm 1: one backward-Euler step from ``(x_n, v_n)``.

    Returns ``(x, v, F_d, F~)`` at ``t_{n+1}``; the spring force is ``k x``.
    """
    c = dt / m
    F_tilde = m / dt * v_n + F_next - k * x_n
    v, F_d = correct(F_tilde, tau, c, 1.0 + dt * dt * k / m, inv_gamma)
    return x_n + dt * v, v, F_d, F_tilde


def bdf2_step(
    m: float, k: float, inv_gamma: float, tau: float, dt: float,
    x_n: float, v_n: float, x_prev: float, v_prev: float, F_next: float,
) -> tuple[float, float, float, float]:
    """One BDF2 step from ``(x_n, v_n)`` and ``(x_{n-1}, v_{n-1})``.

    BDF2 reads ``(3 y_{n+1} - 4 y_n + y_{n-1}) / (2 dt) = y'_{n+1}``, i.e. a backward
    Euler step of size ``h = 2 dt / 3`` from the history ``(4 y_n - y_{n-1}) / 3``.
    Returns ``(x, v, F_d, F~)`` at ``t_{n+1}``.
    """
    h = 2.0 * dt / 3.0
    # (4 y_n - y_{n-1}) / 3 written as an increment, so that a stuck state
    # (x_n == x_{n-1}, v = 0) is reproduced bit for bit: (4 x - x) / 3 != x in
    # floating point for about one x in seven.
    x_hat = x_n + (x_n - x_prev) * (1.0 / 3.0)
    v_hat = v_n + (v_n - v_prev) * (1.0 / 3.0)
    c = h / m
    F_tilde = m / h * v_hat + F_next - k * x_hat
    v, F_d = correct(F_tilde, tau, c, 1.0 + h * h * k / m, inv_gamma)
    return x_hat + h * v, v, F_d, F_tilde


def initial_dashpot_force(osc: BinghamOscillator, x0: float, v0: float, F0: float,
                          h: float = 0.0) -> float:
    """The consistent ``F_d(0)`` that the limit ``dt -> 0`` of the steps selects.

    Slipping (``v0 != 0``): ``F_d = sgn(v0) tau + v0 / gamma`` from eq. (6).
    At rest the law only asks ``|F_d| <= tau``; we take the force that keeps the
    mass at rest if it can, ``clip(F(0) - k x0, -tau, tau)``.  (The paper's choice
    ``F_d(0) = 0`` is also admissible; it agrees with ours whenever ``F(0) = k x0``.)

    With a limit step ``h > 0`` (``integrate`` passes ``1e-20 dt``, as
    :func:`lumped.solvers.implicit.initial_state.consistent_initial_state` does), a
    ``v0`` that the step reverses or stops, ``fl(v0 + h a)`` 0 or of the other sign with
    ``a = (F(0) - k x0 - F_d) / m`` (``v0 = 1e-113`` under a load past ``tau`` the other
    way), counts as rest: the force is that of the slip or the stick that follows, with
    the sign of relation (16) (:mod:`lumped.solvers.implicit.initial_slip`).
    """
    if initial_velocity(osc, x0, v0, F0, h) != 0.0:
        return math.copysign(osc.tau, v0) + v0 / osc.gamma
    return min(max(F0 - osc.k * x0, -osc.tau), osc.tau)


def initial_velocity(osc: BinghamOscillator, x0: float, v0: float, F0: float,
                     h: float = 0.0) -> float:
    """``v0``, or 0 when the limit step ``h > 0`` reverses or stops it (see
    :func:`initial_dashpot_force`): the mass then starts at rest, a change of ``v0``
    below ``h |a|``, so that row 0 holds law (6). The rule is
    :func:`limit_step_velocity`'s."""
    return limit_step_velocity(osc.m, osc.k, 1.0 / osc.gamma, osc.tau, x0, v0, F0, h)


def limit_step_velocity(m: float, k: float, inv_gamma: float, tau: float, x0: float,
                        v0: float, F0: float, h: float) -> float:
    r"""``v0``, or 0 when the limit step ``h > 0`` reverses or stops it:

    .. math:: v_h = \operatorname{fl}\Bigl(v_0 + h\,\frac{F(0) - k x_0 - (\operatorname{sgn}(v_0)
              \tau + v_0 / \gamma)}{m}\Bigr) = 0 \ \text{ or }\ \operatorname{sgn} v_h
              \ne \operatorname{sgn} v_0

    (``F0`` the forcing at ``t = 0``; ``inv_gamma = 1 / gamma``). The one rule of
    :func:`initial_velocity` and of the compiled summaries
    (:func:`lumped.solvers.closed.closed_form_jit.summary_one` compiles this code)."""
    if v0 == 0.0 or h == 0.0:
        return v0
    v_h = v0 + h * (F0 - k * x0 - (math.copysign(tau, v0) + v0 * inv_gamma)) / m
    return v0 if v_h != 0.0 and (v_h > 0.0) == (v0 > 0.0) else 0.0


_Columns = tuple[list[float], list[float], list[float], list[float]]


def _columns(x0: float, v0: float, Fd0: float, n: int) -> _Columns:
    """Preallocated ``x, v, F_d, F~`` columns of ``n + 1`` samples, row 0 filled in."""
    return [x0] * (n + 1), [v0] * (n + 1), [Fd0] * (n + 1), [Fd0] * (n + 1)


def run_bdf1_loop(
    osc: BinghamOscillator, forcing: Callable[[float], float],
    x: float, v: float, Fd0: float, dt: float, n: int,
) -> _Columns:
    """The BDF1 loop on Python floats (Algorithm 1 step by step)."""
    m, k, tau, inv_gamma = osc.m, osc.k, osc.tau, 1.0 / osc.gamma
    xs, vs, Fds, Fts = _columns(x, v, Fd0, n)
    isfinite = math.isfinite
    for i in range(1, n + 1):
        F = forcing(i * dt)
        if not isfinite(F):
            raise ValueError(f"`forcing` returned {F!r} at t = {i * dt!r}")
        x, v, Fds[i], Fts[i] = bdf1_step(m, k, inv_gamma, tau, dt, x, v, F)
        xs[i] = x
        vs[i] = v
    return xs, vs, Fds, Fts


def run_bdf2_loop(
    osc: BinghamOscillator, forcing: Callable[[float], float],
    x: float, v: float, Fd0: float, dt: float, n: int,
) -> _Columns:
    """The BDF2 loop on Python floats; its first step is BDF1."""
    m, k, tau, inv_gamma = osc.m, osc.k, osc.tau, 1.0 / osc.gamma
    xs, vs, Fds, Fts = _columns(x, v, Fd0, n)
    isfinite = math.isfinite
    x_prev, v_prev = x, v
    x, v, Fds[1], Fts[1] = bdf1_step(m, k, inv_gamma, tau, dt, x, v, checked_force(forcing, dt))
    xs[1], vs[1] = x, v
    for i in range(2, n + 1):
        F = forcing(i * dt)
        if not isfinite(F):
            raise ValueError(f"`forcing` returned {F!r} at t = {i * dt!r}")
        x_new, v_new, Fds[i], Fts[i] = bdf2_step(
            m, k, inv_gamma, tau, dt, x, v, x_prev, v_prev, F
        )
        x_prev, v_prev, x, v = x, v, x_new, v_new
        xs[i] = x
        vs[i] = v
    return xs, vs, Fds, Fts


def checked_force(forcing: Callable[[float], float], t: float) -> float:
    """``forcing(t)``, checked finite (the error names ``forcing`` and ``t``)."""
    F = forcing(t)
    try:
        return as_finite("forcing", F)
    except (TypeError, ValueError) as err:
        raise type(err)(f"{err} at t = {t!r}") from None
