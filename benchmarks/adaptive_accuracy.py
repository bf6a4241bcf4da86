"""Time and error of ``radau5`` on the four paper scenes, next to scipy LSODA (tanh model).

For every scene and ``rtol`` in 1e-4 .. 1e-12 (``atol = 1e-3 rtol``): the CPU time of
``simulate(..., method="radau5")`` and ``max |x - x_exact|`` on the 1e-3 grid through the
dense output, against :mod:`lumped.reference`. Next to it, the fastest scipy LSODA run on
the tanh-regularised model (``lumped.bench`` peer, ``eps`` and ``rtol`` ladders) that
reaches the same error. Times are in yardstick units (:func:`lumped.bench.runner.
yardstick`, measured in the same process); the ratio is ours / LSODA's.

Run: ``python benchmarks/adaptive_accuracy.py [--out FILE.md]`` (about a minute).
"""

from __future__ import annotations

import argparse
import math

import numpy as np

from lumped import simulate
from lumped.bench.peers import scipy_solver
from lumped.bench.report import print_and_save
from lumped.bench.runner import measure_unit, time_call
from lumped.bench.scenes import GRID_DT, PAPER_SCENES, generic_scene
from lumped.reference import exact_solution

RTOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
PEER_EPS = (1e-5, 1e-7, 1e-9, 1e-11)
PEER_RTOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)


def _reference(scene, grid):
    return exact_solution(scene.osc, x0=scene.x0, v0=scene.v0, forcing=scene.forcing,
                          t_eval=grid).trajectory.x


def _peers(scene, grid, x_ref, unit):
    out = []
    for eps in PEER_EPS:
        for rtol in PEER_RTOLS:
            run = scipy_solver(scene, "LSODA", eps, rtol, rtol * 1e-3, 50_000, scene.t_end)
            try:
                solved, cpu, _ = time_call(run, min_time=0.02, max_repeats=3)
            except Exception:  # noqa: BLE001 - a failed peer run is skipped, as in the bench
                continue
            err = float(np.max(np.abs(solved.x - x_ref)))
            out.append((err, cpu / unit, eps, rtol))
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help="also write the table to this file")
    args = parser.parse_args()
    unit = measure_unit()
    lines = [f"yardstick unit: {unit * 1e3:.2f} ms", "",
             "| scene | rtol | radau5 max err | steps | events | radau5 time (units) "
             "| best LSODA-tanh time at that error (units) | ratio |",
             "|---|---|---|---|---|---|---|---|"]
    for bs in PAPER_SCENES:
        grid = np.arange(int(round(bs.t_end / GRID_DT)) + 1) * GRID_DT
        x_ref = _reference(bs, grid)
        scene = generic_scene(bs)
        peers = _peers(bs, grid, x_ref, unit)
        for rtol in RTOLS:
            def run(rtol=rtol, scene=scene, bs=bs):
                return simulate(scene, method="radau5", t_end=bs.t_end, rtol=rtol,
                                atol=1e-3 * rtol)

            sol, cpu, _ = time_call(run, min_time=0.02, max_repeats=3)
            err = float(np.max(np.abs(sol.sol(grid)[:, 1] - x_ref)))
            ok = [p for p in peers if p[0] <= max(err, 1e-15)]
            best = min(ok, default=None, key=lambda p: p[1])
            peer = "none reaches it" if best is None else (
                f"{best[1]:.1f} (eps {best[2]:.0e}, rtol {best[3]:.0e})")
            ratio = "-" if best is None else f"{cpu / unit / best[1]:.2f}"
            lines.append(f"| {bs.name} | {rtol:.0e} | {err:.2e} | {sol.stats['steps']} | "
                         f"{len(sol.events)} | {cpu / unit:.1f} | {peer} | {ratio} |")
            if not math.isfinite(err):  # pragma: no cover
                break
    text = "\n".join(lines)
    print_and_save(text, args.out)


if __name__ == "__main__":
    main()
