r"""Hard cases for the time-stepping solvers (not timed).

Each case runs every solver of :data:`SOLVERS` and checks, at every step:

* every value is finite and the solve did not fail;
* the Bingham law (6): ``v = 0`` and ``|F_d| <= tau``, or
  ``F_d = sgn(v) (tau + |v| / gamma)``;
* the discrete balance of the method (BDF1 or BDF2, BDF2's first step being BDF1)
  for both ``x' = v`` and ``m v' = F - k x - F_d``;
* no energy is created: ``E = m v^2 / 2 + k x^2 / 2`` for BDF1 and the G-norm
  two-step energy for BDF2 (derivation in ``docs/stability.md``) never grow by more
  than the work of the forcing, ``dt F_{n+1} v_{n+1}``.

Round-off tolerances.  Every checked relation is an identity in exact arithmetic.
Each computed quantity carries a relative error of a few units of round-off
``u = 2^-53`` per operation, and the steps use fewer than ten operations between
inputs and outputs, so a residual is bounded by a small multiple of ``u`` times the
*sum of the absolute values of the terms it is made of* (its ``scale``) -- not of
the residual's own size, which is zero.  We allow ``TOL = 64 u`` of that scale
(about ``7e-15``): comfortably above the few ``u`` that the steps can produce, and
eleven orders of magnitude below any modelling or discretisation error (the worst
ratio measured over this whole file is 4 u, in the BDF1 momentum balance), so a wrong
sign, a wrong coefficient or a lost term is still caught (see
``test_checks_catch_a_wrong_step``).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pytest
from _helpers import log_uniform
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped.scene import SineBurst, paper_F2, zero_forcing
from lumped.solvers.closed.closed_form import BinghamOscillator
from lumped.solvers.closed.integrate import integrate
from lumped.trajectory import Trajectory

U = 2.0**-53
TOL = 64 * U
#: Below the smallest normal float, numbers have a fixed absolute spacing (2^-1074)
#: and no relative accuracy: residuals that small are accepted (stiff decays reach
#: the subnormal range in a few hundred steps).
TINY = float(np.finfo(float).tiny)


# --------------------------------------------------------------------------- solvers


def _closed(method: str) -> Callable[..., Trajectory]:
    def run(osc, *, x0, v0, forcing, dt, n_steps):
        return integrate(osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=n_steps,
                         method=method)

    return run


@dataclass(frozen=True)
class Tol:
    """Allowed residual: ``rel * scale + force * (the force-to-units factor of the check)``."""

    rel: float
    force: float


#: The closed form: pure round-off (module docstring).
ROUNDOFF = Tol(TOL, 0.0)


def _newton_tol() -> Tol:
    """The generic solver: its Newton stops at ``|G_i| <= rtol S_i + atol`` (defaults
    ``1e-10, 1e-12``, rows in force units); we allow ten times that."""
    from lumped.solvers.newton.options import NewtonOptions

    opts = NewtonOptions()
    return Tol(10.0 * opts.rtol, 10.0 * opts.atol)


@dataclass(frozen=True)
class Solver:
    name: str
    order: int  # 1: BDF1 throughout; 2: BDF2 after a BDF1 first step
    run: Callable[..., Trajectory]
    tol: Tol = ROUNDOFF


def _generic(method: str) -> Callable[..., Trajectory]:
    """The generic semismooth-Newton steps of :func:`lumped.simulate.simulate`."""

    def run(osc, *, x0, v0, forcing, dt, n_steps):
        from lumped.laws import get_law
        from lumped.scene import Element, Mass, Scene
        from lumped.simulate import simulate

        scene = Scene(
            [Mass("mass", m=osc.m, x0=x0, v0=v0)],
            [Element("spring", get_law("linear_spring").bind(k=osc.k), "ground", "mass"),
             Element("dashpot", get_law("bingham").bind(gamma=osc.gamma, tau=osc.tau),
                     "ground", "mass")],
            {"mass": forcing},
        )
        sol = simulate(scene, method=method, dt=dt, t_end=n_steps * dt, throw=False)
        assert sol.ok, f"failed solve: {sol.status} {sol.message}"
        assert sol.stats["steps"] == n_steps
        x = sol.column("x_mass")
        return Trajectory(sol.t, x, sol.column("v_mass"), sol.column("F_spring"),
                          sol.column("F_dashpot"), method=f"generic-{method}",
                          stats=dict(sol.stats))

    return run


SOLVERS = (
    Solver("closed-bdf1", 1, _closed("bdf1")),
    Solver("closed-bdf2", 2, _closed("bdf2")),
    Solver("generic-bdf1", 1, _generic("bdf1"), _newton_tol()),
    Solver("generic-bdf2", 2, _generic("bdf2"), _newton_tol()),
)


# --------------------------------------------------------------------------- checks


def forcing_values(forcing, t: np.ndarray) -> np.ndarray:
    """``F(t_n)`` on the solver's own grid (``t_n = n * dt``, as the steps evaluate it)."""
    return np.array([float(forcing(float(ti))) for ti in t])


