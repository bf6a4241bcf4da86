"""Run the random-network property suite at a large budget and count its examples
(issue 29: "10 000 examples per method at ``LUMPED_LARGE=1``").

Each method's property of ``tests/solvers/test_random_networks.py`` runs as pytest runs
it under ``LUMPED_LARGE=N`` (profile ``long``, a fixed ``--hypothesis-seed``), split into
chunks of ``--chunk`` examples, each chunk a fresh process with its own seed (``seed``,
``seed + 1``, ...): a compiled method keeps every structure it compiles in its process
(about 8.5 MB each, numba never frees one), so its chunks bound the memory. The counts
are hypothesis's own statistics (``--hypothesis-show-statistics``: passing, failing,
invalid); a failing chunk keeps its whole output in ``--logs``.

Usage, from the repository root, under ``nice`` on a shared machine::

    python benchmarks/property_counts.py --methods bdf1 bdf2 --examples 10000
    python benchmarks/property_counts.py --methods jit-bdf2 --examples 1000 --chunk 250

Methods (the property each runs):

* ``bdf1``, ``bdf2``: ``test_random_passive_network`` (every check of the suite);
* ``radau5``: ``test_random_passive_network_python_loop`` (its Python loop);
* ``radau5-tight``: ``test_random_network_tight_tolerance`` (``rtol = 1e-10``, against
  ``bdf2`` and ``bdf1`` as ``dt`` halves);
* ``radau5-both``: ``test_random_passive_network_both_loops`` (the Python and the compiled
  loop give the same numbers; compiles each new structure);
* ``jit-bdf1``, ``jit-bdf2``: ``test_random_passive_network_compiled`` (compiles each new
  structure: about 2 s of CPU a draw).

Prints one line per chunk and a table per method: examples passing, failing, invalid,
CPU seconds (the children's) and CPU seconds per passing example.
"""

from __future__ import annotations

import argparse
import os
import re
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

TEST = "tests/solvers/test_random_networks.py::"
PROPERTIES = {
    "bdf1": "test_random_passive_network[bdf1]",
    "bdf2": "test_random_passive_network[bdf2]",
    "radau5": "test_random_passive_network_python_loop[radau5]",
    "radau5-tight": "test_random_network_tight_tolerance[radau5]",
    "radau5-both": "test_random_passive_network_both_loops[radau5]",
    "jit-bdf1": "test_random_passive_network_compiled[jit-bdf1]",
    "jit-bdf2": "test_random_passive_network_compiled[jit-bdf2]",
}
#: hypothesis's statistics line, e.g. "10000 passing, 0 failing, and 1358 invalid ..."
_COUNTS = re.compile(r"(\d+) passing, (\d+) failing, and (\d+) invalid")


def counts(output: str) -> tuple[int, int, int] | None:
    """``(passing, failing, invalid)`` summed over the statistics lines of ``output`` (one
    per test function run), or ``None`` when it has none (pytest stopped first)."""
    found = _COUNTS.findall(output)
    if not found:
        return None
    return tuple(sum(int(f[k]) for f in found) for k in range(3))  # type: ignore[return-value]


def run_chunk(method: str, examples: int, seed: int, cache: str, logs: Path) -> dict:
    """One chunk in a fresh process: its counts, return code and CPU seconds."""
    env = dict(os.environ, LUMPED_LARGE=str(examples), HYPOTHESIS_PROFILE="long",
               XDG_CACHE_HOME=cache)
    cmd = [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", "-n", "0",
           TEST + PROPERTIES[method], f"--hypothesis-seed={seed}",
           "--hypothesis-show-statistics"]
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    done = subprocess.run(cmd, env=env, capture_output=True, text=True, check=False)
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    out = done.stdout + done.stderr
    got = counts(out)
    row = {"method": method, "seed": seed, "rc": done.returncode,
           "cpu": (after.ru_utime + after.ru_stime) - (before.ru_utime + before.ru_stime),
           "wall": time.perf_counter() - t0, "counts": got}
    if done.returncode != 0 or got is None:
        path = logs / f"{method}-{seed}.log"
        path.write_text(out)
        row["log"] = str(path)
    return row


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--methods", nargs="+", default=["bdf1", "bdf2", "radau5"],
                    choices=sorted(PROPERTIES))
    ap.add_argument("--examples", type=int, default=10_000, help="per method")
    ap.add_argument("--chunk", type=int, default=None,
                    help="examples per process (default: all in one; 500 for compiled methods)")
    ap.add_argument("--seed", type=int, default=22100, help="the first chunk's seed")
    ap.add_argument("--logs", type=Path, default=Path(tempfile.gettempdir()),
                    help="where a failing chunk's output is kept")
    args = ap.parse_args(argv)
    if args.examples < 1:
        ap.error(f"--examples must be at least 1, got {args.examples}")
    if args.chunk is not None and args.chunk < 2:
        ap.error(f"--chunk must be at least 2 (LUMPED_LARGE=1 means 10 000), got {args.chunk}")
    args.logs.mkdir(parents=True, exist_ok=True)
    cache = tempfile.mkdtemp(prefix="lumped-property-cache-")
    failed = False
    table = []
    for method in args.methods:
        compiled = method.startswith("jit-") or method == "radau5-both"
        chunk = args.chunk or (500 if compiled else args.examples)
        total = [0, 0, 0]
        cpu, seed, left = 0.0, args.seed, args.examples
        while left > 0:
            n = max(2, min(chunk, left))
            row = run_chunk(method, n, seed, cache, args.logs)
            got = row["counts"] or (0, 0, 0)
            total = [a + b for a, b in zip(total, got, strict=True)]
            cpu += row["cpu"]
            print(f"{method:13s} seed {seed}: {n} asked, passing/failing/invalid {got}, "
                  f"rc {row['rc']}, {row['cpu']:.0f} s CPU" +
                  (f", output in {row['log']}" if "log" in row else ""), flush=True)
            if row["rc"] != 0 or row["counts"] is None:
                failed = True
                break
            left -= n
            seed += 1
        table.append((method, *total, cpu))
    print(f"\n{'method':13s} {'passing':>8s} {'failing':>8s} {'invalid':>8s} {'CPU s':>8s} "
          f"{'s/example':>9s}")
    for method, p, f, i, cpu in table:
        print(f"{method:13s} {p:8d} {f:8d} {i:8d} {cpu:8.0f} {cpu / max(p, 1):9.3f}")
    return 1 if failed else 0


if __name__ == "__main__":
    raise SystemExit(main())
