"""Compiled closed form and ensembles: per-step cost, throughput, compile time.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/sweep_speed.py [--steps 50000] [--scenes 10000] [--quick]

Measured in one process, each as the best of several interleaved repeats, and reported
in nanoseconds and in units of the benchmark yardstick (:func:`lumped.bench.yardstick`,
one iteration of a pure-Python float loop), since shared machines are noisy:

1. per step, on the paper's F2 scene (sine burst, off at t = 1; t_end = steps * 1e-4):
   the hand-written numba loop of Algorithm 1 (``benchmarks/handwritten_loop.py``, the
   limit), the compiled closed form (summary kernel, no storage; and storing every
   step), ``integrate`` compiled and pure Python, and the generic compiled methods
   ``jit-bdf1``/``jit-bdf2`` when they are registered;
2. first-run and cached compile time of the closed-form kernels, each in a fresh process
   (a new numba cache directory, then the same one again);
3. an ensemble: a grid of ``--scenes`` forced-oscillator scenes (amplitude x frequency)
   through :func:`lumped.sweep.simulate_many` on one thread, on all cores, and on a
   2-worker Dask LocalCluster: wall time (scenario-steps per second achieved) and CPU
   time of the process (ns per scenario-step per core, which other jobs on a shared
   machine do not inflate). A scenario-step is a step of the grid ``t_n = n dt`` of one
   scene: the summary kernel stops at a state at rest that every later step maps onto
   itself and counts the rest (bit for bit the same summary), so a scene that comes to
   rest costs less than its step count.

``--ensemble-only`` runs part 3 alone (for a re-measurement when the machine is quiet).
"""

from __future__ import annotations

import argparse
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE))

from handwritten_loop import algorithm1_loop  # noqa: E402

from lumped.bench import YARDSTICK_ITERATIONS, measure_unit  # noqa: E402
from lumped.scene import paper_F2  # noqa: E402
from lumped.solvers.closed import closed_form_jit as J  # noqa: E402
from lumped.solvers.closed.closed_form import BinghamOscillator, integrate  # noqa: E402

M, K, GAMMA, TAU, DT = 1.0, 100.0, 1.0, 1.0, 1e-4
A, W, T_OFF = paper_F2.amplitude, paper_F2.omega, paper_F2.t_off

_COMPILE_SNIPPET = """
import time
t0 = time.perf_counter()
import numpy as np
from lumped.solvers.closed import closed_form_jit as J
t1 = time.perf_counter()
out = np.empty((1, len(J.SUMMARY_FIELDS)))
p = np.array([[1.0, 100.0, 1.0, 1.0, 0.0, 0.0, 2.0, 10.0, 15.7, 1.0]])
J.summary_batch(p, 1e-4, 10, True, out)
J.summary_batch_serial(p, 1e-4, 10, True, out)
x = np.zeros(11); v = np.zeros(11); f = np.zeros(11); g = np.zeros(11)
J.run_steps(1.0, 100.0, 1.0, 1.0, 1e-4, True, 2, 10.0, 15.7, 1.0, np.empty(0), x, v, f, g)
print(t1 - t0, time.perf_counter() - t1)
"""


def best_of(fn, repeats: int) -> float:
    best = math.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - t0)
    return best


