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
* ``cpu_new_s``, ``ratio_new`` -- the user's columns, for the entries with
  ``Method.new_numbers`` (our compiled methods): after the warm timing, runs with
  **new numbers** (the scene's ``k`` times ``1 + 1e-6 (n + r)``, ``n`` counting such runs
  in the process and ``r`` drawn once per process, so a value never run before;
  :mod:`lumped.bench.new_numbers`), each on a scene object no other run has touched and
  with numbers of its own, with no warm-up: what a user who edits a number gets (the
  loops compiled for the scene's *structure* are loaded, nothing compiled for these
  numbers is). As many such runs as the warm timing took calls (``new_repeats``, at most
  :data:`~lumped.bench.new_numbers.NEW_REPEATS`), and the smallest time is kept: the
  statistic of ``cpu_s``, so
  that ``new_over_warm`` (``cpu_new_s / cpu_s``) compares like with like (a time taken
  once reads 10-30 % above the smallest of several on a shared machine, whatever the
  numbers). ``cpu_new_first_s`` is the first of those runs alone (on the first setting
  of a scene, it also makes the law's class for new numbers,
  :mod:`lumped.codegen.parametric`: what a user's first edit costs). They are timed,
  not scored (their exact solutions are others). ``nan`` for the other entries; a
  failed run with new numbers leaves ``nan`` and says why in ``message``.

Methods (see :data:`METHODS`, a registry: adding a method is one entry):

* ``closed-bdf1`` / ``closed-bdf2`` -- :func:`lumped.solvers.closed.integrate.integrate` over a
  ladder of ``dt``;
* ``generic-bdf1`` / ``generic-bdf2`` -- the semismooth-Newton steps of
  :func:`lumped.simulate.simulate` on the same scene built from the ``linear_spring`` and
  ``bingham`` laws (listed only when those modules import), over the ladder of ``dt``
  down to ``Ladders.slow_min_dt``;
* ``jit-bdf1`` / ``jit-bdf2`` -- the same steps compiled (``simulate(method="jit-bdf1")``),
  over the whole ladder of ``dt``, each setting after an untimed warm-up; run only when
  named (``lumped bench --methods ...``, to keep the default bench short; a run with new
  numbers compiles nothing: the compiled code is one module per structure);
* ``radau5`` -- :func:`lumped.simulate.simulate` with ``compiled=True`` over
  ``Ladders.tol_rtols``, after an untimed warm-up;
* ``scipy-Radau`` / ``scipy-BDF`` / ``scipy-LSODA`` -- :func:`scipy.integrate.solve_ivp` on
  the tanh-regularised model ``F_d = v / gamma + tau tanh(v / eps)`` over a ladder of
  ``eps`` and ``rtol`` (``atol = rtol * L`` with ``L`` the scene's displacement scale),
  with the analytic Jacobian of :func:`regularised_jacobian` (no overflow for any
  ``v / eps``), integrated in two pieces when the forcing switches off inside the
  interval (a careful user splits at a known jump).  A failed run (``status < 0``, an
  exception, a non-finite value, or more than ``max_nfev`` evaluations) is recorded
  with ``status = "failed"`` and its message, never dropped.
* ``scipy-events-DOP853`` / ``scipy-events-LSODA`` / ``scipy-events-RK45`` -- what an expert
  writes by hand for this scene (:mod:`lumped.bench.event_peer`): ``solve_ivp`` on the
  exact law, slip+ / slip- / stick modes switched by terminal events, break-out from
  stick found on ``|F(t) - k x| = tau``, split at the forcing's switch-off, over
  ``Ladders.tol_rtols`` (``atol = rtol * L``).

A method of ours driven by ``rtol``/``atol`` is one entry:
``register_bench_method(tolerance_method(name, simulate_method, rtols))``.

Everything here is plain Python; the per-step work of every method is the method's own.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable, Iterable
from dataclasses import asdict, dataclass, field

import numpy as np

from .event_peer import event_peer_methods
from .event_study import event_study
from .methods import Method, Solved, closed_form_method, generic_method, tolerance_method
from .new_numbers import NEW_REPEATS, NewTimes, time_new_numbers
from .peers import scipy_method, scipy_solver
from .scenes import FULL, GRID_DT, PAPER_SCENES, SCENES, BenchScene, Ladders, reference_grid
from .timing import measure_unit, time_call

__all__ = [
    "BENCH_METHODS",
    "KINDS",
    "METHODS",
    "register_bench_method",
    "available_methods",
    "RunResult",
    "run_one",
    "BenchReport",
    "run_benchmark",
    "count_steps",
    "creep_table",
]


# --------------------------------------------------------------------------- methods


def _generic_available() -> bool:
    """Whether the generic solver and the law library are importable."""
    try:
        from .. import laws, scene, simulate  # noqa: F401
    except ImportError:
        return False
    return True


#: The registry: every method the benchmark runs, by name (see :func:`register_bench_method`).
BENCH_METHODS: dict[str, Method] = {}

#: The registered methods in order of registration (rebuilt by :func:`register_bench_method`).
METHODS: tuple[Method, ...] = ()


def register_bench_method(method: Method) -> Method:
    """Add (or replace) ``method`` in the registry of the benchmark; returns it.

    A tolerance-driven method of ours is one entry, e.g.
    ``register_bench_method(tolerance_method("adaptive", "radau", rtols=(1e-4, ...)))``
    (see :func:`lumped.bench.methods.tolerance_method`).
    """
    global METHODS
    if not isinstance(method, Method):
        raise TypeError(f"`method` must be a Method, got {type(method).__name__}")
    if method.kind not in KINDS:
        raise ValueError(f"`method.kind` must be one of {KINDS}, got {method.kind!r}")
    BENCH_METHODS[method.name] = method
    METHODS = tuple(BENCH_METHODS.values())
    return method


#: The kinds of entry and what each is swept over (see :class:`Method`).
KINDS = ("step", "scipy", "tol")

for _m in (
    Method("closed-bdf1", "step", closed_form_method("bdf1")),
    Method("closed-bdf2", "step", closed_form_method("bdf2")),
    Method("generic-bdf1", "step", generic_method("bdf1"), slow=True),
    Method("generic-bdf2", "step", generic_method("bdf2"), slow=True),
    # opt-in, to keep the default bench short (new numbers compile nothing)
    Method("jit-bdf1", "step", generic_method("jit-bdf1"), warmup=True, new_numbers=True,
           default=False),
    Method("jit-bdf2", "step", generic_method("jit-bdf2"), warmup=True, new_numbers=True,
           default=False),
    # compiled at once: the untimed warm-up call pays the compile, the timed calls run
    # the compiled loop (a short run of a new scene would otherwise stay in Python)
    tolerance_method("radau5", "radau5", compiled=True),
    Method("scipy-Radau", "scipy", scipy_method("Radau"), ours=False),
    Method("scipy-BDF", "scipy", scipy_method("BDF"), ours=False),
    Method("scipy-LSODA", "scipy", scipy_method("LSODA"), ours=False),
    Method("scipy-events-DOP853", "tol", event_peer_methods("DOP853"), ours=False),
    Method("scipy-events-LSODA", "tol", event_peer_methods("LSODA"), ours=False),
    Method("scipy-events-RK45", "tol", event_peer_methods("RK45"), ours=False),
):
    register_bench_method(_m)


def available_methods(*, every: bool = False) -> tuple[Method, ...]:
    """The registered methods run by default (``every=True``: also those run only when
    named, ``Method.default`` false), minus the generic solver's entries when it is not
    installed."""
    return tuple(m for m in BENCH_METHODS.values()
                 if (every or m.default)
                 and (not m.name.startswith(("generic", "jit")) or _generic_available()))


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
    cpu_new_s: float = math.nan
    ratio_new: float = math.nan
    new_over_warm: float = math.nan
    cpu_new_first_s: float = math.nan
    new_repeats: int = 0

    @property
    def ok(self) -> bool:
        return self.status == "ok"

    @property
    def has_new_numbers(self) -> bool:
        """Whether this row holds a time of a run with new numbers."""
        return math.isfinite(self.cpu_new_s)


def _settings(method: Method, scene: BenchScene, ladders: Ladders) -> list[dict]:
    if method.kind == "step":
        floor = ladders.slow_min_dt if method.slow else 0.0
        return [{"dt": dt} for dt in ladders.dts if dt >= floor * (1.0 - 1e-12)]
    if method.kind == "tol":
        rtols = ladders.tol_rtols if method.rtols is None else method.rtols
        return [{"rtol": r, "atol": r * scene.length_scale} for r in rtols]
    return [{"eps": e, "rtol": r, "atol": r * scene.length_scale}
            for e in ladders.eps for r in ladders.rtols]


def _label(setting: dict) -> str:
    if "dt" in setting:
        return f"dt={setting['dt']:g}"
    if "eps" not in setting:
        return f"rtol={setting['rtol']:g}"
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
        if method.warmup:
            runner()
        solved, cpu, calls = time_call(runner, min_time=ladders.min_time)
        max_err, end_err = _score(solved, x_ref, grid_dt)
    except Exception as err:  # a failed run is a result; its time is the time to failure
        spent = time.process_time() - t0
        return RunResult(**row, status="failed", message=f"{type(err).__name__}: {err}",
                         max_err=nan, end_err=nan, steps=0, nfev=0, cpu_s=spent,
                         ratio=spent / unit, repeats=1)
    new = NewTimes(nan, nan, 0, "")
    if method.new_numbers:
        new = time_new_numbers(scene, method, setting, ladders, min(calls, NEW_REPEATS))
    return RunResult(**row, status="ok", message=new.message, max_err=max_err,
                     end_err=end_err, steps=solved.steps, nfev=solved.nfev, cpu_s=cpu,
                     ratio=cpu / unit, repeats=calls, cpu_new_s=new.best,
                     ratio_new=new.best / unit,
                     new_over_warm=new.best / cpu if cpu > 0.0 else nan,
                     cpu_new_first_s=new.first, new_repeats=new.runs)




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
    ours: tuple[str, ...] = ()


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

    ``progress(message)`` is called after every run, after the creep test and after the
    event study: :func:`count_steps` calls in all.

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
                say(f"{scene.name} {method.name} {row.setting}")
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
                       wall_s=time.perf_counter() - start,
                       ours=tuple(m.name for m in methods if m.ours))


def count_steps(
    ladders: Ladders, scenes: Iterable[BenchScene], methods: Iterable[Method], *,
    creep: bool = True, events: bool = True,
) -> int:
    """How many times :func:`run_benchmark` reports progress with these arguments."""
    scenes, methods = tuple(scenes), tuple(methods)
    runs = sum(len(_settings(m, s, ladders)) for s in scenes for m in methods)
    return runs + int(creep) + int(events)


def _rescale(row: RunResult, unit: float) -> RunResult:
    d = asdict(row)
    d["ratio"] = row.cpu_s / unit
    d["ratio_new"] = row.cpu_new_s / unit
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
        elif method.kind == "tol":
            settings = [{"rtol": ladders.creep_rtol,
                         "atol": ladders.creep_rtol * held.length_scale}]
        else:
            settings = [{"eps": e, "rtol": ladders.creep_rtol,
                         "atol": ladders.creep_rtol * held.length_scale} for e in ladders.eps]
        for setting in settings:
            try:
                if method.kind == "step":
                    solved = method.solve(held, setting, ladders)()
                elif method.kind == "tol":
                    solved = method.solve(held, {**setting, "grid_dt": 0.01}, ladders)()
                else:
                    solved = scipy_solver(held, method.name.removeprefix("scipy-"),
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


