"""Run the four scenarios of the paper's Section 3 and write CSVs, figures and a summary
table (``lumped paper --out DIR``); progress shows on a terminal (not with ``--quiet``)."""

from __future__ import annotations

import argparse
import time
from collections.abc import Sequence
from pathlib import Path

from .._validate import as_positive
from ..plotting import have_matplotlib, plot_trajectory
from ..scenarios import PAPER_DT, PAPER_METHODS, PAPER_SCENARIOS, PAPER_T_END, run_scenario
from ..trajectory import StickSummary, fmt_number, summarize
from .progress import Progress, progress_wanted

__all__ = ["add_arguments", "format_summary", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``lumped paper``."""
    parser.add_argument("--out", required=True, type=Path, help="output directory")
    parser.add_argument(
        "--method", default=PAPER_METHODS[0],
        help=f"one of {', '.join(PAPER_METHODS)}; default: closed-bdf1, the paper's "
        "Algorithm 1 (bdf1/bdf2: the generic Newton solver; exact: the event-driven reference)",
    )
    parser.add_argument("--dt", type=float, default=PAPER_DT,
                        help=f"time step (default {PAPER_DT})")
    parser.add_argument("--t-end", type=float, default=PAPER_T_END,
                       help=f"final time (default {PAPER_T_END})")
    parser.add_argument("--scenario", action="append", default=None, metavar="NAME",
                       help="run only this scenario (repeatable); default: all four")
    parser.add_argument("--quiet", action="store_true",
                        help="print nothing but errors (no progress, no summary table)")


def run(args: argparse.Namespace) -> int:
    """Run the selected scenarios; ``ValueError`` for a bad option."""
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
    quiet = bool(getattr(args, "quiet", False))
    plots = have_matplotlib()
    if not plots and not quiet:
        print("matplotlib is not installed: writing CSVs only (pip install 'lumped[plot]').")
    rows = []
    started = time.perf_counter()
    with Progress(len(names), "lumped paper", enabled=progress_wanted(quiet)) as bar:
        for name in names:
            traj = run_scenario(name, method=method, dt=dt, t_end=t_end)
            traj.to_csv(out / f"{name}.csv")
            if plots:
                plot_trajectory(traj, out / f"{name}.png",
                                title=f"{name} ({method}, dt = {dt:g})")
            rows.append((name, summarize(traj)))
            bar.update(note=name)
    if quiet:
        return 0
    print(format_summary(rows))
    print(f"wrote {len(rows)} scenario(s) to {out} with {method}, dt = {dt:g}, t_end = {t_end:g} "
          f"in {time.perf_counter() - started:.2f} s")
    return 0


def format_summary(rows: Sequence[tuple[str, StickSummary]]) -> str:
    """A fixed-width table: final x and v, last slip-to-stick time, rest position, stick time."""
    header = ("scenario", "final x", "final v", "last stick at", "rest x", "stick time")
    lines = [header] + [
        (name, fmt_number(s.final_x), fmt_number(s.final_v), fmt_number(s.last_stick_time),
         fmt_number(s.rest_position), fmt_number(s.stick_time))
        for name, s in rows
    ]
    widths = [max(len(line[i]) for line in lines) for i in range(len(header))]
    text = ["  ".join(cell.ljust(w) for cell, w in zip(line, widths, strict=True)).rstrip()
            for line in lines]
    text.insert(1, "  ".join("-" * w for w in widths))
    return "\n".join(text)
