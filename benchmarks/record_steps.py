"""``radau5`` under a ground-acceleration record: time and error against a tight run.

Usage, from the repository root::

    python benchmarks/record_steps.py

The scene is the isolated structure of ``examples/isolator.py`` (a base slab on a
Coulomb slider and a restoring spring, a storey on a spring and a damper) under the
shipped synthetic record (4001 points over 20 s). For each ``rtol`` (``atol = 1e-3
rtol``, ``compiled=True``; the scene object is new for every run, the structure's module
loaded) it prints the warm run's wall time, the steps, the events, and the largest error
of each kind of state (positions, velocities, forces) on a 5 ms grid against the run at
``rtol = 1e-11``.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "examples"))

import isolator  # noqa: E402

from lumped import simulate  # noqa: E402
from lumped.io import read_at2  # noqa: E402

RTOLS = (1e-5, 1e-7, 1e-9)
REFERENCE = 1e-11


def run(record, rtol: float):
    """A new scene, run once untimed (compiles on a first call), then timed."""
    kw = dict(method="radau5", rtol=rtol, atol=1e-3 * rtol, t_end=20.0, compiled=True)
    simulate(isolator.scenes(record)[0], **kw)
    scene = isolator.scenes(record)[0]
    t0 = time.perf_counter()
    sol = simulate(scene, **kw)
    return sol, time.perf_counter() - t0


def main() -> None:
    record = read_at2(isolator.HERE / "records" / "synthetic_ground.at2")
    grid = np.linspace(0.0, 20.0, 4001)
    ref, _ = run(record, REFERENCE)
    y_ref = ref.sol(grid)
    N = len(ref.scene.nodes)
    print("| rtol | wall time | steps | events | error x | error v | error F |")
    print("|---|---|---|---|---|---|---|")
    for rtol in RTOLS:
        sol, wall = run(record, rtol)
        err = np.abs(sol.sol(grid) - y_ref).max(axis=0)
        # columns t, x_1, v_1, x_2, v_2, ..., then the forces
        ex, ev = err[1:1 + 2 * N:2].max(), err[2:1 + 2 * N:2].max()
        eF = err[1 + 2 * N:].max()
        print(f"| {rtol:.0e} | {wall:.3f} s | {sol.stats['steps']} | {sol.stats['events']} "
              f"| {ex:.1e} | {ev:.1e} | {eF:.1e} |")


if __name__ == "__main__":
    main()
