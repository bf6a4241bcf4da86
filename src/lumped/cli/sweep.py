"""``lumped sweep SCENE.toml --grid PATH=START:STOP:NUM [--grid ...] --out DIR``.

Runs the scene file for every point of a grid of parameters
(:func:`lumped.sweep.simulate_many`) and writes into DIR:

* ``sweep.csv`` -- one row per scene: the parameters, ``status``, ``message``, the final
  state, rest position, stick time, stick-slip cycles, events, dissipated energy;
* ``sweep.parquet`` -- the same table (when pyarrow is installed);
* ``sweep.nc`` -- the same as NetCDF3 over the grid's axes (when xarray is installed;
  :meth:`lumped.sweep.SweepResult.write_netcdf`);
* ``<quantity>.png`` -- a heat map of ``--quantity`` over a grid of one or two paths
  (a line over one path; when matplotlib is installed; otherwise a note says so).

``--steady-amplitude ELEMENT_OR_NODE`` adds the steady amplitude under the scene's sine
forcing or sine ground motion (:mod:`lumped.sweep.steady`) and plots it by default: over
a grid of ``ground.motion.omega`` (or ``nodes.<n>.force.omega``) it is the
amplitude-frequency curve.

A grid axis is ``PATH=START:STOP:NUM`` (NUM evenly spaced values, both ends included) or
``PATH=V1,V2,...``; PATH is a dotted key of the scene file, e.g.
``nodes.mass.force.amplitude`` or ``elements.dashpot.parameters.tau``. The exit code is
0 when every scene ran to the end, 1 when some stopped early (their rows say why).

``--dt`` runs a fixed-step method; ``--rtol``/``--atol`` (or the file's ``[solver]``
``rtol``/``atol``) run the adaptive ``radau5`` at that tolerance, on its output grid when
there is a ``dt`` too, else on its step points (a fixed-step ``--method`` refuses them).
"""

from __future__ import annotations

import argparse
import sys
import time

from ..solvers.registry import METHODS

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``lumped sweep``."""
    parser.add_argument("scene", help="scene file (TOML), see docs/scenes.md")
    parser.add_argument("--grid", action="append", required=True, metavar="PATH=SPEC",
                        help="one grid axis, 'path=start:stop:num' or 'path=a,b,c' "
                        "(repeatable: the grid is the product)")
    parser.add_argument("--out", required=True, help="output directory")
    parser.add_argument("--quantity", default=None,
                        help="column for the heat map (default: rest_position, or "
                        "steady_amplitude with --steady-amplitude)")
    parser.add_argument("--steady-amplitude", dest="steady_amplitude", default=None,
                        metavar="ELEMENT_OR_NODE",
                        help="add the steady amplitude of this element ('a+b' for elements "
                        "in parallel) or node under the scene's sine forcing or sine ground "
                        "motion (columns steady_omega, steady_amplitude, steady_cycles, "
                        "energy_per_cycle, zeta_eq); over a grid of its omega, the plot is "
                        "the amplitude-frequency curve")
    parser.add_argument("--method", choices=METHODS, default=None,
                        help="solver (default: the file's [solver] method, else auto)")
    parser.add_argument("--dt", type=float, default=None, help="step size (overrides the file)")
    parser.add_argument("--t-end", dest="t_end", type=float, default=None,
                        help="final time (overrides the file)")
    parser.add_argument("--rtol", type=float, default=None,
                        help="relative tolerance of the adaptive radau5 (overrides the file; "
                        "with --method auto it runs radau5; refused by a fixed-step method)")
    parser.add_argument("--atol", type=float, default=None,
                        help="absolute tolerance of the adaptive radau5 (overrides the file)")
    parser.add_argument("--backend", choices=("local", "dask"), default="local",
                        help="local: compiled batch or process pool; dask: a LocalCluster")
    parser.add_argument("--quiet", action="store_true", help="no progress bar, no summary")


def run(args: argparse.Namespace) -> int:
    """Run the sweep and write the files; bad arguments raise ValueError (exit code 2)."""
    from ..plotting import have_matplotlib
    from ..sweep import parse_grid_spec, simulate_many

    grid: dict[str, list[float]] = {}
    for spec in args.grid:
        name, values = parse_grid_spec(spec)
        if name in grid:
            raise ValueError(f"`--grid` {name!r} is given twice")
        grid[name] = values
    started = time.perf_counter()
    result = simulate_many(args.scene, grid, method=args.method, dt=args.dt, t_end=args.t_end,
                           rtol=args.rtol, atol=args.atol, backend=args.backend,
                           progress=None if not args.quiet else False,
                           steady_amplitude=args.steady_amplitude)
    quantity = args.quantity or ("steady_amplitude" if args.steady_amplitude else
                                 "rest_position")
    column = result.column_for(quantity)
    written = result.write(args.out)
    suffixes = {path.suffix for path in written}
    notes = [f"no {kind} file: {pkg} is not installed (pip install 'lumped[sweep]')"
             for suffix, kind, pkg in ((".parquet", "Parquet", "pyarrow"),
                                       (".nc", "NetCDF", "xarray")) if suffix not in suffixes]
    if len(grid) > 2:
        notes.append(f"no heat map: it needs one or two grid axes, got {len(grid)}")
    elif not have_matplotlib():
        notes.append("no heat map: matplotlib is not installed (pip install 'lumped[plot]')")
    else:
        png = f"{args.out}/{column}.png"
        written.append(result.heatmap(column, png, title=f"{column} ({args.scene})"))
    if not args.quiet:
        table = result.table
        failed = int((table["status"] != "success").sum())
        print(f"{len(table)} scenes ({result.backend}, {table['method'].iloc[0]}) in "
              f"{time.perf_counter() - started:.2f} s; {failed} stopped early")
        for path in written:
            print(f"wrote {path}")
    for note in notes:
        print(note, file=sys.stderr)
    return 0 if result.ok else 1
