r"""Work-precision benchmark: error against the exact reference versus CPU time.

Every run integrates one *scene* (one mass, a linear spring and a Bingham dashpot,
``m v' = F(t) - k x - F_d``, law (6)) on ``[0, t_end]`` and is scored against the
event-driven exact solution of :mod:`lumped.reference`:

* ``max_err`` -- ``max |x - x_ref|`` over the common grid ``t_i = i * GRID_DT`` on
  ``[0, t_end]``.  Time-stepping methods are scored at their own nodes ``t_n = n dt``
  (no interpolation): at every node on the common grid when ``dt <= GRID_DT``, at
  every node (each of which lies on the grid) when ``dt > GRID_DT``.  The scipy runs
  are scored on their dense output at every grid point.
* ``end_err`` -- ``|x(t_end) - x_ref(t_end)|`` (the rest position when the mass has
  stopped).
* ``steps`` -- time steps taken (accepted steps for scipy); ``nfev`` -- right-hand-side
  evaluations (scipy) or forcing evaluations (closed form).
* ``cpu_s`` -- CPU time (:func:`time.process_time`) of the solve alone (building the
  output arrays included, scoring excluded); runs faster than ``min_time`` are repeated
  and the smallest time is kept.
* ``ratio`` -- ``cpu_s`` divided by the CPU time of the *yardstick*
  (:func:`yardstick`), measured in the same process: the benchmark's unit of time.

Methods (see :data:`METHODS`, a registry: adding a method is one entry):

* ``closed-bdf1`` / ``closed-bdf2`` -- :func:`lumped.bingham.integrate` over a ladder of ``dt``;
* ``generic-bdf1`` / ``generic-bdf2`` -- the semismooth-Newton steps of
  :func:`lumped.simulate.simulate` on the same scene built from the ``linear_spring`` and
  ``bingham`` laws (listed only when those modules import), over the ladder of ``dt``
  down to ``Ladders.slow_min_dt``;
* ``scipy-Radau`` / ``scipy-BDF`` / ``scipy-LSODA`` -- :func:`scipy.integrate.solve_ivp` on
  the tanh-regularised model ``F_d = v / gamma + tau tanh(v / eps)`` over a ladder of
  ``eps`` and ``rtol`` (``atol = rtol * L`` with ``L`` the scene's displacement scale),
  with the analytic Jacobian of :func:`regularised_jacobian` (no overflow for any
  ``v / eps``), integrated in two pieces when the forcing switches off inside the
  interval (a careful user splits at a known jump).  A failed run (``status < 0``, an
  exception, a non-finite value, or more than ``max_nfev`` evaluations) is recorded
  with ``status = "failed"`` and its message, never dropped.

Everything here is plain Python; the per-step work of every method is the method's own.
"""

from __future__ import annotations

import csv
import math
import time
from collections.abc import Callable, Iterable, Sequence
from dataclasses import asdict, dataclass, field, fields
from pathlib import Path

import numpy as np

from ._validate import as_positive
from .bingham import BinghamOscillator, integrate
from .forcing import SineBurst, paper_F1, paper_F2, zero_forcing

__all__ = [
    "BenchScene",
    "SCENES",
    "PAPER_SCENES",
    "OWN_SCENES",
    "Method",
    "METHODS",
    "RunResult",
    "Ladders",
    "FULL",
    "QUICK",
    "TARGETS",
    "GRID_DT",
    "YARDSTICK_ITERATIONS",
    "yardstick",
    "time_call",
    "regularised_rhs",
    "regularised_jacobian",
    "reference_grid",
    "run_benchmark",
    "summarize_runs",
    "creep_table",
    "write_csv",
    "read_csv",
    "write_markdown",
    "write_plot",
    "observed_orders",
    "event_study",
    "event_markdown",
    "EVENT_SCENES",
]

#: Step of the common grid on which errors are measured.
GRID_DT = 1e-3
#: Error targets of the summary (absolute, in units of x).
TARGETS = (1e-3, 1e-5, 1e-7, 1e-9)
#: Iterations of the yardstick loop (one unit of benchmark time).
YARDSTICK_ITERATIONS = 500_000


# --------------------------------------------------------------------------- scenes


@dataclass(frozen=True)
class BenchScene:
    """One benchmark problem: parameters, initial state and forcing.

    Attributes
    ----------
    name : str
        Short identifier used in the tables.
    osc : BinghamOscillator
        ``m, k, gamma, tau`` (``tau = mu_s N_f``).
    x0, v0 : float
        Initial state (consistent forces are derived by each method).
    forcing : SineBurst or None
        ``A sin(w t)`` up to ``t_off``; ``None`` for no forcing.
    t_end : float
        End of the scored interval.
    note : str
        What the scene exercises.
    """

    name: str
    osc: BinghamOscillator
    x0: float
    v0: float = 0.0
    forcing: SineBurst | None = None
    t_end: float = 5.0
    note: str = ""

    @property
    def force(self) -> Callable[[float], float]:
        """The forcing as a callable (``zero_forcing`` when there is none)."""
        return zero_forcing if self.forcing is None else self.forcing

    @property
    def length_scale(self) -> float:
        """Displacement scale ``L = max(|x0|, tau / k, A / k)`` used to set scipy's ``atol``."""
        amp = 0.0 if self.forcing is None else abs(self.forcing.amplitude)
        return max(abs(self.x0), self.osc.tau / self.osc.k, amp / self.osc.k)