def check_law(
    traj: Trajectory, osc: BinghamOscillator, F: np.ndarray, tol: Tol = ROUNDOFF,
) -> None:
    """Law (6) at every sample, to round-off.

    Every sample must lie on one branch of the law:

    * stick: ``|F_d| <= tau`` and ``v = 0`` -- exactly ``0`` for the closed form; an
      iterative solver may leave a round-off velocity, accepted when
      ``m |v| / dt <= TOL * S`` (``S`` the scale of the momentum balance, see
      :func:`check_balance`: the velocity a round-off force residual produces);
    * slip: ``sgn F_d = sgn v`` and ``F_d = sgn(v) (tau + |v| / gamma)`` to ``TOL |F_d|``.
    """
    m, k, tau = osc.m, osc.k, osc.tau
    x, v, Fd = traj.x, traj.v, traj.F_d
    dt = float(traj.t[1])
    x_prev = np.concatenate([[x[0]], x[:-1]])
    v_prev = np.concatenate([[v[0]], v[:-1]])
    S = m * (np.abs(v) + np.abs(v_prev)) / dt + np.abs(F) + k * (np.abs(x) + np.abs(x_prev)) \
        + np.abs(Fd)
    within = np.abs(Fd) <= tau * (1.0 + tol.rel) + tol.force
    stick = within & ((v == 0.0) | (m * np.abs(v) / dt <= tol.rel * S + tol.force + TINY))
    sv = np.sign(v)
    expected = sv * (tau + np.abs(v) / osc.gamma)
    slip = (v != 0.0) & (np.abs(Fd - expected) <= tol.rel * np.abs(Fd) + tol.force + TINY) \
        & ((np.sign(Fd) == sv) | (np.abs(expected) < TINY))  # F_d may underflow to 0
    bad = ~(stick | slip)
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise AssertionError(
            f"law (6) violated at step {i}: v = {v[i]!r}, F_d = {Fd[i]!r}, tau = {tau!r}"
        )
    assert np.all(np.abs(Fd[v == 0.0]) <= tau * (1.0 + tol.rel) + tol.force), \
        "stuck beyond the yield force"


def _assert_small(residual, scale, what: str, tol: Tol = ROUNDOFF, force_units=0.0) -> None:
    """``|residual| <= tol.rel * scale + tol.force * force_units`` (+ the subnormal floor)."""
    bad = np.abs(residual) > tol.rel * scale + tol.force * force_units + TINY
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise AssertionError(
            f"{what}: residual {residual[i]!r} > {tol.rel:.1e} * scale {scale[i]!r} "
            f"(+ {tol.force:.1e} in force units) at step {i}"
        )


