"""Adaptive sweeps: ``radau5`` at ``rtol = 1e-6`` over a grid of the 3-mass chain.

Usage, from the repository root (after ``pip install -e ".[test,sweep]"``)::

    python benchmarks/sweep_adaptive.py [--points 20] [--jobs 2] [--python-points 5]

The scene is the bench's 3-mass Bingham chain (``lumped.bench.network_scenes``, the
same numbers; 5 s, the sine burst on ``m3`` off at 3 s), built by :func:`chain` from a
parameter set. Two sweeps of ``--points`` scenes each, through
:func:`lumped.sweep.simulate_many` with ``method="radau5", rtol=1e-6`` and no ``dt``:

(a) the burst's **amplitude** 2-6 N: a number of the forcing, not of a law;
(b) the middle spring's **stiffness** ``k2`` 15-25 N/m: a law parameter (a new bound law
    per point, whose Python kernels sympy generates; one compiled module per structure
    serves every ``k2``).

Before measuring, one run with ``compiled=True`` makes sure the structure's module and
the compiled loop are in the disk cache (its time is printed: a few seconds when they
are already there, the first compile otherwise), so the sweeps run on a **warm cache**.
For each sweep, in this process (``n_jobs=1``): CPU seconds, wall seconds, the steps of
all scenes (``stats["steps"]``) and steps per CPU second, and how many generated modules
this process loaded (``len(lumped.codegen.module_cache.LOADED_MODULES)`` before and after); then
with ``--jobs`` worker processes (spawned: each imports lumped and loads the module from
the disk cache): wall seconds, the CPU of this process and its workers, steps per wall
second. Last, ``--python-points`` scenes of each sweep run one by one with
``compiled=False`` (the Python loop; ``simulate_many`` has no switch for it) and the same
row summary (``lumped.sweep.summary.solution_record``), for steps per CPU second against
the compiled loop.

Times are also given in yardsticks (:func:`lumped.bench.measure_unit`), since shared
machines are noisy.
"""

from __future__ import annotations

import argparse
import os
import resource
import time

import numpy as np

from lumped.bench import YARDSTICK_ITERATIONS, measure_unit
from lumped.bench.network_scenes import CHAIN_FORCING, CHAIN_LINKS
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.scene.forcing import SineBurst

T_END, RTOL = 5.0, 1e-6


def chain(values: dict) -> Scene:
    """The bench's 3-mass chain (``bingham_chain(3)``) with ``values`` over its numbers:
    ``amplitude`` of the burst on ``m3``, ``k1``..``k3`` of the springs."""
    lin, bing = get_law("linear_spring"), get_law("bingham")
    nodes, elements = [], []
    for i, (m, k, gamma, tau) in enumerate(CHAIN_LINKS, start=1):
        a, b = ("ground" if i == 1 else f"m{i - 1}"), f"m{i}"
        nodes.append(Mass(b, m=m))
        elements += [Element(f"s{i}", lin.bind(k=float(values.get(f"k{i}", k))), a, b),
                     Element(f"d{i}", bing.bind(gamma=gamma, tau=tau), a, b)]
    burst = SineBurst(float(values.get("amplitude", CHAIN_FORCING.amplitude)),
                      CHAIN_FORCING.omega, CHAIN_FORCING.t_off)
    return Scene(nodes, elements, {"m3": burst})


def _cpu_children() -> float:
    ru = resource.getrusage(resource.RUSAGE_CHILDREN)
    return ru.ru_utime + ru.ru_stime


def sweep(grid: dict, n_jobs: int) -> dict:
    """One ``simulate_many`` call, measured."""
    from lumped.codegen import module_cache
    from lumped.sweep import simulate_many

    loaded = len(module_cache.LOADED_MODULES)
    children = _cpu_children()
    wall, cpu = time.perf_counter(), time.process_time()
    res = simulate_many(chain, grid, method="radau5", rtol=RTOL, t_end=T_END,
                        n_jobs=n_jobs, progress=False)
    cpu = time.process_time() - cpu
    wall = time.perf_counter() - wall
    table = res.table
    return {"backend": res.backend, "wall": wall, "cpu": cpu,
            "cpu_children": _cpu_children() - children,
            "steps": int(table["steps"].sum()), "ok": bool(res.ok),
            "methods": sorted(set(table["method"])),
            "modules": (loaded, len(module_cache.LOADED_MODULES))}


