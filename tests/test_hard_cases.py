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
from hypothesis import given
from hypothesis import strategies as st

from lumped.bingham import BinghamOscillator, integrate
from lumped.forcing import SineBurst, paper_F2, zero_forcing
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
class Solver:
    name: str
    order: int  # 1: BDF1 throughout; 2: BDF2 after a BDF1 first step
    run: Callable[..., Trajectory]


SOLVERS = (
    Solver("closed-bdf1", 1, _closed("bdf1")),
    Solver("closed-bdf2", 2, _closed("bdf2")),
)


# --------------------------------------------------------------------------- checks


def forcing_values(forcing, dt: float, n: int) -> np.ndarray:
    """``F(n dt)`` exactly as the steps evaluate it (``i * dt``)."""
    return np.array([float(forcing(i * dt)) for i in range(n + 1)])


def check_law(traj: Trajectory, osc: BinghamOscillator) -> None:
    """Law (6) at every sample, to ``TOL`` relative to ``|F_d|``."""
    v, Fd = traj.v, traj.F_d
    stuck = v == 0.0
    assert np.all(np.abs(Fd[stuck]) <= osc.tau * (1.0 + TOL)), "stuck beyond the yield force"
    s = np.sign(v[~stuck])
    expected = s * (osc.tau + np.abs(v[~stuck]) / osc.gamma)
    normal = np.abs(expected) >= TINY  # else F_d may underflow to 0
    assert np.all(np.sign(Fd[~stuck][normal]) == s[normal]), "sgn F_d != sgn v while slipping"
    bad = np.abs(Fd[~stuck] - expected) > TOL * np.abs(Fd[~stuck]) + TINY
    assert not np.any(bad), f"law (6) violated at {np.flatnonzero(bad)[:5]}"


def _assert_small(residual, scale, what: str) -> None:
    bad = np.abs(residual) > TOL * scale + TINY
    if np.any(bad):
        i = int(np.flatnonzero(bad)[0])
        raise AssertionError(
            f"{what}: residual {residual[i]!r} > {TOL:.1e} * scale {scale[i]!r} at step {i}"
        )


def check_balance(traj: Trajectory, osc: BinghamOscillator, F: np.ndarray, order: int) -> None:
    """The discrete ``x' = v`` and ``m v' = F - k x - F_d`` of the method, every step."""
    m, k = osc.m, osc.k
    x, v, Fd = traj.x, traj.v, traj.F_d
    dt = float(traj.t[1])  # t_1 = 1 * dt exactly
    # Step 1 (and every step for BDF1): backward Euler.
    last = len(x) if order == 1 else 2
    sl, pr = slice(1, last), slice(0, last - 1)
    _assert_small(x[sl] - x[pr] - dt * v[sl],
                  np.abs(x[sl]) + np.abs(x[pr]) + dt * np.abs(v[sl]), "BDF1 x' = v")
    force = F[sl] - k * x[sl] - Fd[sl]
    _assert_small(m * (v[sl] - v[pr]) / dt - force,
                  m * (np.abs(v[sl]) + np.abs(v[pr])) / dt + np.abs(F[sl])
                  + k * (np.abs(x[sl]) + np.abs(x[pr])) + np.abs(Fd[sl]),
                  "BDF1 m v' = F - k x - F_d")
    if order == 2 and len(x) > 2:
        n1, n0, nm = slice(2, None), slice(1, -1), slice(0, -2)
        _assert_small(3 * x[n1] - 4 * x[n0] + x[nm] - 2 * dt * v[n1],
                      3 * np.abs(x[n1]) + 4 * np.abs(x[n0]) + np.abs(x[nm])
                      + 2 * dt * np.abs(v[n1]), "BDF2 x' = v")
        force = F[n1] - k * x[n1] - Fd[n1]
        _assert_small(m * (3 * v[n1] - 4 * v[n0] + v[nm]) / (2 * dt) - force,
                      m * (3 * np.abs(v[n1]) + 4 * np.abs(v[n0]) + np.abs(v[nm])) / (2 * dt)
                      + np.abs(F[n1]) + k * (np.abs(x[n1]) + 4 * np.abs(x[n0]) + np.abs(x[nm]))
                      + np.abs(Fd[n1]), "BDF2 m v' = F - k x - F_d")


def energy(osc: BinghamOscillator, x, v):
    """``E = m v^2 / 2 + F_s^2 / (2 k)`` with ``F_s = k x``."""
    return 0.5 * osc.m * v * v + 0.5 * osc.k * x * x


def g_energy(osc: BinghamOscillator, x1, v1, x0, v0):
    r"""BDF2's two-step energy ``||(y_{n+1}, y_n)||_G^2``, ``G = [[5, -2], [-2, 1]] / 4``.

    In the energy inner product ``<y, z> = k x_y x_z + m v_y v_z`` this is
    ``(|y_{n+1}|^2 + |2 y_{n+1} - y_n|^2) / 4``, equal to ``E`` when ``y_{n+1} = y_n``.
    """
    return 0.25 * (osc.k * (x1 * x1 + (2 * x1 - x0) ** 2) + osc.m * (v1 * v1 + (2 * v1 - v0) ** 2))