def check_balance(
    traj: Trajectory, osc: BinghamOscillator, F: np.ndarray, order: int, tol: Tol = ROUNDOFF,
) -> None:
    """The discrete ``x' = v`` and ``m v' = F - k x - F_d`` of the method, every step.

    A force residual ``r`` of the solver moves ``v`` by ``dt r / m`` and ``x`` by
    ``dt^2 r / m``: the factors applied to ``tol.force``.
    """
    m, k = osc.m, osc.k
    x, v, Fd = traj.x, traj.v, traj.F_d
    dt = float(traj.t[1])  # t_1 = 1 * dt exactly
    # Step 1 (and every step for BDF1): backward Euler.
    last = len(x) if order == 1 else 2
    sl, pr = slice(1, last), slice(0, last - 1)
    _assert_small(x[sl] - x[pr] - dt * v[sl],
                  np.abs(x[sl]) + np.abs(x[pr]) + dt * np.abs(v[sl]), "BDF1 x' = v",
                  tol, dt * dt / m)
    force = F[sl] - k * x[sl] - Fd[sl]
    _assert_small(m * (v[sl] - v[pr]) / dt - force,
                  m * (np.abs(v[sl]) + np.abs(v[pr])) / dt + np.abs(F[sl])
                  + k * (np.abs(x[sl]) + np.abs(x[pr])) + np.abs(Fd[sl]),
                  "BDF1 m v' = F - k x - F_d", tol, 1.0)
    if order == 2 and len(x) > 2:
        n1, n0, nm = slice(2, None), slice(1, -1), slice(0, -2)
        _assert_small(3 * x[n1] - 4 * x[n0] + x[nm] - 2 * dt * v[n1],
                      3 * np.abs(x[n1]) + 4 * np.abs(x[n0]) + np.abs(x[nm])
                      + 2 * dt * np.abs(v[n1]), "BDF2 x' = v", tol, dt * dt / m)
        force = F[n1] - k * x[n1] - Fd[n1]
        _assert_small(m * (3 * v[n1] - 4 * v[n0] + v[nm]) / (2 * dt) - force,
                      m * (3 * np.abs(v[n1]) + 4 * np.abs(v[n0]) + np.abs(v[nm])) / (2 * dt)
                      + np.abs(F[n1]) + k * (np.abs(x[n1]) + 4 * np.abs(x[n0]) + np.abs(x[nm]))
                      + np.abs(Fd[n1]), "BDF2 m v' = F - k x - F_d", tol, 1.0)


def energy(osc: BinghamOscillator, x, v):
    """``E = m v^2 / 2 + F_s^2 / (2 k)`` with ``F_s = k x``."""
    return 0.5 * osc.m * v * v + 0.5 * osc.k * x * x


def g_energy(osc: BinghamOscillator, x1, v1, x0, v0):
    r"""BDF2's two-step energy ``||(y_{n+1}, y_n)||_G^2``, ``G = [[5, -2], [-2, 1]] / 4``.

    In the energy inner product ``<y, z> = k x_y x_z + m v_y v_z`` this is
    ``(|y_{n+1}|^2 + |2 y_{n+1} - y_n|^2) / 4``, equal to ``E`` when ``y_{n+1} = y_n``.
    """
    return 0.25 * (osc.k * (x1 * x1 + (2 * x1 - x0) ** 2) + osc.m * (v1 * v1 + (2 * v1 - v0) ** 2))


def check_energy(
    traj: Trajectory, osc: BinghamOscillator, F: np.ndarray, order: int, tol: Tol = ROUNDOFF,
) -> None:
    """No energy created beyond the work ``dt F_{n+1} v_{n+1}`` of the forcing.

    BDF1 (and BDF2's first step): ``E_{n+1} - E_n = dt (F - F_d) v_{n+1}
    - m (dv)^2 / 2 - k (dx)^2 / 2 <= dt F v_{n+1}`` since ``F_d v >= 0``.
    BDF2 (``n >= 1``): ``Eg_{n+1} - Eg_n = dt (F - F_d) v_{n+1} - |y_{n+1} - 2 y_n
    + y_{n-1}|^2 / 4 <= dt F v_{n+1}``.  Unforced, BDF2 also has ``Eg_1 <= E_0``.
    A force residual ``r`` of a solver does work of at most ``r`` times the distance
    ``|x_{n+1}| + |x_n| + dt (|v_{n+1}| + |v_n|)``: the factor applied to ``tol.force``.
    A round-off velocity left on the stick branch (accepted by :func:`check_law`) makes
    ``dt F_d v`` of either sign: its size is added to the allowance (it is zero for the
    closed form, whose stuck velocity is exactly 0).
    """
    x, v = traj.x, traj.v
    dt = float(traj.t[1])
    E = energy(osc, x, v)
    work = dt * F[1:] * v[1:]
    on_stick = np.abs(traj.F_d[1:]) <= osc.tau * (1.0 + tol.rel) + tol.force
    work = work + np.where(on_stick, dt * np.abs(traj.F_d[1:] * v[1:]), 0.0)
    reach = np.abs(x[1:]) + np.abs(x[:-1]) + dt * (np.abs(v[1:]) + np.abs(v[:-1]))
    last = len(x) if order == 1 else 2
    gain = E[1:last] - E[: last - 1] - work[: last - 1]
    scale = E[1:last] + E[: last - 1] + np.abs(work[: last - 1])
    _assert_small(np.maximum(gain, 0.0), scale, "BDF1 energy created", tol, reach[: last - 1])
    if order == 2 and len(x) > 2:
        Eg = g_energy(osc, x[1:], v[1:], x[:-1], v[:-1])  # Eg[j] pairs (y_{j+1}, y_j)
        gain = Eg[1:] - Eg[:-1] - work[1:]
        scale = Eg[1:] + Eg[:-1] + E[:-2] + E[1:-1] + E[2:] + np.abs(work[1:])
        _assert_small(np.maximum(gain, 0.0), scale, "BDF2 G-energy created", tol,
                      reach[1:] + reach[:-1])
        if not np.any(F):
            _assert_small(np.array([max(Eg[0] - E[0], 0.0)]), np.array([E[0] + E[1]]),
                          "BDF2 first G-energy above E_0")


