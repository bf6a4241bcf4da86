"""``jit-bdf2`` against ``bdf2`` on scenes with a string (issue 27, "Locks compiled too").

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/jit_lock_speed.py [--steps 50000] [--repeats 3]

A scene with a position lock runs the compiled loop while every string is slack and the
reference's steps across impacts and locks (``lumped.solvers.bdf.lock_handover``); before,
``jit-bdf2`` ran such a scene whole on ``bdf2``. Warm (every scene compiled and run once,
untimed), in one process, each time the smallest CPU time of ``--repeats`` interleaved
runs of ``simulate``, ``dt = 1e-4``; printed with the ratio to ``bdf2`` and the split
of the steps (``compiled_steps``, ``reference_steps``, ``handovers``), and the largest
difference from ``bdf2`` relative to each column's size. Scenes:

* ``pulled``: a mass on a string beside a Newtonian dashpot, pulled by a sine: the
  string is taut (on the reference) about half the time;
* ``rattle``: a mass on a linear spring, driven by a sine, tethered by a string it
  reaches briefly in each cycle (an impact, a short locked phase): mostly compiled;
* ``stuck``: a string beside a Bingham dashpot under a slow sine: taut and stuck
  (indeterminate forces, on the reference) for a part of each cycle.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from lumped import Element, Mass, Scene, simulate
from lumped.bench import measure_unit
from lumped.laws import get_law
from lumped.scene.forcing import SineBurst

DT = 1e-4


def _law(name, **params):
    return get_law(name).bind(**params)


SCENES = {
    "pulled": lambda: Scene(
        [Mass("mass", 1.0, v0=0.3)],
        [Element("string", _law("string_spring", k=10.0, L=0.2), "ground", "mass"),
         Element("damper", _law("newtonian", c=0.5), "ground", "mass")],
        {"mass": SineBurst(20.0, 3.0, 1e9)}),
    "rattle": lambda: Scene(
        [Mass("mass", 1.0)],
        [Element("spring", _law("linear_spring", k=100.0), "ground", "mass"),
         Element("string", _law("string_spring", k=1.0, L=0.05), "ground", "mass"),
         Element("damper", _law("newtonian", c=0.2), "ground", "mass")],
        {"mass": SineBurst(15.0, 9.0, 1e9)}),
    "stuck": lambda: Scene(
        [Mass("m", 1.0)],
        [Element("s", _law("string_spring", k=10.0, L=0.05), "ground", "m"),
         Element("d", _law("bingham", gamma=1.0, tau=2.0), "ground", "m")],
        {"m": SineBurst(6.0, 5.0, 1e9)}),
}


def _cpu(fn):
    t0 = time.process_time()
    out = fn()
    return out, time.process_time() - t0


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=50_000)
    ap.add_argument("--repeats", type=int, default=3)
    args = ap.parse_args()
    t_end = args.steps * DT
    unit = measure_unit()
    print(f"yardstick Y = {unit * 1e3:.1f} ms; {args.steps} steps of dt = {DT}, warm, "
          f"best of {args.repeats} (CPU)")
    print(f"{'scene':8} {'method':22} {'CPU s':>8} {'Y':>7} {'x bdf2':>7} {'compiled':>9} "
          f"{'reference':>9} {'handovers':>9} {'impacts':>7} {'max rel diff':>12}")
    for name, make in SCENES.items():
        runs = {"bdf2": {}, "jit-bdf2": {"fast": True}, "jit-bdf2 fast=False": {"fast": False}}
        for label, extra in runs.items():  # warm: compile, load the caches
            simulate(make(), method=label.split()[0], dt=DT, t_end=10 * DT, **extra)
        best = dict.fromkeys(runs, float("inf"))
        sols = {}
        for _ in range(args.repeats):  # interleaved
            for label, extra in runs.items():
                sol, cpu = _cpu(lambda lb=label, ex=extra, mk=make: simulate(
                    mk(), method=lb.split()[0], dt=DT, t_end=t_end, **ex))
                best[label] = min(best[label], cpu)
                sols[label] = sol
        ref = sols["bdf2"]
        scale = np.abs(ref.data).max(axis=0) + 1e-300
        for label in runs:
            st = sols[label].stats
            diff = float((np.abs(sols[label].data - ref.data) / scale).max())
            print(f"{name:8} {label:22} {best[label]:8.3f} {best[label] / unit:7.1f} "
                  f"{best[label] / best['bdf2']:7.3f} {st.get('compiled_steps', '-'):>9} "
                  f"{st.get('reference_steps', '-'):>9} {st.get('handovers', '-'):>9} "
                  f"{st.get('impacts', '-'):>7} {diff:12.2e}")


if __name__ == "__main__":
    main()
