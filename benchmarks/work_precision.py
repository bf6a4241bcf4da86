"""Work-precision benchmark (the same code as ``lumped bench``).

Usage, from the repository root::

    PYTHONPATH=src python benchmarks/work_precision.py --out bench-out [--quick]
"""

from __future__ import annotations

import argparse

from lumped.cli.bench import add_arguments, run

if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_arguments(parser)
    raise SystemExit(run(parser.parse_args()))