_PAPER_OSC = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)

#: The four scenarios of the paper's Section 3.
PAPER_SCENES: tuple[BenchScene, ...] = (
    BenchScene("forcing-F1", _PAPER_OSC, 0.0, forcing=paper_F1,
               note="eq. (17a): stays stuck, x = 0 exactly"),
    BenchScene("forcing-F2", _PAPER_OSC, 0.0, forcing=paper_F2,
               note="eq. (17b): slips while forced, sticks after"),
    BenchScene("release-0.005", _PAPER_OSC, 0.005, note="k x0 < tau: never moves"),
    BenchScene("release-0.5", _PAPER_OSC, 0.5, note="free decay to a stretched rest"),
)

#: Variations: other k, gamma, tau, amplitude and frequency, and repeated stick/break-out.
OWN_SCENES: tuple[BenchScene, ...] = (
    BenchScene("stiff-k1e4", BinghamOscillator(1.0, 1e4, 1.0, 1.0), 0.01,
               note="k = 1e4 (w = 100), about 50 half-swings before sticking"),
    BenchScene("viscous-soft", BinghamOscillator(1.0, 10.0, 0.2, 0.5), 0.3,
               note="k = 10, gamma = 0.2, tau = 0.5: heavily damped slip"),
    BenchScene("near-coulomb", BinghamOscillator(1.0, 100.0, 1e3, 1.0), 0.3,
               note="gamma = 1e3: close to Coulomb friction"),
    BenchScene("high-yield-forced", BinghamOscillator(1.0, 100.0, 1.0, 5.0), 0.0,
               forcing=SineBurst(8.0, 3.0 * math.pi, 2.0),
               note="tau = 5, A = 8, w = 3 pi, off at t = 2"),
    BenchScene("fast-forcing", BinghamOscillator(1.0, 100.0, 5.0, 2.0), 0.0,
               forcing=SineBurst(20.0, 40.0 * math.pi, 3.0),
               note="A = 20 at 20 Hz, gamma = 5, tau = 2, off at t = 3"),
    BenchScene("stick-breakout", BinghamOscillator(1.0, 100.0, 1.0, 1.0), 0.0,
               forcing=SineBurst(1.5, 2.0 * math.pi, 4.0),
               note="A = 1.5 at 1 Hz, off at t = 4: sticks and breaks out twice per period"),
)

SCENES: tuple[BenchScene, ...] = PAPER_SCENES + OWN_SCENES


# --------------------------------------------------------------------------- timing


def yardstick(iterations: int = YARDSTICK_ITERATIONS) -> float:
    """The unit of benchmark time: symplectic Euler on Python floats.

    ``iterations`` updates ``v -= h w^2 x; x += h v`` of a harmonic oscillator
    (``h = 1e-3``, ``w^2 = 100``), a fixed pure-Python float loop that does not depend
    on any library code, so speed-ups of ``lumped`` show up as smaller ratios.
    Returns the final ``x`` (so the loop cannot be optimised away).
    """
    x, v, h, w2 = 1.0, 0.0, 1e-3, 100.0
    for _ in range(iterations):
        v -= h * w2 * x
        x += h * v
    return x


def time_call(
    fn: Callable[[], object], *, min_time: float = 0.05, max_repeats: int = 20,
) -> tuple[object, float, int]:
    """CPU time of ``fn()``: best of several calls when one call is shorter than ``min_time``.

    Returns ``(result of the first call, smallest CPU time in seconds, number of calls)``.
    Calls are repeated until their total reaches ``4 * min_time`` or ``max_repeats``.
    """
    t0 = time.process_time()
    result = fn()
    best = total = time.process_time() - t0
    calls = 1
    if best < min_time:
        while calls < max_repeats and total < 4.0 * min_time:
            t0 = time.process_time()
            fn()
            elapsed = time.process_time() - t0
            best = min(best, elapsed)
            total += elapsed
            calls += 1
    return result, best, calls


# --------------------------------------------------------------------------- methods


@dataclass(frozen=True)
class Ladders:
    """Settings swept by the benchmark."""

    dts: tuple[float, ...]
    eps: tuple[float, ...]
    rtols: tuple[float, ...]
    creep_t_end: float = 100.0
    creep_rtol: float = 1e-10
    max_nfev: int = 200_000
    min_time: float = 0.05
    slow_min_dt: float = 1e-4
    event_dts: tuple[float, ...] = tuple(1e-3 * 10.0 ** (-j / 6.0) for j in range(13))


