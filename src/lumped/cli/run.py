"""``lumped run SCENE.toml --out results.csv [--method ...] [--dt ...] [--t-end ...]
[--rtol ...] [--atol ...] [--quiet]``.

Loads a scene file (:mod:`lumped.io.scenefile`), runs :func:`lumped.simulate.simulate`
with the file's ``[solver]`` settings overridden by the command line, and writes the
CSV (``t``, ``x_<node>``, ``v_<node>`` per node, ``F_<element>`` per element).  On a
terminal a line shows the elapsed time once the run has lasted two seconds
(:class:`lumped.cli.progress.Ticker`); not with ``--quiet`` or when stdout is not a
terminal.
"""

from __future__ import annotations

import argparse
import sys

from ..simulate import simulate
from ..solvers.registry import FIXED_STEP_METHODS, METHODS, resolve_method
from ..solvers.status import SolverError
from .progress import Ticker, progress_wanted

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``lumped run``."""
    parser.add_argument("scene", help="scene file (TOML), see docs/scenes.md")
    parser.add_argument("--out", required=True, help="CSV file to write")
    parser.add_argument("--method", choices=METHODS, default=None,
                        help="solver (default: the file's [solver] method, else auto)")
    parser.add_argument("--dt", type=float, default=None, help="step size (overrides the file)")
    parser.add_argument("--t-end", dest="t_end", type=float, default=None,
                        help="final time (overrides the file)")
    parser.add_argument("--rtol", type=float, default=None,
                        help="relative tolerance of an adaptive method (overrides the file)")
    parser.add_argument("--atol", type=float, default=None,
                        help="absolute tolerance of an adaptive method (overrides the file)")
    parser.add_argument("--quiet", action="store_true",
                        help="no elapsed-time line on the terminal while the solver runs")


def run(args: argparse.Namespace) -> int:
    """Run the scene; exit code 0 on success, 1 when the solver stopped early (the CSV
    then holds the steps up to the failure) or found no consistent initial state. Bad
    files, settings or initial forces raise ValueError."""
    from ..io.scenefile import load_scene

    scene, settings = load_scene(args.scene)
    method = args.method or settings.get("method", "auto")
    dt = args.dt if args.dt is not None else settings.get("dt")
    t_end = args.t_end if args.t_end is not None else settings.get("t_end")
    rtol = args.rtol if args.rtol is not None else settings.get("rtol")
    atol = args.atol if args.atol is not None else settings.get("atol")
    if dt is None and resolve_method(scene, method, dt=dt, rtol=rtol,
                                     atol=atol) in FIXED_STEP_METHODS:
        raise ValueError(f"{args.scene}: no step size: give --dt or [solver] dt")
    if t_end is None:
        raise ValueError(f"{args.scene}: no final time: give --t-end or [solver] t_end")
    try:
        with Ticker(f"lumped run {args.scene}",
                    enabled=progress_wanted(bool(getattr(args, "quiet", False)))):
            sol = simulate(scene, method=method, dt=dt, t_end=t_end, rtol=rtol, atol=atol,
                           throw=False)
    except SolverError as err:  # no consistent initial state: nothing to write
        print(f"lumped run: {err}", file=sys.stderr)
        return 1
    path = sol.to_csv(args.out)
    st = sol.stats
    print(f"{path}: {len(sol.t)} rows, method {sol.method}, {st['steps']} steps, "
          f"{st['newton_iterations']} Newton iterations")
    if not sol.ok:
        print(f"lumped run: solver stopped: {sol.message}", file=sys.stderr)
        return 1
    return 0
