"""``lumped bench --out DIR [--quick] [--quiet]``: the work-precision benchmark.

Writes ``runs.csv`` (every run), ``summary.md`` (fastest run per scene, error target
and method; creep; observed orders) and ``work_precision.png`` (when matplotlib is
installed) into ``DIR``, then prints the ratio of our best method's time to the fastest
scipy time per scene and error target, warm and with new numbers (the user's columns:
each setting of our compiled methods run again with a ``k`` never run before in the
process, a new ``k`` for each run, as many runs as the warm timing took; the smallest
time kept, as for the warm time).  Progress shows on a terminal (not with ``--quiet``).  See
:mod:`lumped.bench` for what is measured.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from .progress import Progress, progress_wanted

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Options of ``lumped bench``."""
    parser.add_argument("--out", required=True, type=Path, metavar="DIR",
                        help="directory for runs.csv, summary.md and work_precision.png")
    parser.add_argument("--quick", action="store_true",
                        help="short ladders (under 2 minutes) instead of the full run")
    parser.add_argument("--scenes", default=None, metavar="NAMES",
                        help="comma-separated scene names (default: all)")
    parser.add_argument("--methods", default=None, metavar="NAMES",
                        help="comma-separated method names (default: all available but "
                             "jit-bdf1 and jit-bdf2, which run only when named)")
    parser.add_argument("--no-creep", action="store_true", help="skip the 100 s creep runs")
    parser.add_argument("--no-events", action="store_true", help="skip the event study")
    parser.add_argument("--quiet", action="store_true",
                        help="print nothing but errors (no progress, no summary)")
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
    methods = bench.available_methods()
    if getattr(args, "methods", None):
        names = [n.strip() for n in args.methods.split(",") if n.strip()]
        known = {m.name: m for m in bench.available_methods(every=True)}
        unknown = [n for n in names if n not in known]
        if unknown:
            raise ValueError(f"`--methods`: unknown method(s) {unknown}; known: {list(known)}")
        methods = tuple(known[n] for n in names)
    creep, events = not args.no_creep, not args.no_events
    total = bench.count_steps(ladders, scenes, methods, creep=creep, events=events)
    with Progress(total, "lumped bench", enabled=progress_wanted(args.quiet)) as bar:
        report = bench.run_benchmark(ladders=ladders, scenes=scenes, methods=methods,
                                     creep=creep, events=events,
                                     progress=lambda msg: bar.update(note=msg))
    lines = bench.write_outputs(report, args.out)
    if not args.quiet:
        for line in lines:
            print(line)
        print(f"{len(report.runs)} runs ({sum(not r.ok for r in report.runs)} failed) "
              f"in {report.wall_s:.1f} s wall time; yardstick {report.unit_s * 1e3:.2f} ms")
        print("Our best method / the fastest scipy peer (CPU time ratio; < 1: we are faster):")
        print(bench.ratio_table(report), end="")
        if any(r.has_new_numbers for r in report.runs):
            print("With new numbers (the user's columns: k never run before in the process, "
                  "a new k each run), our best / the fastest scipy peer:")
            print(bench.ratio_table(report, new_numbers=True), end="")
    return 0
