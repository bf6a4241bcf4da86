"""The ``lumped`` command.

``lumped paper --out DIR [--method M] [--dt DT] [--t-end T]`` reproduces Section 3 of
the paper: one CSV (and, with matplotlib, one PNG) per scenario, and a summary table
on stdout.  ``lumped run SCENE.toml`` simulates a scene file, ``lumped compare SCENE``
checks the generic solver against the closed form, ``lumped bench --out DIR`` measures
speed against error, ``lumped sweep SCENE --grid ... --out DIR`` runs a parameter study,
``lumped warm SCENE`` compiles a scene's code for the compiled methods ahead of time.
Usage errors (bad values, unknown names, bad files) exit with code 2 and a message naming
the argument.
"""

from __future__ import annotations

import argparse
import importlib
import sys
from collections.abc import Sequence

from .. import __version__

__all__ = ["main", "build_parser"]


#: Subcommands that live in their own modules: (name, module, one-line help).
_SUBCOMMANDS = (
    ("paper", "paper", "reproduce the paper's Section 3 (four scenarios)"),
    ("run", "run", "simulate a scene file (TOML) and write its CSV"),
    ("compare", "compare", "compare the generic Newton solver with the closed form"),
    ("bench", "bench", "work-precision benchmark against the exact reference and scipy"),
    ("sweep", "sweep", "run a scene file over a grid of parameters: table and heat map"),
    ("warm", "warm", "compile a scene file's structure ahead of time for the compiled methods"),
)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``lumped`` command, with one sub-parser per subcommand."""
    parser = argparse.ArgumentParser(
        prog="lumped",
        description="Lumped-parameter systems with implicit constitutive laws (DAEs).",
    )
    parser.add_argument("--version", action="version", version=f"lumped {__version__}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, module, summary in _SUBCOMMANDS:
        mod = importlib.import_module(f"lumped.cli.{module}")
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


if __name__ == "__main__":  # pragma: no cover
    raise SystemExit(main())