def python_loop(values: list[dict]) -> tuple[float, int]:
    """CPU seconds and steps of ``simulate(..., compiled=False)`` + the row summary."""
    from lumped import simulate
    from lumped.sweep.summary import solution_record

    steps, cpu = 0, time.process_time()
    for v in values:
        scene = chain(v)
        sol = simulate(scene, method="radau5", rtol=RTOL, t_end=T_END, compiled=False)
        solution_record(sol, scene, None)
        steps += sol.stats["steps"]
    return time.process_time() - cpu, steps


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--points", type=int, default=20, help="scenes per sweep")
    parser.add_argument("--jobs", type=int, default=2,
                        help="worker processes of the pooled sweeps (0: none)")
    parser.add_argument("--python-points", type=int, default=5,
                        help="scenes per sweep run with compiled=False (0: none)")
    args = parser.parse_args()

    from lumped import simulate
    from lumped.codegen import jit, module_cache

    unit = measure_unit()
    print(f"yardstick: {unit * 1e3:.1f} ms ({unit / YARDSTICK_ITERATIONS * 1e9:.1f} ns an "
          f"iteration); load average {os.getloadavg()[0]:.1f}; {os.cpu_count()} cores")
    cached = module_cache.module_cached(jit.scene_source(chain({})).source)
    before = len(module_cache.LOADED_MODULES)
    t0 = time.process_time()
    sol = simulate(chain({}), method="radau5", rtol=RTOL, t_end=T_END, compiled=True)
    print(f"warm-up (compiled=True; structure module {'in' if cached else 'not in'} the "
          f"disk cache before): {time.process_time() - t0:.2f} s CPU, loop "
          f"{sol.stats['loop']!r}, {sol.stats['steps']} steps, {sol.stats['events']} events; "
          f"modules loaded {before} -> {len(module_cache.LOADED_MODULES)}")

    n = args.points
    grids = {"(a) amplitude": {"amplitude": np.linspace(2.0, 6.0, n)},
             "(b) k2 (a law parameter)": {"k2": np.linspace(15.0, 25.0, n)}}
    print(f"\n{n} points per sweep, radau5 rtol {RTOL:g}, t_end {T_END:g} s, no dt")
    head = ("| sweep | processes | wall s | CPU s (with workers) | steps | steps/CPU s | "
            "steps/wall s | CPU / scene, ms | yardsticks / scene | modules loaded |")
    print(head)
    print("|---" * (head.count("|") - 1) + "|")
    for name, grid in grids.items():
        runs = [1] + ([args.jobs] if args.jobs > 1 else [])
        for jobs in runs:
            r = sweep(grid, jobs)
            cpu = r["cpu"] + r["cpu_children"]
            modules = f"{r['modules'][0]} -> {r['modules'][1]}" if jobs == 1 else "(workers)"
            flag = "" if r["ok"] and r["methods"] == ["radau5"] else " FAILED ROWS"
            print(f"| {name} | {r['backend']} x{jobs} | {r['wall']:.2f} | {cpu:.2f} | "
                  f"{r['steps']} | {r['steps'] / cpu:.3g} | {r['steps'] / r['wall']:.3g} | "
                  f"{cpu / n * 1e3:.1f} | {cpu / n / unit:.2f} | {modules} |{flag}")
    if args.python_points > 0:
        p = min(args.python_points, n)
        print(f"\ncompiled=False (the Python loop), {p} scenes of each sweep, one process:")
        for name, grid in grids.items():
            (key, values), = grid.items()
            cpu, steps = python_loop([{key: float(v)} for v in values[:p]])
            print(f"  {name}: {cpu:.2f} s CPU, {steps} steps, {steps / cpu:.3g} steps/CPU s, "
                  f"{cpu / p * 1e3:.0f} ms a scene ({cpu / p / unit:.1f} yardsticks)")


if __name__ == "__main__":
    main()
