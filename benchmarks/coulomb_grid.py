"""The Coulomb limit over issue 29's whole grid: ``radau5`` on one-mass Bingham scenes.

Issue 29's target: on free and forced one-mass scenes across ``gamma`` 1e0..1e12, ``k``
1e-2..1e6 and ``m`` 1e-2..1e2, every ``rtol`` 1e-4..1e-12 runs through, the error falls
with ``rtol`` and is at most 1e-8 relative at ``rtol = 1e-11`` against
:mod:`lumped.reference`, and the steps at ``gamma = 1e12`` are within 2x of the
``coulomb`` law's on the same scene.

Each scene: a mass ``m`` on a linear spring ``k`` and a Bingham dashpot (``gamma``,
``tau = 1``) to ground, over three natural periods ``P = 2 pi sqrt(m / k)``; *free*:
released from ``x0 = 6 tau / k``; *forced*: from rest under ``4 tau sin(0.7 (2 pi / P) t)``
on ``[0, 1.5 P]`` (the scenes of ``tests/solvers/eventdriven/test_coulomb_limit.py``'s
property). ``simulate(scene, method="radau5", rtol=r, atol=1e-3 r tau / k)`` through the
public API; the error is ``max |x - x_exact| / max |x_exact|`` on the grid of ``P / 1000``
through the dense output. Printed: one line per scene (the errors per ``rtol``, the steps
at the tightest) and a summary of the targets; a run that ends without success, raises
or needs a bridge is a failure.

Run: ``python benchmarks/coulomb_grid.py [--rtols 1e-4 1e-6 ...] [--quick]``.
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.reference import reference_for_grid
from lumped.scene import SineBurst
from lumped.solvers.closed.closed_form import BinghamOscillator

GAMMAS = (1e0, 1e3, 1e6, 1e9, 1e12)
KS = (1e-2, 1e0, 1e2, 1e4, 1e6)
MS = (1e-2, 1e0, 1e2)
RTOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-11, 1e-12)
TAU = 1.0


def _setup(m: float, k: float, forced: bool):
    period = 2.0 * math.pi * math.sqrt(m / k)
    dt = period / 1000.0
    t_end = dt * round(3.0 * period / dt)
    if forced:
        return 0.0, SineBurst(4.0 * TAU, 0.7 * 2.0 * math.pi / period, 1.5 * period), t_end, dt
    return 6.0 * TAU / k, None, t_end, dt


def _run(law, m, k, x0, forcing, t_end, rtol):
    scene = Scene([Mass("mass", m=m, x0=x0)],
                  [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                   Element("dashpot", law, "ground", "mass")],
                  {} if forcing is None else {"mass": forcing})
    return simulate(scene, method="radau5", rtol=rtol, atol=1e-3 * rtol * TAU / k,
                    t_end=t_end, throw=False)


def _error(sol, x_ref, dt) -> float:
    grid = np.arange(len(x_ref)) * dt
    x = sol.sol(grid)[:, sol.columns.index("x_mass")]
    return float(np.max(np.abs(x - x_ref)) / np.max(np.abs(x_ref)))


def _scene_runs(m: float, k: float, forced: bool, gamma: float, rtols: list[float],
                found: dict) -> str:
    """Run one scene at every ``rtol``, note what misses a target in ``found`` and return
    its printed line."""
    x0, forcing, t_end, dt = _setup(m, k, forced)
    x_ref = reference_for_grid(BinghamOscillator(m, k, gamma, TAU), x0=x0, forcing=forcing,
                               dt=dt, t_end=t_end).x
    law = get_law("bingham").bind(gamma=gamma, tau=TAU)
    where = (m, k, forced, gamma)
    errs, steps = [], 0
    for rtol in rtols:
        try:
            sol = _run(law, m, k, x0, forcing, t_end, rtol)
        except Exception as err:  # noqa: BLE001 (reported, counted)
            found["failures"].append((*where, rtol, repr(err)[:120]))
            errs.append(math.nan)
            continue
        if not sol.ok or sol.stats.get("bridges", 0):
            found["failures"].append((*where, rtol, sol.message[:120]))
        errs.append(_error(sol, x_ref, dt))
        steps = sol.stats["steps"]
        if rtol == 1e-11:
            found["worst11"] = max(found["worst11"], errs[-1])
            if errs[-1] > 1e-8:
                found["misses"].append((*where, errs[-1]))
    # the error falls with rtol: no rise above 10x the previous level's (the error's own
    # noise at round-off: below 1e-13 relative is level)
    for a, b, r in zip(errs, errs[1:], rtols[1:], strict=False):
        if b > 10.0 * a and b > 1e-13 and b > r:
            found["rises"].append((*where, r, a, b))
    coul = ""
    if gamma == 1e12:
        c = _run(get_law("coulomb").bind(tau=TAU, r=1.0), m, k, x0, forcing, t_end,
                 rtols[-1])
        ratio = steps / max(c.stats["steps"], 1)
        coul = f" coulomb {c.stats['steps']} steps ({ratio:.2f}x)"
        if ratio > 2.0:
            found["slow"].append((m, k, forced, ratio))
    return (f"m={m:g} k={k:g} {'forced' if forced else 'free  '} gamma={gamma:g}: "
            + " ".join(f"{e:.1e}" for e in errs) + f" | {steps} steps{coul}")


def _report(title: str, items: list) -> None:
    print(f"{title}: {len(items)}")
    for item in items:
        print("  ", item)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rtols", type=float, nargs="+", default=list(RTOLS))
    parser.add_argument("--quick", action="store_true", help="gamma 1 and 1e12 only")
    args = parser.parse_args()
    gammas = (1e0, 1e12) if args.quick else GAMMAS
    found = {"failures": [], "rises": [], "misses": [], "slow": [], "worst11": 0.0}
    t0 = time.process_time()
    for m in MS:
        for k in KS:
            for forced in (False, True):
                for gamma in gammas:
                    print(_scene_runs(m, k, forced, gamma, args.rtols, found), flush=True)
    print(f"\nCPU {time.process_time() - t0:.0f} s; rtols {args.rtols}")
    _report("failures (no success, an exception or a bridge)", found["failures"])
    _report("error rising with a tighter rtol (10x, above 1e-13 and above rtol)",
            found["rises"])
    print(f"rtol 1e-11: worst relative error {found['worst11']:.2e}; ", end="")
    _report("above 1e-8", found["misses"])
    _report("gamma 1e12 over 2x the coulomb law's steps", found["slow"])


if __name__ == "__main__":
    main()
