"""Compiled generic BDF (``jit-bdf1``/``jit-bdf2``): cost per step and compile time.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/jit_step_speed.py [--steps 50000] [--repeats 5]

Measured in one process, each the smallest CPU time of ``--repeats`` interleaved runs,
reported in nanoseconds and in units of one iteration of the benchmark yardstick
(:func:`lumped.bench.measure_unit`, a pure-Python float loop), since shared machines
are noisy:

1. per step, on the paper's Bingham scene with forcing F2 (``dt = 1e-4``): the
   compiled generic loop alone (every step stored; the run's setup -- consistent initial
   state, forcing tables, source hash -- is timed apart), ``simulate(method="jit-...")``
   end to end, the pure-Python generic step (``run_bdf``) and the compiled closed-form
   step storing every step (``lumped.solvers.closed.closed_form_jit.run_steps``); the issue's
   target is generic compiled at most 3x the compiled closed form (also over the sine
   burst alone, the first 10 000 steps, where every step moves or sticks under
   forcing: on the full run most steps are at rest). The compiled generic
   loop is timed twice: the default fast path (``lumped.solvers.bdf.fast_codegen``, with its
   hand-over) and the faithful port alone (``fast=False``); both also on
   ``examples/maxwell.toml`` and ``examples/two-masses.toml`` (their ratio is to the
   paper scene's closed form, the only scene the closed form runs);
2. compile time: a fresh process with an empty scene cache (``LUMPED_CACHE_DIR``; the
   solver cores' helpers come from numba's cache beside the package), then a second
   fresh process that loads the scene's machine code from the disk cache.
"""

from __future__ import annotations

import argparse
import math
import os
import re
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from lumped.bench import YARDSTICK_ITERATIONS, measure_unit
from lumped.bench.timing import time_call
from lumped.scenarios import scenario_scene
from lumped.simulate import simulate
from lumped.solvers.bdf.core_jit import compiled_run_bdf_core
from lumped.solvers.bdf.fast_jit import run_fast_path
from lumped.solvers.bdf.fixed_step import run_bdf
from lumped.solvers.bdf.fixed_step_jit import loop_arguments
from lumped.solvers.newton.options import NewtonOptions

DT = 1e-4
SCENE = "forcing-F2"

_CHILD = """
import time
t0 = time.perf_counter()
from lumped import simulate
from lumped.scenarios import scenario_scene
t1 = time.perf_counter()
simulate(scenario_scene({scene!r}), method="jit-bdf2", dt=1e-4, t_end=1e-3, fast=True)
t2 = time.perf_counter()
simulate(scenario_scene({scene!r}), method="jit-bdf2", dt=1e-4, t_end=1e-3, fast=True)
print(t1 - t0, t2 - t1, time.perf_counter() - t2)
"""


def _scenes():
    from lumped.bench.network_scenes import bingham_chain
    from lumped.io import load_scene

    root = Path(__file__).resolve().parents[1] / "examples"
    return {SCENE: scenario_scene(SCENE), "maxwell": load_scene(root / "maxwell.toml")[0],
            "two-masses": load_scene(root / "two-masses.toml")[0],
            "chain-3": bingham_chain(3)}