def check_all(
    solver: Solver, osc: BinghamOscillator, *, x0: float, v0: float = 0.0,
    forcing=zero_forcing, dt: float, n_steps: int,
) -> Trajectory:
    traj = solver.run(osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=n_steps)
    assert len(traj) == n_steps + 1
    for name in ("x", "v", "F_s", "F_d"):
        assert np.all(np.isfinite(getattr(traj, name))), name
    F = forcing_values(forcing, traj.t)
    check_law(traj, osc, F, solver.tol)
    check_balance(traj, osc, F, solver.order, solver.tol)
    check_energy(traj, osc, F, solver.order, solver.tol)
    return traj


SOLVER_IDS = [s.name for s in SOLVERS]
solvers = pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)
CLOSED = SOLVERS[:2]
GENERIC = SOLVERS[2:]


# --------------------------------------------------------------------------- cases


@solvers
@pytest.mark.parametrize("gamma", [1e-6, 1e-3, 1.0, 1e3, 1e6, 1e12])
@pytest.mark.parametrize("forced", [False, True], ids=["release", "forced"])
def test_gamma_range(solver, gamma, forced):
    osc = BinghamOscillator(1.0, 100.0, gamma, 1.0)
    traj = check_all(solver, osc, x0=0.0 if forced else 0.5,
                     forcing=paper_F2 if forced else zero_forcing, dt=1e-3, n_steps=10_000)
    if gamma >= 1e3 and not forced:
        # Near-Coulomb free decay (4 tau / k = 0.04 lost per period of 0.63 s) has
        # stopped inside the yield band by t = 10.
        assert traj.v[-1] == 0.0 and abs(osc.k * traj.x[-1]) <= osc.tau


@solvers
@pytest.mark.parametrize("k", [1e-3, 1.0, 1e3, 1e6, 1e10])
@pytest.mark.parametrize("w_dt", [1e-2, 1e2, 1e4])
def test_stiffness_range(solver, k, w_dt):
    """``w dt`` up to 1e4: the implicit steps stay stable and dissipative."""
    osc = BinghamOscillator(1.0, k, 1.0, 1.0)
    w = math.sqrt(k / osc.m)
    dt = w_dt / w
    traj = check_all(solver, osc, x0=10.0 * osc.tau / k, v0=0.0, dt=dt, n_steps=2000)
    if w_dt >= 1e2:  # L-stable: no spurious oscillation survives
        assert abs(osc.k * traj.x[-1]) <= 10.0 * osc.tau


@solvers
@pytest.mark.parametrize("dt", [1e-9, 1e-6, 1e-3, 1e-1, 1.0])
@pytest.mark.parametrize("forced", [False, True], ids=["release", "forced"])
def test_dt_range(solver, dt, forced):
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    check_all(solver, osc, x0=0.0 if forced else 0.5, v0=0.3,
              forcing=paper_F2 if forced else zero_forcing, dt=dt, n_steps=3000)


@solvers
@pytest.mark.parametrize("tau", [0.0, 1e-9, 1e-3, 1.0, 1e3, 1e9])
def test_yield_force_range(solver, tau):
    osc = BinghamOscillator(1.0, 100.0, 1.0, tau)
    x0 = (3.0 * tau + 1.0) / osc.k
    check_all(solver, osc, x0=x0, dt=1e-3, n_steps=5000)
    check_all(solver, osc, x0=0.0, forcing=SineBurst(2.0 * tau + 1.0, 5 * math.pi, 1.0),
              dt=1e-3, n_steps=3000)


def _square(amplitude: float, period: float) -> Callable[[float], float]:
    def F(t: float) -> float:
        return amplitude if math.floor(2.0 * t / period) % 2 == 0 else -amplitude

    return F


