"""Reproduce issue 11: impacts, locks and hard points in the generic fixed-step solver.

Run from the repository root: ``python benchmarks/repro_issue11.py``. Prints, per case and
method, the status and the measured error (or the failure message).
"""

from __future__ import annotations

import math

import numpy as np

from lumped.bench.impact_scenes import exact_impact, impact_scene, lock_scene
from lumped.simulate import simulate


def main() -> None:
    for dt in (1e-3, 1e-4):
        for method in ("bdf1", "bdf2", "auto"):
            sol = simulate(impact_scene(), method=method, dt=dt, t_end=3.0, throw=False)
            err = np.max(np.abs(sol.x["mass"] - exact_impact(sol.t)))
            x, v = sol.x["mass"], sol.v["mass"]
            E = 0.5 * v**2 + 0.5 * x**2
            after = sol.t > math.pi / 6 + 2 * dt
            print(f"impact {method:5s} dt={dt:g}: {sol.status.value}, max err {err:.3g} "
                  f"({err / dt:.2f} dt), max E after impact {E[after].max():.4f}")
    for dt in (1e-3, 1e-4):
        for method in ("bdf1", "bdf2", "auto"):
            sol = simulate(lock_scene(), method=method, dt=dt, t_end=3.0, throw=False)
            print(f"lock   {method:5s} dt={dt:g}: {sol.status.value} {sol.message[:150]}")
            if sol.ok:
                x = sol.x["mass"]
                F = sol.F["string"] + sol.F["friction"]
                late = sol.t > 2.0
                print(f"       x-L {np.max(np.abs(x[late] - 0.5)):.2g}, "
                      f"v {np.max(np.abs(sol.v['mass'][late])):.2g}, "
                      f"load-sum {np.max(np.abs(F[late] - 1.0)):.2g}")


if __name__ == "__main__":
    main()
