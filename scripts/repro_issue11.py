"""Reproduce issue 11: impacts, locks and hard points in the generic fixed-step solver.

Run from the repository root: ``python scripts/repro_issue11.py``. Prints, per case and
method, the status and the measured error (or the failure message).
"""

from __future__ import annotations

import math

import numpy as np

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.simulate import simulate


def impact_scene() -> Scene:
    return Scene([Mass("mass", m=1.0, x0=0.0, v0=1.0)],
                 [Element("string", get_law("string_spring").bind(k=1.0, L=0.5),
                          "ground", "mass")])


def exact_impact(t):
    t = np.asarray(t, dtype=float)
    ts = math.pi / 6
    return np.where(t < ts, np.sin(t), 0.5 * np.cos(t - ts))


def lock_scene() -> Scene:
    return Scene([Mass("mass", m=1.0, x0=0.0, v0=0.0)],
                 [Element("string", get_law("string_spring").bind(k=1.0, L=0.5),
                          "ground", "mass"),
                  Element("friction", get_law("coulomb").bind(tau=0.2, r=10.0),
                          "ground", "mass")],
                 forces={"mass": 1.0})


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