def per_step(n: int, repeats: int) -> dict[str, float]:
    """Seconds per step of each variant (best of ``repeats``, interleaved)."""
    osc = BinghamOscillator(M, K, GAMMA, TAU)
    out = np.empty(len(J.SUMMARY_FIELDS))
    cols = [np.zeros(n + 1) for _ in range(4)]
    empty = np.empty(0)
    variants = {
        "hand-written loop (BDF1)": lambda: algorithm1_loop(M, K, GAMMA, TAU, DT, n, 0.0, 0.0,
                                                            A, W, T_OFF),
        "compiled closed form BDF1, summary": lambda: J.summary_one(
            M, K, 1.0 / GAMMA, TAU, DT, n, False, 0.0, 0.0, J.FORCE_SINE, A, W, T_OFF, out),
        "compiled closed form BDF1, every step stored": lambda: J.run_steps(
            M, K, 1.0 / GAMMA, TAU, DT, False, J.FORCE_SINE, A, W, T_OFF, empty, *cols),
        "compiled closed form BDF2, summary": lambda: J.summary_one(
            M, K, 1.0 / GAMMA, TAU, DT, n, True, 0.0, 0.0, J.FORCE_SINE, A, W, T_OFF, out),
        "integrate(engine='compiled') BDF1": lambda: integrate(
            osc, x0=0.0, forcing=paper_F2, dt=DT, n_steps=n, engine="compiled"),
    }
    for fn in variants.values():  # compile / load from cache
        fn()
    best = {name: math.inf for name in variants}
    for _ in range(repeats):
        for name, fn in variants.items():
            best[name] = min(best[name], best_of(fn, 1))
    per = {name: t / n for name, t in best.items()}
    n_py = max(n // 10, 1000)
    per["integrate(engine='python') BDF1"] = best_of(
        lambda: integrate(osc, x0=0.0, forcing=paper_F2, dt=DT, n_steps=n_py, engine="python"),
        3) / n_py
    per.update(generic_jit(n_py))
    return per


def generic_jit(n: int) -> dict[str, float]:
    """The compiled generic fixed-step methods, if registered (branch ``jit``)."""
    from lumped.io import load_scene
    from lumped.simulate import simulate
    from lumped.solvers import registry

    scene, _ = load_scene(HERE.parent / "examples" / "forcing-F2.toml")
    found = {}
    for method in ("jit-bdf1", "jit-bdf2"):
        if method not in registry.METHODS:
            continue
        simulate(scene, method=method, dt=DT, t_end=100 * DT)
        found[f"generic {method} (simulate)"] = best_of(
            lambda m=method: simulate(scene, method=m, dt=DT, t_end=n * DT), 3) / n
    return found


def compile_times() -> tuple[tuple[float, float], tuple[float, float]]:
    """``(import s, first calls s)`` in a fresh process: cold cache, then warm."""
    env = dict(os.environ)
    with tempfile.TemporaryDirectory() as cache:
        env["NUMBA_CACHE_DIR"] = cache
        runs = [tuple(float(u) for u in subprocess.run(
            [sys.executable, "-c", _COMPILE_SNIPPET], env=env, check=True,
            capture_output=True, text=True).stdout.split()) for _ in range(2)]
    return runs[0], runs[1]


def timed(fn, repeats: int) -> tuple[float, float]:
    """``(wall s, CPU s of this process, all threads)`` of the fastest (by wall) call."""
    best = (math.inf, math.inf)
    for _ in range(repeats):
        w0, c0 = time.perf_counter(), time.process_time()
        fn()
        run = (time.perf_counter() - w0, time.process_time() - c0)
        best = min(best, run)
    return best


def ensemble(n_scenes: int, n_steps: int, repeats: int) -> tuple[int, dict]:
    """Wall and CPU time of a grid sweep: one thread, all threads (prange), Dask."""
    from lumped.sweep import simulate_many

    side = int(round(math.sqrt(n_scenes)))
    grid = {"nodes.mass.force.amplitude": np.linspace(0.0, 20.0, side),
            "nodes.mass.force.omega": np.linspace(2.0, 30.0, side)}
    scene = HERE.parent / "examples" / "forcing-F2.toml"
    kw = dict(dt=DT, t_end=n_steps * DT, progress=False)
    simulate_many(scene, {k: v[:2] for k, v in grid.items()}, **kw)  # warm up
    times = {}
    times["in-process, 1 thread"] = timed(
        lambda: simulate_many(scene, grid, n_jobs=1, **kw), repeats)
    times["in-process, all cores (prange)"] = timed(
        lambda: simulate_many(scene, grid, **kw), repeats)
    from dask.distributed import Client, LocalCluster

    with LocalCluster(n_workers=2, threads_per_worker=1, processes=False,
                      dashboard_address=":0") as cluster, Client(cluster) as client:
        simulate_many(scene, {k: v[:2] for k, v in grid.items()}, client=client, **kw)
        times["Dask LocalCluster, 2 workers"] = timed(
            lambda: simulate_many(scene, grid, client=client, **kw), repeats)
    return side * side, times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--scenes", type=int, default=10_000)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--quick", action="store_true", help="small sizes, for a smoke test")
    parser.add_argument("--ensemble-only", action="store_true",
                        help="skip the per-step table and the compile times")
    args = parser.parse_args()
    if args.quick:
        args.steps, args.scenes, args.repeats = 5_000, 100, 2
    import numba

    print(f"date: {time.strftime('%Y-%m-%d %H:%M')}, cpus: {os.cpu_count()}, "
          f"numba {numba.__version__} ({numba.get_num_threads()} threads), "
          f"python {sys.version.split()[0]}")
    if not args.ensemble_only:
        per_step_and_compile(args)
    ensemble_report(args)


def per_step_and_compile(args) -> None:
    unit = measure_unit() / YARDSTICK_ITERATIONS
    per = per_step(args.steps, args.repeats)
    unit = min(unit, measure_unit() / YARDSTICK_ITERATIONS)
    limit = per["hand-written loop (BDF1)"]
    print(f"\nyardstick iteration: {unit * 1e9:.1f} ns; {args.steps} steps of dt = {DT:g}, "
          "paper F2 scene")
    print(f"{'per step':48s} {'ns':>9s} {'yardstick':>10s} {'/ hand loop':>12s}")
    for name, sec in per.items():
        print(f"{name:48s} {sec * 1e9:9.2f} {sec / unit:10.3f} {sec / limit:12.2f}")

    cold, warm = compile_times()
    print(f"\nfresh process: import lumped.solvers.closed.closed_form_jit {cold[0]:.2f} s / "
          f"{warm[0]:.2f} s; first calls of the four kernels (compile): {cold[1]:.2f} s with "
          f"an empty cache, {warm[1]:.2f} s from the disk cache")


def ensemble_report(args) -> None:
    unit_now = measure_unit() / YARDSTICK_ITERATIONS
    scenes, times = ensemble(args.scenes, args.steps, max(1, args.repeats // 2))
    work = scenes * args.steps
    base = times["in-process, all cores (prange)"][0]
    print(f"\nensemble: {scenes} scenes x {args.steps} steps (closed-form BDF2, compiled); "
          f"yardstick iteration now {unit_now * 1e9:.1f} ns; load average "
          f"{os.getloadavg()[0]:.1f}")
    print(f"{'':32s} {'wall s':>7s} {'steps/s (wall)':>15s} {'CPU s':>7s} "
          f"{'CPU ns/step':>11s} {'yardstick':>9s} {'wall vs in-process':>19s}")
    for name, (wall, cpu) in times.items():
        print(f"{name:32s} {wall:7.2f} {work / wall:15.3e} {cpu:7.2f} "
              f"{cpu / work * 1e9:11.2f} {cpu / work / unit_now:9.3f} {base / wall:19.2f}")


if __name__ == "__main__":
    main()