FULL = Ladders(
    dts=(1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2e-4, 1e-4, 5e-5, 2e-5, 1e-5, 5e-6, 2e-6),
    eps=(1e-5, 1e-7, 1e-9, 1e-11),
    rtols=(1e-4, 1e-6, 1e-8, 1e-10, 1e-12),
    max_nfev=50_000,
    slow_min_dt=2e-5,
)
QUICK = Ladders(
    dts=(1e-2, 1e-3, 1e-4, 1e-5),
    eps=(1e-5, 1e-9),
    rtols=(1e-6, 1e-10),
    max_nfev=50_000,
    min_time=0.02,
    slow_min_dt=1e-3,
    event_dts=tuple(1e-3 * 10.0 ** (-j / 4.0) for j in range(5)),
)


@dataclass(frozen=True)
class Solved:
    """What a method's solve returns for scoring: ``x`` on the common grid (or its nodes)."""

    t: np.ndarray
    x: np.ndarray
    steps: int
    nfev: int


@dataclass(frozen=True)
class Method:
    """A registry entry.

    Attributes
    ----------
    name : str
        Column name in the tables.
    kind : {"step", "scipy"}
        ``"step"`` methods are swept over ``Ladders.dts``; ``"scipy"`` ones over
        ``Ladders.eps x Ladders.rtols``.
    solve : callable
        ``solve(scene, setting, ladders) -> callable``; the returned zero-argument
        callable performs the timed solve and returns a :class:`Solved`.
    ours : bool
        ``True`` for the methods of this package.
    slow : bool
        A ``"step"`` method whose steps cost tens of microseconds: it skips the ``dt``
        of the ladder below ``Ladders.slow_min_dt`` (a time budget; the table then
        shows what the remaining ladder reaches).
    """

    name: str
    kind: str
    solve: Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]
    ours: bool = True
    slow: bool = False


