"""Observed orders of the closed-form BDF1/BDF2 against the exact reference.

Run from the repository root::

    PYTHONPATH=src python examples/reference_convergence.py

For each scene and method it prints the error in x against
:func:`lumped.reference.reference_for_grid` on the same grid, in three norms --
the largest error on [0, 5], the error at t = 5 (the rest position once the mass has
stuck) and the largest error on the first smooth slip arc (before the first zero of
v) -- and the slope of log(error) against log(dt).  It also times the reference on
the four paper scenarios at dt = 1e-4, as a ratio to closed-form BDF1 on the same grid.
"""

from __future__ import annotations

import math
import time

import numpy as np

from lumped.reference import exact_solution, reference_for_grid
from lumped.scene import SineBurst, paper_F1, paper_F2, zero_forcing
from lumped.solvers.closed.closed_form import BinghamOscillator
from lumped.solvers.closed.integrate import integrate

PAPER = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)
SCENES = {
    "release-0.5": (0.5, None),
    "paper-F2": (0.0, paper_F2),
    "stick-slip 1.5 sin(10 t)": (0.0, SineBurst(1.5, 10.0)),
}
DTS = 2e-3 / 2.0 ** np.arange(7)
T_END = 5.0


def slope(dts, errs) -> float:
    return float(np.polyfit(np.log(dts), np.log(errs), 1)[0])


def orders() -> None:
    print(f"dt ladder: {', '.join(f'{dt:.4g}' for dt in DTS)}")
    for name, (x0, forcing) in SCENES.items():
        first = exact_solution(PAPER, x0=x0, forcing=forcing, t_eval=[0.0, T_END])
        slips = [iv for iv in first.intervals if iv.phase == "slip"]
        arc = (slips[0].t_start, slips[0].t_end)
        for method in ("bdf1", "bdf2"):
            e_max, e_end, e_arc = [], [], []
            for dt in DTS:
                ref = reference_for_grid(PAPER, x0=x0, forcing=forcing, dt=dt, t_end=T_END)
                num = integrate(PAPER, x0=x0, forcing=forcing or zero_forcing, dt=dt,
                                t_end=T_END, method=method)
                err = np.abs(num.x - ref.x)
                e_max.append(err.max())
                e_end.append(err[-1])
                on_arc = (ref.t >= arc[0]) & (ref.t <= arc[0] + 0.9 * (arc[1] - arc[0]))
                e_arc.append(err[on_arc].max())
            print(f"{name:26s} {method}: max {slope(DTS, e_max):5.2f}  end {slope(DTS, e_end):5.2f}"
                  f"  first arc {slope(DTS, e_arc):5.2f}")
            for label, errs in (("max", e_max), ("end", e_end), ("arc", e_arc)):
                print(f"    {label}: " + " ".join(f"{e:.2e}" for e in errs))


def timings(repeat: int = 5) -> None:
    paper = {"paper-F1": (0.0, paper_F1), "paper-F2": (0.0, paper_F2),
             "release-0.005": (0.005, None), "release-0.5": (0.5, None)}
    for name, (x0, forcing) in paper.items():
        best_ref = best_bdf = math.inf
        for _ in range(repeat):
            t0 = time.perf_counter()
            ref = reference_for_grid(PAPER, x0=x0, forcing=forcing, dt=1e-4, t_end=T_END)
            t1 = time.perf_counter()
            integrate(PAPER, x0=x0, forcing=forcing or zero_forcing, dt=1e-4, t_end=T_END)
            t2 = time.perf_counter()
            best_ref, best_bdf = min(best_ref, t1 - t0), min(best_bdf, t2 - t1)
        print(f"{name:14s} reference {best_ref * 1e3:7.2f} ms ({ref.stats['events']:2d} events)"
              f"   closed BDF1 {best_bdf * 1e3:7.2f} ms   ratio {best_ref / best_bdf:.3f}")


if __name__ == "__main__":
    orders()
    timings()
