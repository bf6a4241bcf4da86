"""The ``lumped`` command.

``lumped paper --out DIR [--method M] [--dt DT] [--t-end T]`` reproduces Section 3 of
the paper: one CSV (and, with matplotlib, one PNG) per scenario, and a summary table
on stdout.  ``lumped run SCENE.toml`` simulates a scene file, ``lumped compare SCENE``
checks the generic solver against the closed form, ``lumped bench --out DIR`` measures
speed against error.  Usage errors (bad values, unknown
names, bad files) exit with code 2 and a message naming the argument.
"""

from __future__ import annotations

import argparse
import importlib
import sys
import time
from collections.abc import Sequence
from pathlib import Path

from . import __version__
from ._validate import as_positive
from .plotting import have_matplotlib, plot_trajectory
from .scenarios import (
    PAPER_DT,
    PAPER_METHODS,
    PAPER_SCENARIOS,
    PAPER_T_END,
    run_scenario,
)
from .trajectory import StickSummary, _fmt, summarize

__all__ = ["main", "build_parser"]



#: Subcommands that live in their own modules: (name, module, one-line help).
_SUBCOMMANDS = (
    ("run", "cmd_run", "simulate a scene file (TOML) and write its CSV"),
    ("compare", "cmd_compare", "compare the generic Newton solver with the closed form"),
    ("bench", "cmd_bench", "work-precision benchmark against the exact reference and scipy"),
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``lumped`` command, with one sub-parser per subcommand."""
    parser = argparse.ArgumentParser(
        prog="lumped",
        description="Lumped-parameter systems with implicit constitutive laws (DAEs).",
    )
    parser.add_argument("--version", action="version", version=f"lumped {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    paper = sub.add_parser(
        "paper", help="reproduce the paper's Section 3 (four scenarios)",
        description="Run the four scenarios of the paper's Section 3 and write CSVs, figures "
        "and a summary table.",
    )
    paper.add_argument("--out", required=True, type=Path, help="output directory")
    paper.add_argument(
        "--method", default=PAPER_METHODS[0],
        help=f"one of {', '.join(PAPER_METHODS)}; default: closed-bdf1, the paper's "
        "Algorithm 1 (bdf1/bdf2: the generic Newton solver; exact: the event-driven reference)",
    )
    paper.add_argument("--dt", type=float, default=PAPER_DT, help=f"time step (default {PAPER_DT})")
    paper.add_argument("--t-end", type=float, default=PAPER_T_END,
                       help=f"final time (default {PAPER_T_END})")
    paper.add_argument("--scenario", action="append", default=None, metavar="NAME",
                       help="run only this scenario (repeatable); default: all four")
    paper.set_defaults(handler=_run_paper)

    for name, module, summary in _SUBCOMMANDS:
        mod = importlib.import_module(f"lumped.{module}")
        sp = sub.add_parser(name, help=summary, description=(mod.__doc__ or "").strip())
        mod.add_arguments(sp)
        sp.set_defaults(handler=mod.run)
    return parser


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``lumped`` console script; returns the exit code."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse: --help (0) or a usage error (2)
        return int(exc.code or 0)
    try:
        return int(args.handler(args))
    except (ValueError, TypeError) as exc:
        print(f"lumped {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except (RuntimeError, FloatingPointError) as exc:  # a failed solve: not a usage error
        print(f"lumped {args.command}: failed: {exc}", file=sys.stderr)
        return 1


def _run_paper(args: argparse.Namespace) -> int:
    method = args.method
    if method not in PAPER_METHODS:
        raise ValueError(f"`--method` must be one of {PAPER_METHODS}, got {args.method!r}")
    dt = as_positive("--dt", args.dt)
    t_end = as_positive("--t-end", args.t_end)
    names = args.scenario or list(PAPER_SCENARIOS)
    for name in names:
        if name not in PAPER_SCENARIOS:
            raise ValueError(
                f"unknown scenario {name!r}; known scenarios: {', '.join(PAPER_SCENARIOS)}"
            )
    out: Path = args.out
    plots = have_matplotlib()
    if not plots:
        print("matplotlib is not installed: writing CSVs only (pip install 'lumped[plot]').")
    rows = []
    started = time.perf_counter()
    for name in names:
        traj = run_scenario(name, method=method, dt=dt, t_end=t_end)
        traj.to_csv(out / f"{name}.csv")
        if plots:
            plot_trajectory(traj, out / f"{name}.png", title=f"{name} ({method}, dt = {dt:g})")
        rows.append((name, summarize(traj)))
    print(format_summary(rows))
    print(f"wrote {len(rows)} scenario(s) to {out} with {method}, dt = {dt:g}, t_end = {t_end:g} "
          f"in {time.perf_counter() - started:.2f} s")
    return 0


def format_summary(rows: Sequence[tuple[str, StickSummary]]) -> str:
    """A fixed-width table: final x and v, last slip-to-stick time, rest position, stick time."""
    header = ("scenario", "final x", "final v", "last stick at", "rest x", "stick time")
    lines = [header] + [
        (name, _fmt(s.final_x), _fmt(s.final_v), _fmt(s.last_stick_time),
         _fmt(s.rest_position), _fmt(s.stick_time))
        for name, s in rows
    ]
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    text = ["  ".join(cell.ljust(w) for cell, w in zip(line, widths, strict=True)).rstrip()
            for line in lines]
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