def _closed_form(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        dt = setting["dt"]

        def run() -> Solved:
            traj = integrate(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.force,
                             dt=dt, t_end=scene.t_end, method=method)
            return Solved(traj.t, traj.x, traj.stats["steps"], traj.stats["steps"])

        return run

    return solve


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


def _scipy(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        return _scipy_solver(scene, method, setting["eps"], setting["rtol"],
                             setting["atol"], ladders.max_nfev, scene.t_end)

    return solve


def _scipy_solver(
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


def _generic(method: str) -> Callable[[BenchScene, dict, Ladders], Callable[[], Solved]]:
    """The generic semismooth-Newton BDF steps of :func:`lumped.simulate.simulate`."""

    def solve(scene: BenchScene, setting: dict, ladders: Ladders) -> Callable[[], Solved]:
        from .simulate import simulate

        sc = generic_scene(scene)
        dt = setting["dt"]

        def run() -> Solved:
            sol = simulate(sc, method=method, dt=dt, t_end=scene.t_end, throw=True)
            x = sol.column("x_mass")
            return Solved(sol.t, x, int(sol.stats.get("steps", len(x) - 1)),
                          int(sol.stats.get("residual_evals", 0)))

        return run

    return solve


def generic_scene(scene: BenchScene):
    """``scene`` as a :class:`lumped.scene.Scene`: one mass, a ``linear_spring`` and a
    ``bingham`` dashpot, both from ground to the mass, and the same forcing."""
    from .laws import get_law
    from .scene import Element, Mass, Scene

    o = scene.osc
    forces = {} if scene.forcing is None else {"mass": scene.forcing}
    return Scene(
        [Mass("mass", m=o.m, x0=scene.x0, v0=scene.v0)],
        [Element("spring", get_law("linear_spring").bind(k=o.k), "ground", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=o.gamma, tau=o.tau),
                 "ground", "mass")],
        forces,
    )


def _generic_available() -> bool:
    """Whether the generic solver and the law library are importable."""
    try:
        from . import laws, scene, simulate  # noqa: F401
    except ImportError:
        return False
    return True


#: The registry: every method the benchmark runs.
METHODS: tuple[Method, ...] = (
    Method("closed-bdf1", "step", _closed_form("bdf1")),
    Method("closed-bdf2", "step", _closed_form("bdf2")),
    Method("generic-bdf1", "step", _generic("bdf1"), slow=True),
    Method("generic-bdf2", "step", _generic("bdf2"), slow=True),
    Method("scipy-Radau", "scipy", _scipy("Radau"), ours=False),
    Method("scipy-BDF", "scipy", _scipy("BDF"), ours=False),
    Method("scipy-LSODA", "scipy", _scipy("LSODA"), ours=False),
)


def available_methods() -> tuple[Method, ...]:
    """:data:`METHODS` minus the generic solver's entries when it is not installed."""
    return tuple(m for m in METHODS if not m.name.startswith("generic") or _generic_available())


# --------------------------------------------------------------------------- reference


def reference_grid(scene: BenchScene, grid_dt: float = GRID_DT) -> np.ndarray:
    """Exact ``x`` on the common grid ``t_i = i * grid_dt``, ``0 <= t_i <= t_end``."""
    from .reference import reference_for_grid

    traj = reference_for_grid(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.forcing,
                              dt=grid_dt, t_end=scene.t_end)
    return np.asarray(traj.x, dtype=float)


# --------------------------------------------------------------------------- runs


@dataclass(frozen=True)
class RunResult:
    """One row of the benchmark CSV."""

    scene: str
    method: str
    setting: str
    dt: float
    eps: float
    rtol: float
    atol: float
    status: str
    message: str
    max_err: float
    end_err: float
    steps: int
    nfev: int
    cpu_s: float
    ratio: float
    repeats: int

    @property
    def ok(self) -> bool:
        return self.status == "ok"


def _settings(method: Method, scene: BenchScene, ladders: Ladders) -> list[dict]:
    if method.kind == "step":
        floor = ladders.slow_min_dt if method.slow else 0.0
        return [{"dt": dt} for dt in ladders.dts if dt >= floor * (1.0 - 1e-12)]
    return [{"eps": e, "rtol": r, "atol": r * scene.length_scale}
            for e in ladders.eps for r in ladders.rtols]


def _label(setting: dict) -> str:
    if "dt" in setting:
        return f"dt={setting['dt']:g}"
    return f"eps={setting['eps']:g} rtol={setting['rtol']:g}"


def _score(solved: Solved, x_ref: np.ndarray, grid_dt: float) -> tuple[float, float]:
    """``(max_err, end_err)`` of ``solved`` against the exact ``x_ref`` on the common grid."""
    t, x = solved.t, solved.x
    n = len(t) - 1
    if len(x_ref) == len(x):
        err = np.abs(x - x_ref)
    else:
        dt = (t[-1] - t[0]) / n
        ratio = grid_dt / dt
        if ratio >= 1.0:
            stride = int(round(ratio))
            if abs(stride - ratio) > 1e-9 * ratio or stride * (len(x_ref) - 1) != n:
                raise ValueError(f"dt = {dt!r} does not divide the grid step {grid_dt!r}")
            err = np.abs(x[::stride] - x_ref)
        else:
            stride = int(round(1.0 / ratio))
            if abs(stride - 1.0 / ratio) > 1e-9 / ratio or stride * n != len(x_ref) - 1:
                raise ValueError(f"dt = {dt!r} is not a multiple of the grid step {grid_dt!r}")
            err = np.abs(x - x_ref[::stride])
    if not np.all(np.isfinite(err)):
        raise FloatingPointError("non-finite x in the solution")
    return float(np.max(err)), float(err[-1])


def run_one(
    scene: BenchScene, method: Method, setting: dict, x_ref: np.ndarray, unit: float,
    ladders: Ladders, grid_dt: float = GRID_DT,
) -> RunResult:
    """Run, time and score one setting; failures become a row with ``status="failed"``."""
    nan = math.nan
    row = {"scene": scene.name, "method": method.name, "setting": _label(setting),
           "dt": setting.get("dt", nan), "eps": setting.get("eps", nan),
           "rtol": setting.get("rtol", nan), "atol": setting.get("atol", nan)}
    t0 = time.process_time()
    try:
        runner = method.solve(scene, setting, ladders)
        solved, cpu, calls = time_call(runner, min_time=ladders.min_time)
        max_err, end_err = _score(solved, x_ref, grid_dt)
    except Exception as err:  # a failed run is a result; its time is the time to failure
        spent = time.process_time() - t0
        return RunResult(**row, status="failed", message=f"{type(err).__name__}: {err}",
                         max_err=nan, end_err=nan, steps=0, nfev=0, cpu_s=spent,
                         ratio=spent / unit, repeats=1)
    return RunResult(**row, status="ok", message="", max_err=max_err, end_err=end_err,
                     steps=solved.steps, nfev=solved.nfev, cpu_s=cpu, ratio=cpu / unit,
                     repeats=calls)


@dataclass
class BenchReport:
    """Everything one benchmark run produced."""

    runs: list[RunResult]
    creep: list[dict]
    events: list[dict]
    unit_s: float
    reference_s: dict[str, float]
    methods: tuple[str, ...]
    scenes: tuple[str, ...]
    wall_s: float = 0.0
    notes: list[str] = field(default_factory=list)


def measure_unit(repeats: int = 5) -> float:
    """Smallest CPU time of :func:`yardstick` over ``repeats`` calls (seconds)."""
    best = math.inf
    for _ in range(repeats):
        t0 = time.process_time()
        yardstick()
        best = min(best, time.process_time() - t0)
    return best


def run_benchmark(
    *,
    ladders: Ladders = FULL,
    scenes: Iterable[BenchScene] = SCENES,
    methods: Iterable[Method] | None = None,
    creep: bool = True,
    events: bool = True,
    progress: Callable[[str], None] | None = None,
    grid_dt: float = GRID_DT,
) -> BenchReport:
    """Run every method over its ladder on every scene, plus the creep test and the
    event study (:func:`event_study`, closed forms only).

    The yardstick is measured before and after the runs; the smaller value is the unit.
    """
    start = time.perf_counter()
    scenes = tuple(scenes)
    methods = available_methods() if methods is None else tuple(methods)
    say = progress or (lambda _msg: None)
    unit = measure_unit()
    runs: list[RunResult] = []
    ref_s: dict[str, float] = {}
    for scene in scenes:
        x_ref = reference_grid(scene, grid_dt)  # first call pays for imports
        t0 = time.process_time()
        reference_grid(scene, grid_dt)
        ref_s[scene.name] = time.process_time() - t0
        for method in methods:
            for setting in _settings(method, scene, ladders):
                row = run_one(scene, method, setting, x_ref, unit, ladders, grid_dt)
                runs.append(row)
            say(f"{scene.name:18s} {method.name:12s} done")
    creep_rows = creep_table(ladders, methods) if creep else []
    if creep:
        say("creep done")
    event_rows = event_study(dts=ladders.event_dts) if events else []
    if events:
        say("event study done")
    unit_after = measure_unit()
    if unit_after < unit:  # rescale with the better measurement
        runs = [_rescale(r, unit_after) for r in runs]
        unit = unit_after
    return BenchReport(runs=runs, creep=creep_rows, events=event_rows, unit_s=unit,
                       reference_s=ref_s,
                       methods=tuple(m.name for m in methods),
                       scenes=tuple(s.name for s in scenes),
                       wall_s=time.perf_counter() - start)


def _rescale(row: RunResult, unit: float) -> RunResult:
    d = asdict(row)
    d["ratio"] = row.cpu_s / unit
    return RunResult(**d)


# --------------------------------------------------------------------------- creep


def creep_table(ladders: Ladders, methods: Iterable[Method]) -> list[dict]:
    """Drift ``max |x - 0.005|`` of ``release-0.005`` held for ``ladders.creep_t_end`` seconds.

    The exact solution never moves (``k x0 = 0.5 < tau = 1``): drift 0.  The closed
    forms are run at ``dt = 1e-3``; the regularised models at every ``eps`` with
    ``rtol = ladders.creep_rtol``.  Drift is sampled every 0.01 s.
    """
    scene = next(s for s in PAPER_SCENES if s.name == "release-0.005")
    t_end = ladders.creep_t_end
    held = BenchScene(scene.name, scene.osc, scene.x0, t_end=t_end)
    rows = []
    for method in methods:
        if method.kind == "step":
            settings = [{"dt": 1e-3}]
        else:
            settings = [{"eps": e, "rtol": ladders.creep_rtol,
                         "atol": ladders.creep_rtol * held.length_scale} for e in ladders.eps]
        for setting in settings:
            try:
                if method.kind == "step":
                    solved = method.solve(held, setting, ladders)()
                else:
                    solved = _scipy_solver(held, method.name.removeprefix("scipy-"),
                                           setting["eps"], setting["rtol"], setting["atol"],
                                           ladders.max_nfev, t_end, grid_dt=0.01)()
                x = solved.x[:: max(1, int(round(0.01 / setting.get("dt", 0.01))))]
                drift = float(np.max(np.abs(x - held.x0)))
                rows.append({"method": method.name, "setting": _label(setting),
                             "drift": drift, "x_end": float(solved.x[-1]), "status": "ok"})
            except Exception as err:
                rows.append({"method": method.name, "setting": _label(setting),
                             "drift": math.nan, "x_end": math.nan,
                             "status": f"failed: {type(err).__name__}: {err}"})
    return rows


# --------------------------------------------------------------------------- summary


def summarize_runs(
    runs: Sequence[RunResult], targets: Sequence[float] = TARGETS,
) -> dict[tuple[str, float, str], RunResult | None]:
    """For each ``(scene, target, method)`` the fastest ok run with ``max_err <= target``.

    ``None`` means no run of that method reached the target ("unreachable").
    """
    out: dict[tuple[str, float, str], RunResult | None] = {}
    for r in runs:
        for tgt in targets:
            key = (r.scene, tgt, r.method)
            out.setdefault(key, None)
            if r.ok and r.max_err <= tgt:
                best = out[key]
                if best is None or r.cpu_s < best.cpu_s:
                    out[key] = r
    return out


def observed_orders(
    runs: Sequence[RunResult], *, floor: float = 1e-13, max_dt: float = 1e-4,
) -> dict[tuple[str, str], tuple[float, float, str]]:
    """Least-squares slope of ``log err`` against ``log dt`` for each ``(scene, method)``.

    Returns ``(order in max_err, order in end_err, dt range)`` for the time-stepping
    methods, fitted on the runs with ``dt <= max_dt`` (the asymptotic range: coarser
    steps stop the mass after a different number of swings), or on the three finest
    runs when fewer than three have ``dt <= max_dt`` (the slow generic solver's ladder
    stops at ``Ladders.slow_min_dt``).  Errors below ``floor`` (round-off, or an exactly
    reproduced rest) are left out; a slope needs three points (``nan`` otherwise).
    """
    groups: dict[tuple[str, str], list[RunResult]] = {}
    for r in runs:
        if r.ok and math.isfinite(r.dt):
            groups.setdefault((r.scene, r.method), []).append(r)
    out = {}
    for key, rows in groups.items():
        rows = sorted(rows, key=lambda r: r.dt)
        fine = [r for r in rows if r.dt <= max_dt * (1 + 1e-12)]
        if len(fine) < 3:
            fine = rows[:3]
        span = f"{fine[0].dt:g}..{fine[-1].dt:g}"
        out[key] = (_slope([(r.dt, r.max_err) for r in fine], floor),
                    _slope([(r.dt, r.end_err) for r in fine], floor), span)
    return out


def _slope(points: list[tuple[float, float]], floor: float) -> float:
    pts = [(math.log(d), math.log(e)) for d, e in points if e > floor]
    if len(pts) < 3:
        return math.nan
    xs = np.array([p[0] for p in pts])
    ys = np.array([p[1] for p in pts])
    return float(np.polyfit(xs, ys, 1)[0])


# --------------------------------------------------------------------------- events


#: Scenes of the event study: reversals, stick/break-out, forcing, a single stop.
EVENT_SCENES = ("release-0.5", "stick-breakout", "forcing-F2", "viscous-soft")


def event_study(
    scene_names: Sequence[str] = EVENT_SCENES,
    *,
    dts: Sequence[float] | None = None,
    methods: Sequence[str] = ("bdf1", "bdf2"),
    windows: int = 3,
) -> list[dict]:
    """Observed order of the closed-form steps between the events of the exact solution.

    For each scene and step formula, the error ``|x_n - x(t_n)|`` at the method's own
    nodes is split into windows: before the first event, then between consecutive
    events (each window named after the event that opens it: ``reversal``, ``stick``
    or ``breakout``; ``forcing-off`` is not counted as an event), plus the whole run
    and the final value.  ``dts`` should not be commensurate (default: 13 values
    ``1e-3 * 10**(-j/6)``), so the events fall at varied fractions ``theta`` of a step;
    each row holds the least-squares slope of ``log err`` on ``log dt`` and the spread
    ``max/min`` of ``err / dt^slope`` over the ladder (near 1 for a clean power law,
    large when the constant depends on ``theta``).
    """
    from .reference import exact_solution

    dts = tuple(1e-3 * 10.0 ** (-j / 6.0) for j in range(13)) if dts is None else tuple(dts)
    by_name = {s.name: s for s in SCENES}
    rows: list[dict] = []
    for name in scene_names:
        scene = by_name[name]
        probe = exact_solution(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.forcing,
                               t_eval=[0.0, scene.t_end])
        events = [e for e in probe.events if e.kind != "forcing-off"]
        edges = [0.0] + [e.t for e in events[:windows]]
        labels = ["before 1st event"] + [f"after event {i + 1} ({e.kind})"
                                         for i, e in enumerate(events[:windows])]
        ends = edges[1:] + [events[windows].t if len(events) > windows else math.inf]
        for method in methods:
            errs: dict[str, list[tuple[float, float]]] = {}
            for dt in dts:
                traj = integrate(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.force,
                                 dt=dt, t_end=scene.t_end, method=method)
                ref = exact_solution(scene.osc, x0=scene.x0, v0=scene.v0,
                                     forcing=scene.forcing, t_eval=traj.t).trajectory.x
                err = np.abs(traj.x - ref)
                for label, lo, hi in zip(labels, edges, ends, strict=True):
                    inside = (traj.t > lo) & (traj.t < hi) if lo > 0 else traj.t < hi
                    if np.any(inside):
                        errs.setdefault(label, []).append((dt, float(np.max(err[inside]))))
                errs.setdefault("whole run", []).append((dt, float(np.max(err))))
                errs.setdefault("end value", []).append((dt, float(err[-1])))
            for label, pts in errs.items():
                p = _slope(pts, 1e-13)
                spread = math.nan
                if math.isfinite(p):
                    c = [e / d**p for d, e in pts if e > 1e-13]
                    spread = max(c) / min(c)
                rows.append({"scene": name, "method": f"closed-{method}", "window": label,
                             "order": p, "spread": spread,
                             "err_at_finest": pts[-1][1]})
    return rows


def event_markdown(rows: Sequence[dict]) -> str:
    """The event study as a markdown table."""
    lines = ["| scene | method | window | observed order | spread of err/dt^p | "
             "err at finest dt |", "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['scene']} | {r['method']} | {r['window']} | {r['order']:.2f} | "
                     f"{r['spread']:.3g} | {r['err_at_finest']:.2e} |")
    return "\n".join(lines) + "\n"


# --------------------------------------------------------------------------- output


def write_csv(runs: Sequence[RunResult], path: str | Path) -> Path:
    """All runs, one row each, full precision."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    names = [f.name for f in fields(RunResult)]
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(names)
        for r in runs:
            w.writerow([_csv_cell(getattr(r, n)) for n in names])
    return path


def read_csv(path: str | Path) -> list[RunResult]:
    """The runs written by :func:`write_csv` (to redraw tables or plots)."""
    kinds = {f.name: f.type for f in fields(RunResult)}
    out = []
    with Path(path).open(newline="") as fh:
        for row in csv.DictReader(fh):
            out.append(RunResult(**{
                k: (int(v) if kinds[k] in ("int", int) else
                    float(v) if kinds[k] in ("float", float) else v)
                for k, v in row.items()}))
    return out


def _csv_cell(value: object) -> object:
    if isinstance(value, float):
        return repr(value)
    return value


def _cell(r: RunResult | None) -> str:
    if r is None:
        return "unreachable"
    return f"{r.ratio:.3g} ({r.setting})"


def markdown_tables(report: BenchReport, targets: Sequence[float] = TARGETS) -> str:
    """The summary (per scene and target) and the creep table as markdown."""
    best = summarize_runs(report.runs, targets)
    methods = report.methods
    lines = [
        f"Time unit: the yardstick ({YARDSTICK_ITERATIONS} iterations of a pure-Python "
        f"symplectic Euler loop) took {report.unit_s * 1e3:.2f} ms of CPU time in this run. "
        "Each cell: fastest run reaching the target in max |x - x_ref| on [0, 5], "
        "as CPU time / yardstick (setting).",
        "",
    ]
    ours = {m.name for m in METHODS if m.ours}
    for scene in report.scenes:
        lines.append(f"#### {scene}")
        lines.append("")
        lines.append("| target | " + " | ".join(methods) + " | best ours / best scipy |")
        lines.append("|---" * (len(methods) + 2) + "|")
        for tgt in targets:
            cells = [_cell(best.get((scene, tgt, m))) for m in methods]
            lines.append(f"| {tgt:g} | " + " | ".join(cells) + f" | "
                         f"{_ours_vs_scipy(best, scene, tgt, methods, ours)} |")
        lines.append("")
    lines += _overall_table(report, best, targets, ours)
    if report.reference_s:
        lines.append("For comparison, the exact event-driven reference on the same "
                     f"{GRID_DT:g} grid (error at round-off level) took, in yardstick units: "
                     + ", ".join(f"{k} {v / report.unit_s:.3g}"
                                 for k, v in report.reference_s.items()) + ".")
        lines.append("")
    failed = [r for r in report.runs if not r.ok]
    lines.append(f"Failed runs: {len(failed)} of {len(report.runs)}"
                 + (" (listed in the CSV with their messages)." if failed else "."))
    by_method: dict[str, int] = {}
    for r in failed:
        by_method[r.method] = by_method.get(r.method, 0) + 1
    if by_method:
        lines.append("By method: " + ", ".join(f"{k}: {v}" for k, v in sorted(by_method.items()))
                     + ".")
    lines.append("")
    if report.creep:
        lines.append(f"#### Creep: release-0.005 held for {FULL.creep_t_end:g} s "
                     "(exact drift: 0)")
        lines.append("")
        lines.append("| method | setting | max abs(x - 0.005) | x(end) | status |")
        lines.append("|---|---|---|---|---|")
        for c in report.creep:
            lines.append(f"| {c['method']} | {c['setting']} | {c['drift']:.3g} | "
                         f"{c['x_end']:.10g} | {c['status']} |")
        lines.append("")
    return "\n".join(lines)


def _fastest(best, scene, tgt, names) -> RunResult | None:
    cands = [best.get((scene, tgt, m)) for m in names]
    cands = [c for c in cands if c is not None]
    return min(cands, key=lambda r: r.cpu_s) if cands else None


def _ours_vs_scipy(best, scene, tgt, methods, ours) -> str:
    a = _fastest(best, scene, tgt, [m for m in methods if m in ours])
    b = _fastest(best, scene, tgt, [m for m in methods if m not in ours])
    if a is None and b is None:
        return "-"
    if a is None:
        return "ours unreachable"
    if b is None:
        return "scipy unreachable"
    return f"{a.cpu_s / b.cpu_s:.3g}"


def _overall_table(report, best, targets, ours) -> list[str]:
    """Per target and method: scenes reached, and the geometric mean of the fastest ratios."""
    lines = ["#### All scenes", "",
             "Per target and method: scenes where the target was reached, and the geometric "
             "mean over those scenes of the fastest time (yardstick units).", "",
             "| target | " + " | ".join(report.methods) + " |",
             "|---" * (len(report.methods) + 1) + "|"]
    n = len(report.scenes)
    for tgt in targets:
        cells = []
        for m in report.methods:
            got = [best.get((s, tgt, m)) for s in report.scenes]
            got = [g for g in got if g is not None]
            if not got:
                cells.append(f"0/{n}")
                continue
            gm = math.exp(sum(math.log(max(g.ratio, 1e-12)) for g in got) / len(got))
            cells.append(f"{len(got)}/{n}, {gm:.3g}")
        lines.append(f"| {tgt:g} | " + " | ".join(cells) + " |")
    lines.append("")
    return lines


def write_markdown(report: BenchReport, path: str | Path) -> Path:
    """``markdown_tables`` plus the orders of the step methods, written to ``path``."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    orders = observed_orders(report.runs)
    lines = [markdown_tables(report),
             "#### Observed orders (slope of log error vs log dt)", "",
             "Fitted for dt <= 1e-4, or on the three finest dt of a shorter ladder.", "",
             "| scene | method | dt fitted | order, max over [0, 5] | order, x(5) |",
             "|---|---|---|---|---|"]
    for (scene, method), (p_max, p_end, span) in sorted(orders.items()):
        lines.append(f"| {scene} | {method} | {span} | {_order(p_max)} | {_order(p_end)} |")
    lines.append("")
    if report.events:
        lines += ["#### Orders between events (closed forms, errors at the nodes)", "",
                  event_markdown(report.events)]
    path.write_text("\n".join(lines))
    return path


def _order(p: float) -> str:
    return "n/a (errors < 1e-13: exact)" if not math.isfinite(p) else f"{p:.2f}"


def write_plot(report: BenchReport, path: str | Path) -> str:
    """Log-log error against time, one panel per scene and one line per method.

    Each line is the method's lower-left envelope (runs not beaten in both time and
    error by another run of the same method).  Returns a one-line notice.
    """
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        import matplotlib.ticker
    except ImportError:
        return "matplotlib is not installed: no plot written"
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    n = len(report.scenes)
    cols = 2 if n > 1 else 1
    rows = math.ceil(n / cols)
    fig, axes = plt.subplots(rows, cols, figsize=(9, 2.4 * rows), squeeze=False)
    markers = "os^vDP*Xh"
    for ax, scene in zip(axes.flat, report.scenes, strict=False):
        for i, m in enumerate(report.methods):
            pts = sorted((r.ratio, max(r.max_err, 1e-17)) for r in report.runs
                         if r.scene == scene and r.method == m and r.ok)
            front, best_err = [], math.inf
            for t, e in pts:
                if e < best_err:
                    front.append((t, e))
                    best_err = e
            if front:
                ax.loglog(*zip(*front, strict=True), marker=markers[i % len(markers)],
                          ms=3, lw=1, label=m)
        for tgt in TARGETS:
            ax.axhline(tgt, color="0.85", lw=0.5, zorder=0)
        ax.set_title(scene, fontsize=9)
        ax.tick_params(labelsize=7)
        ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    for ax in axes.flat[n:]:
        ax.axis("off")
    for ax in axes[-1]:
        ax.set_xlabel("CPU time / yardstick", fontsize=8)
    for ax in axes[:, 0]:
        ax.set_ylabel("max |x - x_ref|", fontsize=8)
    handles, labels = axes.flat[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="lower center", ncol=len(labels), fontsize=8)
    fig.tight_layout(rect=(0, 0.04, 1, 1))
    fig.savefig(path, dpi=70)
    plt.close(fig)
    return f"plot written to {path}"


def write_outputs(report: BenchReport, out: str | Path) -> list[str]:
    """Write ``runs.csv``, ``summary.md`` and ``work_precision.png`` into ``out``."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    msgs = [f"runs written to {write_csv(report.runs, out / 'runs.csv')}",
            f"summary written to {write_markdown(report, out / 'summary.md')}"]
    msgs.append(write_plot(report, out / "work_precision.png"))
    return msgs


def check_ladders(ladders: Ladders, grid_dt: float = GRID_DT) -> None:
    """Every ``dt`` must divide the grid step or be a multiple of it."""
    for dt in ladders.dts:
        as_positive("dt", dt)
        r = grid_dt / dt
        q = r if r >= 1 else 1 / r
        if abs(q - round(q)) > 1e-9 * q:
            raise ValueError(f"`dt` = {dt!r} neither divides nor is a multiple of {grid_dt!r}")