def _steps(levels: list[tuple[float, float]]) -> Callable[[float], float]:
    def F(t: float) -> float:
        value = 0.0
        for start, level in levels:
            if t >= start:
                value = level
        return value

    return F


@solvers
@pytest.mark.parametrize(
    "forcing",
    [_square(5.0, 0.37), _steps([(0.1, 50.0), (0.35, -80.0), (0.6, 0.0), (0.9, 1e6)])],
    ids=["square", "steps"],
)
def test_forcing_with_jumps(solver, forcing):
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    check_all(solver, osc, x0=0.0, forcing=forcing, dt=1e-3, n_steps=2000)


@solvers
def test_square_forcing_a_hair_above_the_yield_force(solver):
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    check_all(solver, osc, x0=0.0, forcing=_square(1.0 + 1e-12, 0.01), dt=1e-3, n_steps=2000)


@solvers
@pytest.mark.parametrize("dt", [1e-5, 1e-4, 1e-3])
def test_rapid_stick_slip(solver, dt):
    """Forcing just above the yield force at 100 Hz: stick and slip alternate quickly."""
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    F = SineBurst(1.5, 200.0 * math.pi, math.inf)
    traj = check_all(solver, osc, x0=0.0, forcing=F, dt=dt, n_steps=int(round(0.5 / dt)))
    moving = traj.v != 0.0
    switches = np.count_nonzero(moving[1:] != moving[:-1])
    if dt <= 1e-4:
        assert switches >= 50, switches  # 100 breakouts in 0.5 s, each ending in a stick


@pytest.mark.parametrize("solver", CLOSED, ids=[s.name for s in CLOSED])
@pytest.mark.parametrize("x0", [0.005, 0.1 / 100, 2.1060533511106927e-05, -0.0099999])
def test_stuck_state_held_without_drift(solver, x0):
    """``|k x0| <= tau``, no forcing: a million steps reproduce ``x0`` bit for bit."""
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    n = 1_000_000
    traj = solver.run(osc, x0=x0, v0=0.0, forcing=zero_forcing, dt=1e-3, n_steps=n)
    assert np.all(traj.x == x0)
    assert np.all(traj.v == 0.0)
    assert np.all(traj.F_d == -osc.k * x0)


@pytest.mark.parametrize("solver", GENERIC, ids=[s.name for s in GENERIC])
def test_generic_stuck_state_held_without_drift(solver):
    """As above for the generic solver (1e5 steps: its steps cost ~10 us)."""
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    x0 = 2.1060533511106927e-05  # (4 x0 - x0) / 3 != x0 in floating point
    traj = solver.run(osc, x0=x0, v0=0.0, forcing=zero_forcing, dt=1e-3, n_steps=100_000)
    assert np.all(traj.x == x0)
    assert np.all(traj.v == 0.0)
    assert np.all(traj.F_d == -osc.k * x0)


@solvers
@pytest.mark.parametrize("dt", [1e-9, 1e-6, 1e-3])
def test_huge_and_tiny_scales(solver, dt):
    """``m = 1e-6, k = 1e6`` (``w = 1e6``): resolved, moderately and very stiff."""
    osc = BinghamOscillator(1e-6, 1e6, 1e-3, 1e-2)
    check_all(solver, osc, x0=1e-6, v0=1.0, dt=dt, n_steps=3000)
    check_all(solver, osc, x0=0.0, forcing=SineBurst(0.05, 1e5, math.inf), dt=dt,
              n_steps=3000)


# --------------------------------------------------------------------------- properties

@st.composite
def hard_problems(draw):
    m = draw(log_uniform(1e-6, 1e6))
    k = draw(log_uniform(1e-3, 1e10))
    gamma = draw(log_uniform(1e-6, 1e12))
    tau = draw(st.one_of(st.just(0.0), log_uniform(1e-6, 1e9)))
    w = math.sqrt(k / m)
    dt = draw(log_uniform(1e-4, 1e4)) / w  # w dt from well resolved to very stiff
    scale = (tau + 1.0) / k
    x0 = draw(st.floats(-10.0, 10.0)) * scale
    v0 = draw(st.floats(-10.0, 10.0)) * scale * w
    forced = draw(st.booleans())
    forcing = (SineBurst(draw(st.floats(0.0, 5.0)) * (tau + 1.0),
                         draw(log_uniform(1e-2, 1e2)) * w, draw(st.floats(0.0, 200.0)) * dt)
               if forced else zero_forcing)
    return BinghamOscillator(m, k, gamma, tau), x0, v0, forcing, dt


