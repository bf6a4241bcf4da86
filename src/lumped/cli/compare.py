"""``lumped compare SCENE.toml [--method bdf1|bdf2] [--dt ...] [--t-end ...]``.

Runs the generic Newton solver and the closed form on the scene (see
:func:`lumped.compare.compare`) and prints the largest difference per variable and
the time per step of each path with their ratio.
"""

from __future__ import annotations

import argparse

from ..compare import compare

__all__ = ["add_arguments", "run"]


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``lumped compare``."""
    parser.add_argument("scene", help="scene file (TOML), see docs/scenes.md")
    parser.add_argument("--method", choices=("bdf1", "bdf2"), default="bdf2",
                        help="generic method, compared with closed-<method> (default bdf2)")
    parser.add_argument("--dt", type=float, default=None, help="step size (overrides the file)")
    parser.add_argument("--t-end", dest="t_end", type=float, default=None,
                        help="final time (overrides the file)")
    parser.add_argument("--repeat", type=int, default=3,
                        help="runs per path; the best time counts (default 3)")


def run(args: argparse.Namespace) -> int:
    """Print the comparison; exit code 0. Bad scenes or settings raise ValueError."""
    from ..io.scenefile import load_scene

    scene, settings = load_scene(args.scene)
    dt = args.dt if args.dt is not None else settings.get("dt")
    t_end = args.t_end if args.t_end is not None else settings.get("t_end")
    if dt is None or t_end is None:
        raise ValueError(f"{args.scene}: give --dt and --t-end or [solver] dt and t_end")
    report = compare(scene, dt=dt, t_end=t_end, method=args.method, repeat=args.repeat)
    print(report.format())
    return 0
