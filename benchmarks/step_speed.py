"""Time per step of the closed-form and generic steps on the paper's scenarios.

Usage, from the repository root (after ``pip install -e .``)::

    python benchmarks/step_speed.py [--steps 20000] [--repeats 5]

Every time is the best of ``--repeats`` runs, taken in one process and interleaved
across methods, and is also given in units of one iteration of the benchmark yardstick
(:func:`lumped.bench.yardstick`, a fixed pure-Python float loop), since absolute times on
shared machines are noisy: compare ratios, not microseconds.
"""

from __future__ import annotations

import argparse
import time

from lumped.bench import YARDSTICK_ITERATIONS, measure_unit
from lumped.scenarios import PAPER_SCENARIOS, run_scenario

METHODS = ("closed-bdf1", "closed-bdf2", "bdf1", "bdf2")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=20_000)
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    dt = 1e-4
    t_end = args.steps * dt
    unit = measure_unit() / YARDSTICK_ITERATIONS  # seconds per yardstick iteration
    best = {(s, m): float("inf") for s in PAPER_SCENARIOS for m in METHODS}
    for _ in range(args.repeats):
        for s in PAPER_SCENARIOS:
            for m in METHODS:
                t0 = time.process_time()
                run_scenario(s, method=m, dt=dt, t_end=t_end)
                best[s, m] = min(best[s, m], (time.process_time() - t0) / args.steps)
    unit = min(unit, measure_unit() / YARDSTICK_ITERATIONS)
    print(f"yardstick iteration: {unit * 1e9:.1f} ns; {args.steps} steps of dt = {dt:g}")
    print(f"{'scenario':15s}" + "".join(f"{m:>24s}" for m in METHODS) + "   generic/closed")
    for s in PAPER_SCENARIOS:
        cells = "".join(f"{best[s, m] * 1e6:8.2f} us ({best[s, m] / unit:6.1f} u)"
                        for m in METHODS)
        r1 = best[s, "bdf1"] / best[s, "closed-bdf1"]
        r2 = best[s, "bdf2"] / best[s, "closed-bdf2"]
        print(f"{s:15s}{cells}   {r1:5.1f} / {r2:5.1f}")


if __name__ == "__main__":
    main()