@pytest.mark.parametrize("solver", CLOSED, ids=[s.name for s in CLOSED])
@given(problem=hard_problems())
def test_invariants_hold_on_random_hard_problems(solver, problem):
    osc, x0, v0, forcing, dt = problem
    check_all(solver, osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=300)


@pytest.mark.parametrize("solver", GENERIC, ids=[s.name for s in GENERIC])
@settings(max_examples=100)  # ~10 us per generic step and a scene per example
@given(problem=hard_problems())
def test_invariants_hold_on_random_hard_problems_generic(solver, problem):
    osc, x0, v0, forcing, dt = problem
    check_all(solver, osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=100)


# --------------------------------------------------------------------------- the checks can fail


def test_checks_catch_a_wrong_step():
    """A step with a slightly wrong coefficient or sign must fail the checks."""
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    good = integrate(osc, x0=0.5, dt=1e-3, n_steps=400)
    F = np.zeros(len(good))
    check_balance(good, osc, F, 1)
    check_energy(good, osc, F, 1)

    def tamper(**changes):
        fields = {n: getattr(good, n) for n in ("t", "x", "v", "F_s", "F_d")}
        fields.update(changes)
        return Trajectory(**fields, method="tampered")

    v_up = good.v * (1.0 + 1e-10)
    with pytest.raises(AssertionError):
        check_balance(tamper(v=v_up), osc, F, 1)
    with pytest.raises(AssertionError):
        check_law(tamper(F_d=good.F_d * (1.0 + 1e-10)), osc, F)
    with pytest.raises(AssertionError):
        check_law(tamper(F_d=-good.F_d), osc, F)
    stuck = integrate(osc, x0=0.005, dt=1e-3, n_steps=10)
    with pytest.raises(AssertionError):  # a stuck mass that creeps
        check_law(Trajectory(stuck.t, stuck.x, stuck.v + 1e-9, stuck.F_s, stuck.F_d,
                             method="tampered"), osc, np.zeros(11))
    # A 0.1 % kick to an undamped oscillator (tau = 0, gamma = 1e12), on which BDF1
    # dissipates only ~(w dt)^2 / 2 = 5e-5 of E per step.
    free = BinghamOscillator(1.0, 100.0, 1e12, 0.0)
    run = integrate(free, x0=0.5, dt=1e-3, n_steps=400)
    check_energy(run, free, F, 1)
    x, v = run.x.copy(), run.v.copy()
    x[200:] *= 1.0 + 1e-3
    v[200:] *= 1.0 + 1e-3
    kicked = Trajectory(run.t, x, v, free.k * x, run.F_d, method="tampered")
    with pytest.raises(AssertionError):
        check_energy(kicked, free, F, 1)
    # BDF1 data checked as BDF2 fails the BDF2 balance.
    with pytest.raises(AssertionError):
        check_balance(good, osc, F, 2)


@pytest.mark.parametrize("solver", CLOSED, ids=[s.name for s in CLOSED])
@given(x0=st.floats(-1.0, 1.0).filter(lambda x: x != 0.0), dt=log_uniform(1e-9, 1.0))
def test_random_stuck_states_are_exact(solver, x0, dt):
    """Any ``|k x0| <= tau`` is an exact fixed point of both steps (no round-off drift)."""
    osc = BinghamOscillator(1.0, 1.0, 1.0, 1.0)
    traj = solver.run(osc, x0=x0, v0=0.0, forcing=zero_forcing, dt=dt, n_steps=1000)
    assert np.all(traj.x == x0) and np.all(traj.v == 0.0)


def test_bdf2_plain_energy_can_grow_but_its_g_energy_cannot():
    """Why BDF2 needs the two-step energy: ``E_n`` itself is not monotone."""
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    traj = integrate(osc, x0=0.5, dt=1e-2, n_steps=200, method="bdf2")
    E = energy(osc, traj.x, traj.v)
    assert np.max(np.diff(E) / E[:-1]) > 1e-4  # measured: +4e-4 E_n at step 31
    Eg = g_energy(osc, traj.x[1:], traj.v[1:], traj.x[:-1], traj.v[:-1])
    assert np.all(np.diff(Eg) <= 0.0) and Eg[0] <= E[0]