def check_energy(traj: Trajectory, osc: BinghamOscillator, F: np.ndarray, order: int) -> None:
    """No energy created beyond the work ``dt F_{n+1} v_{n+1}`` of the forcing.

    BDF1 (and BDF2's first step): ``E_{n+1} - E_n = dt (F - F_d) v_{n+1}
    - m (dv)^2 / 2 - k (dx)^2 / 2 <= dt F v_{n+1}`` since ``F_d v >= 0``.
    BDF2 (``n >= 1``): ``Eg_{n+1} - Eg_n = dt (F - F_d) v_{n+1} - |y_{n+1} - 2 y_n
    + y_{n-1}|^2 / 4 <= dt F v_{n+1}``.  Unforced, BDF2 also has ``Eg_1 <= E_0``.
    """
    x, v = traj.x, traj.v
    dt = float(traj.t[1])
    E = energy(osc, x, v)
    work = dt * F[1:] * v[1:]
    last = len(x) if order == 1 else 2
    gain = E[1:last] - E[: last - 1] - work[: last - 1]
    scale = E[1:last] + E[: last - 1] + np.abs(work[: last - 1])
    _assert_small(np.maximum(gain, 0.0), scale, "BDF1 energy created")
    if order == 2 and len(x) > 2:
        Eg = g_energy(osc, x[1:], v[1:], x[:-1], v[:-1])  # Eg[j] pairs (y_{j+1}, y_j)
        gain = Eg[1:] - Eg[:-1] - work[1:]
        scale = Eg[1:] + Eg[:-1] + E[:-2] + E[1:-1] + E[2:] + np.abs(work[1:])
        _assert_small(np.maximum(gain, 0.0), scale, "BDF2 G-energy created")
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
    F = forcing_values(forcing, dt, n_steps)
    check_law(traj, osc)
    check_balance(traj, osc, F, solver.order)
    check_energy(traj, osc, F, solver.order)
    return traj


SOLVER_IDS = [s.name for s in SOLVERS]
solvers = pytest.mark.parametrize("solver", SOLVERS, ids=SOLVER_IDS)


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
    [_square(5.0, 0.37), _square(1.0 + 1e-12, 0.01), _steps([(0.1, 50.0), (0.35, -80.0),
                                                             (0.6, 0.0), (0.9, 1e6)])],
    ids=["square", "square-at-yield", "steps"],
)
def test_forcing_with_jumps(solver, forcing):
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    check_all(solver, osc, x0=0.0, forcing=forcing, dt=1e-3, n_steps=2000)


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


@solvers
@pytest.mark.parametrize("x0", [0.005, 0.1 / 100, 2.1060533511106927e-05, -0.0099999])
def test_stuck_state_held_without_drift(solver, x0):
    """``|k x0| <= tau``, no forcing: a million steps reproduce ``x0`` bit for bit."""
    osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)
    n = 1_000_000
    traj = solver.run(osc, x0=x0, v0=0.0, forcing=zero_forcing, dt=1e-3, n_steps=n)
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

def _log(lo: float, hi: float):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


@st.composite
def hard_problems(draw):
    m = draw(_log(1e-6, 1e6))
    k = draw(_log(1e-3, 1e10))
    gamma = draw(_log(1e-6, 1e12))
    tau = draw(st.one_of(st.just(0.0), _log(1e-6, 1e9)))
    w = math.sqrt(k / m)
    dt = draw(_log(1e-4, 1e4)) / w  # w dt from well resolved to very stiff
    scale = (tau + 1.0) / k
    x0 = draw(st.floats(-10.0, 10.0)) * scale
    v0 = draw(st.floats(-10.0, 10.0)) * scale * w
    forced = draw(st.booleans())
    forcing = (SineBurst(draw(st.floats(0.0, 5.0)) * (tau + 1.0),
                         draw(_log(1e-2, 1e2)) * w, draw(st.floats(0.0, 200.0)) * dt)
               if forced else zero_forcing)
    return BinghamOscillator(m, k, gamma, tau), x0, v0, forcing, dt


@solvers
@given(problem=hard_problems())
def test_invariants_hold_on_random_hard_problems(solver, problem):
    osc, x0, v0, forcing, dt = problem
    check_all(solver, osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=300)


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
        check_law(tamper(F_d=good.F_d * (1.0 + 1e-10)), osc)
    with pytest.raises(AssertionError):
        check_law(tamper(F_d=-good.F_d), osc)
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


@solvers
@given(x0=st.floats(-1.0, 1.0).filter(lambda x: x != 0.0), dt=_log(1e-9, 1.0))
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