def per_step(n: int, repeats: int) -> dict[str, float]:
    opts = NewtonOptions()
    loop = compiled_run_bdf_core()
    variants = {}
    for label, scene in _scenes().items():
        for formula in ("bdf1", "bdf2"):
            js, port, args, _ = loop_arguments(scene, formula, DT, n, opts)
            variants[f"{label} jit-{formula}: fast path (default)"] = (
                lambda s=scene, j=js, p=port, a=args: run_fast_path(s, j, p, a))
            variants[f"{label} jit-{formula}: faithful port (fast=False)"] = (
                lambda p=port, a=args: loop(*p.callbacks(), *a, 0, -1))
            if label == SCENE:
                variants[f"{label} jit-{formula}: simulate() end to end"] = (
                    lambda f=formula, s=scene: simulate(s, method=f"jit-{f}", dt=DT,
                                                        t_end=n * DT))
                variants[f"{label} jit-{formula}: setup only (loop_arguments)"] = (
                    lambda f=formula, s=scene: loop_arguments(s, f, DT, n, opts))
    try:
        import numpy as np

        from lumped.solvers.closed import closed_form_jit as C

        cols = [np.zeros(n + 1) for _ in range(4)]
        A, W, T = 10.0, 5.0 * math.pi, 1.0
        for bdf2 in (False, True):
            variants[f"closed form {'BDF2' if bdf2 else 'BDF1'} compiled (every step stored)"] = (
                lambda b=bdf2: C.run_steps(1.0, 100.0, 1.0, 1.0, DT, b, C.FORCE_SINE, A, W, T,
                                           np.empty(0), *cols))
    except ImportError:
        pass
    for fn in variants.values():  # compile or load from the cache
        fn()
    best = {name: math.inf for name in variants}
    for _ in range(repeats):  # interleaved, CPU time (the machine may be loaded)
        for name, fn in variants.items():
            best[name] = min(best[name], time_call(fn, min_time=0.0, max_repeats=1)[1])
    per = {name: t / n for name, t in best.items()}
    n_py = max(n // 10, 1000)
    scene = scenario_scene(SCENE)
    for formula in ("bdf1", "bdf2"):
        per[f"{SCENE} {formula}: pure-Python generic step"] = time_call(
            lambda f=formula: run_bdf(scene, method=f, dt=DT, n_steps=n_py), min_time=0.0,
            max_repeats=3)[1] / n_py
    return per


def burst_phase(repeats: int) -> dict[str, float]:
    """Per step over the sine burst alone (the first 10 000 steps, ``t <= 1``: slip and
    stick under forcing), fast path and compiled closed form. On the full run 4/5 of the
    steps are at rest after the burst, where the fast path accepts a zero residual at
    once; this row shows the cost of the steps that move."""
    import numpy as np

    from lumped.solvers.closed import closed_form_jit as C

    n = 10_000
    scene = scenario_scene(SCENE)
    variants = {}
    for formula in ("bdf1", "bdf2"):
        js, port, args, _ = loop_arguments(scene, formula, DT, n, NewtonOptions())
        variants[f"{SCENE} jit-{formula}: fast path, the burst only (t <= 1)"] = (
            lambda j=js, p=port, a=args: run_fast_path(scene, j, p, a))
    cols = [np.zeros(n + 1) for _ in range(4)]
    for bdf2 in (False, True):
        variants[f"closed form {'BDF2' if bdf2 else 'BDF1'} compiled, the burst only"] = (
            lambda b=bdf2: C.run_steps(1.0, 100.0, 1.0, 1.0, DT, b, C.FORCE_SINE, 10.0,
                                       5.0 * math.pi, 1.0, np.empty(0), *cols))
    for fn in variants.values():
        fn()
    best = {name: math.inf for name in variants}
    for _ in range(repeats):
        for name, fn in variants.items():
            best[name] = min(best[name], time_call(fn, min_time=0.0, max_repeats=1)[1])
    return {name: t / n for name, t in best.items()}


def compile_times() -> list[tuple[float, float, float]]:
    """``(import s, first simulate s, second simulate s)``: empty cache, then warm."""
    env = dict(os.environ)
    out = []
    with tempfile.TemporaryDirectory() as cache:
        env["LUMPED_CACHE_DIR"] = cache
        for _ in range(2):
            res = subprocess.run([sys.executable, "-c", _CHILD.format(scene=SCENE)], env=env,
                                 check=True, capture_output=True, text=True)
            out.append(tuple(float(u) for u in res.stdout.split()))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=50_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    import numba

    print(f"date: {time.strftime('%Y-%m-%d %H:%M')}, cpus: {os.cpu_count()}, "
          f"numba {numba.__version__}, python {sys.version.split()[0]}")
    unit = measure_unit() / YARDSTICK_ITERATIONS
    per = per_step(args.steps, args.repeats)
    unit = min(unit, measure_unit() / YARDSTICK_ITERATIONS)
    closed = {f: per.get(f"closed form {f.upper()} compiled (every step stored)")
              for f in ("bdf1", "bdf2")}
    print(f"\nyardstick iteration: {unit * 1e9:.1f} ns; {args.steps} steps of dt = {DT:g}, "
          f"paper scene {SCENE}")
    burst = burst_phase(args.repeats)
    for f in ("bdf1", "bdf2"):
        burst[f"closed:{f}"] = burst[f"closed form {f.upper()} compiled, the burst only"]
    print(f"{'per step':62s} {'ns':>10s} {'yardstick':>10s} {'/ closed form':>14s}")
    for table, refs in ((per, closed), (burst, {f: burst[f"closed:{f}"] for f in closed})):
        for name, sec in table.items():
            if name.startswith("closed:"):
                continue
            ref = refs.get(re.search(r"bdf[12]", name, flags=re.I).group(0).lower())
            ratio = f"{sec / ref:14.2f}" if ref else f"{'':14s}"
            print(f"{name:62s} {sec * 1e9:10.1f} {sec / unit:10.3f} {ratio}")
    runs = compile_times()
    (imp0, first0, second0), (imp1, first1, _) = runs
    print(f"\ncompile: fresh process, empty scene cache: import {imp0:.2f} s, first "
          f"simulate(jit-bdf2) {first0:.2f} s (the next one in that process {second0:.3f} s);"
          f"\n         fresh process, warm disk cache: import {imp1:.2f} s, first simulate "
          f"{first1:.2f} s")


if __name__ == "__main__":
    main()
