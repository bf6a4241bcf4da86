"""A parameter study: where does the forced Bingham oscillator come to rest?

The paper's oscillator (m = 1, k = 100, gamma = 1, mu_s N_f = 1) is driven by
F(t) = A sin(omega t) for t <= 1 s and left alone until t = 5 s. Over a grid of forcing
amplitude A and angular frequency omega this maps

* the rest position (the displacement at which the mass sticks for good; |x| <= tau/k),
* the total stick time in [0, 5] s,

from a single scene file (examples/forcing-F2.toml) with lumped.sweep.simulate_many:
the closed-form BDF2 step, compiled, over all scenes in parallel.

Run from the repository root::

    python examples/sweep_study.py                # the docs figure (6400 scenes)
    python examples/sweep_study.py --small --out /tmp/study --csv /tmp/study/table.csv
"""

from __future__ import annotations

import argparse
import time
from pathlib import Path

import numpy as np

from lumped.sweep import simulate_many

HERE = Path(__file__).resolve().parent
AMPLITUDE = "nodes.mass.force.amplitude"
OMEGA = "nodes.mass.force.omega"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=HERE.parent / "docs",
                        help="where to write sweep_study.png (default: docs/)")
    parser.add_argument("--csv", type=Path, default=None, help="also write the table here")
    parser.add_argument("--small", action="store_true", help="a 12 x 10 grid (seconds)")
    args = parser.parse_args()
    n_a, n_w = (12, 10) if args.small else (80, 80)
    grid = {AMPLITUDE: np.linspace(0.0, 20.0, n_a), OMEGA: np.linspace(1.0, 40.0, n_w)}

    started = time.perf_counter()
    result = simulate_many(HERE / "forcing-F2.toml", grid, dt=1e-4, t_end=5.0)
    elapsed = time.perf_counter() - started
    table = result.table
    print(f"{len(table)} scenes x {table['steps'].iloc[0]} steps ({result.backend}, "
          f"{table['method'].iloc[0]}) in {elapsed:.1f} s")
    print(f"all ran to the end: {result.ok}; at rest at t = 5 s: "
          f"{int(table['at_rest'].sum())} of {len(table)}")
    never = table[AMPLITUDE] <= 1.0  # |F| <= mu_s N_f: eq. (19), the mass never moves
    still = int((table.loc[never, "stick_time"] == 5.0).sum())
    print(f"A <= mu_s N_f = 1: stick time 5 s in {still} of {int(never.sum())} scenes")
    rest = table["rest_position.mass"].astype(float)
    print(f"rest positions within the stick band |x| <= tau/k = 0.01: "
          f"{bool((rest.abs() <= 0.01 + 1e-12).all())}")

    args.out.mkdir(parents=True, exist_ok=True)
    plot(result, args.out / "sweep_study.png")
    print(f"wrote {args.out / 'sweep_study.png'}")
    if args.csv is not None:
        result.write(args.csv.parent, stem=args.csv.stem)
        print(f"wrote {args.csv}")


def plot(result, path: Path) -> None:
    """Two heat maps over (omega, A): rest position and stick time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    ds = result.to_xarray()
    w = ds[OMEGA].values
    a = ds[AMPLITUDE].values
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), layout="constrained")
    panels = (("rest_position.mass", "rest position x (m)", "RdBu_r"),
              ("stick_time", "total stick time in [0, 5] s", "viridis"))
    for ax, (var, label, cmap) in zip(axes, panels, strict=True):
        values = np.ma.masked_invalid(ds[var].values.astype(float))
        kw = {"vmin": -0.01, "vmax": 0.01} if var.startswith("rest") else {}
        mesh = ax.pcolormesh(w, a, values, shading="nearest",
                             cmap=plt.get_cmap(cmap).with_extremes(bad="0.8"), **kw)
        fig.colorbar(mesh, ax=ax, label=label)
        ax.axhline(1.0, color="k", lw=0.8, ls="--")
        ax.set_xlabel(r"forcing frequency $\omega$ (rad/s)")
        ax.set_ylabel("forcing amplitude A (N)")
    axes[0].set_title(r"rest position ($|x| \leq \mu_s N_f / k = 0.01$; dashed: A = $\mu_s N_f$)",
                      fontsize=9)
    axes[1].set_title("stick time (F = A sin(omega t) on [0, 1] s, m = 1, k = 100, gamma = 1)",
                      fontsize=9)
    fig.savefig(path, dpi=110)
    plt.close(fig)


if __name__ == "__main__":
    main()
