"""``lumped bench --out DIR [--quick]``: the work-precision benchmark.

Writes ``runs.csv`` (every run), ``summary.md`` (fastest run per scene, error target
and method; creep; observed orders) and ``work_precision.png`` (when matplotlib is
installed) into ``DIR``.  See :mod:`lumped.bench` for what is measured.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``lumped bench``."""
    parser.add_argument("--out", required=True, type=Path, metavar="DIR",
                        help="directory for runs.csv, summary.md and work_precision.png")
    parser.add_argument("--quick", action="store_true",
                        help="short ladders (under 2 minutes) instead of the full run")
    parser.add_argument("--scenes", default=None, metavar="NAMES",
                        help="comma-separated scene names (default: all)")
    parser.add_argument("--no-creep", action="store_true", help="skip the 100 s creep runs")
    parser.add_argument("--no-events", action="store_true", help="skip the event study")
    parser.add_argument("--impact", action="store_true",
                        help="only the impact scene (issue 11): errors against its exact "
                             "motion, written to DIR/impact.md")


def run(args: argparse.Namespace) -> int:
    """Run the benchmark; ``ValueError`` for an unknown scene name."""
    from .. import bench

    if args.impact:  # the impact scene against its exact solution (bench.impact_scenes)
        from ..bench.impact_scenes import impact_errors, impact_markdown

        args.out.mkdir(parents=True, exist_ok=True)
        (args.out / "impact.md").write_text(impact_markdown(impact_errors(timed=True)))
        print(args.out / "impact.md")
        return 0
    scenes = bench.SCENES
    if args.scenes:
        names = [n.strip() for n in args.scenes.split(",") if n.strip()]
        known = {s.name: s for s in bench.SCENES}
        unknown = [n for n in names if n not in known]
        if unknown:
            raise ValueError(f"`--scenes`: unknown scene(s) {unknown}; known: {sorted(known)}")
        scenes = tuple(known[n] for n in names)
    ladders = bench.QUICK if args.quick else bench.FULL
    start = time.perf_counter()

    def progress(msg: str) -> None:
        print(f"[{time.perf_counter() - start:7.1f} s] {msg}", file=sys.stderr, flush=True)

    report = bench.run_benchmark(ladders=ladders, scenes=scenes, creep=not args.no_creep,
                                 events=not args.no_events, progress=progress)
    for line in bench.write_outputs(report, args.out):
        print(line)
    print(f"{len(report.runs)} runs ({sum(not r.ok for r in report.runs)} failed) "
          f"in {report.wall_s:.1f} s wall time; yardstick {report.unit_s * 1e3:.2f} ms")
    return 0
