"""What a new structure costs ``jit-bdf1``/``jit-bdf2``: compile time per random network.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/structure_compile.py [--examples 12] [--seed 1] [--fast {none,true}]
                                           [--method jit-bdf2]

Draws ``--examples`` networks of the property suite (``networks()`` of
``tests/solvers/test_random_networks.py``: 1-4 nodes, every built-in passive law, half of
them loaded), each a structure never compiled (a new temporary ``LUMPED_CACHE_DIR``; the
shared loops come from numba's cache beside the package, so run the script once first on
a fresh machine), and runs each as the suite does (its grid, three levels of ``dt``;
``--fast none`` is the suite's default ``fast=None``, which runs a short run of a new
structure on the faithful port; ``--fast true`` forces the generated fast loop). Prints,
per network, the CPU time of the three runs and of numba's compilations by generated
module (``scene``: :mod:`lumped.codegen.jit`'s module; ``fast``:
:mod:`lumped.solvers.bdf.fast_codegen`'s), then the self CPU time of numba's passes summed
over all networks (``numba:run_pass``, nested passes subtracted; ``native_lowering``
includes LLVM's optimisation and code generation, also given alone as the time under
``numba:llvm_lock``). CPU times on a shared machine spread by 10-20 %; the counts of
compiled functions do not.
"""

from __future__ import annotations

import argparse
import collections
import os
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


class _Timer:
    """numba event listeners: compile time by module kind, self time by pass."""

    def __init__(self) -> None:
        from numba.core import event

        self.by_kind: collections.Counter = collections.Counter()
        self.functions: collections.Counter = collections.Counter()
        self.passes: collections.Counter = collections.Counter()
        self.llvm = 0.0
        timer = self

        class Compile(event.Listener):
            stack: list = []

            def on_start(self, ev):
                f = ev.data["dispatcher"].py_func
                self.stack.append((time.process_time(), f.__module__, f.__qualname__))

            def on_end(self, ev):
                t0, module, name = self.stack.pop()
                kind = ("fast" if module.startswith("lumped_jitfast_") else
                        "scene" if module.startswith("lumped_jit_") else "shared")
                if not self.stack:
                    timer.by_kind[kind] += time.process_time() - t0
                timer.functions[f"{kind}:{name.rstrip('0123456789_')}"] += 1

        class Pass(event.Listener):
            stack: list = []

            def on_start(self, ev):
                self.stack.append([time.process_time(), 0.0])

            def on_end(self, ev):
                t0, inner = self.stack.pop()
                spent = time.process_time() - t0
                name = ev.data["name"]
                func = name[name.find("[") + 1:-1].rstrip("0123456789_")
                timer.passes[f"{name.split(' ')[0]} [{func}]"] += spent - inner
                if self.stack:
                    self.stack[-1][1] += spent

        class Llvm(event.Listener):
            depth = [0, 0.0]

            def on_start(self, ev):
                if self.depth[0] == 0:
                    self.depth[1] = time.process_time()
                self.depth[0] += 1

            def on_end(self, ev):
                self.depth[0] -= 1
                if self.depth[0] == 0:
                    timer.llvm += time.process_time() - self.depth[1]

        for kind, listener in (("numba:compile", Compile()), ("numba:run_pass", Pass()),
                               ("numba:llvm_lock", Llvm())):
            event.register(kind, listener)


def draw(examples: int, seed: int) -> list:
    """``examples`` networks of the property suite's strategy, reproducibly."""
    sys.path[:0] = [str(ROOT / "tests"), str(ROOT / "tests" / "solvers")]
    from hypothesis import HealthCheck, Phase, given, settings
    from hypothesis import seed as hypothesis_seed
    from test_random_networks import networks

    scenes: list = []

    @hypothesis_seed(seed)
    @settings(max_examples=examples, database=None, phases=[Phase.generate], deadline=None,
              suppress_health_check=list(HealthCheck))
    @given(scene=networks())
    def collect(scene) -> None:
        scenes.append(scene)

    collect()
    return scenes[:examples]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=12)
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--fast", choices=("none", "true"), default="none")
    parser.add_argument("--method", default="jit-bdf2", choices=("jit-bdf1", "jit-bdf2"))
    args = parser.parse_args()
    scenes = draw(args.examples, args.seed)
    with tempfile.TemporaryDirectory() as cache:
        os.environ["LUMPED_CACHE_DIR"] = cache  # every structure new
        from test_random_networks import grid

        from lumped import simulate
        from lumped.bench.timing import measure_unit

        unit = measure_unit()
        timer = _Timer()
        fast = {"none": None, "true": True}[args.fast]
        total = time.process_time()
        cost = []
        for i, scene in enumerate(scenes):
            dt, t_end = grid(scene)
            before = dict(timer.by_kind)
            t0 = time.process_time()
            outcome = "ok"
            try:
                for k in range(3):
                    simulate(scene, method=args.method, dt=dt / 2**k, t_end=t_end, fast=fast)
            except Exception as err:  # noqa: BLE001 - a refused or failed draw is shown
                outcome = type(err).__name__
            spent = time.process_time() - t0
            cost.append(spent)
            kinds = " ".join(f"{k} {v - before.get(k, 0.0):.2f} s"
                             for k, v in sorted(timer.by_kind.items())
                             if v - before.get(k, 0.0) > 1e-3)
            print(f"{i:3d} unknowns {len(scene.nodes) + len(scene.elements):2d}: "
                  f"{spent:6.2f} s  {outcome:12s} compiled: {kinds}", flush=True)
        total = time.process_time() - total
    print(f"\n{args.method}, fast={fast}: {len(scenes)} new structures, {total:.1f} s of CPU, "
          f"{total / len(scenes):.2f} s a structure (median {sorted(cost)[len(cost) // 2]:.2f}"
          f" s; yardstick {unit * 1e3:.1f} ms); LLVM (numba:llvm_lock) {timer.llvm:.1f} s")
    print("compiled functions:", dict(sorted(timer.functions.items())))
    for name, spent in timer.passes.most_common(12):
        print(f"  {name:44s} {spent:7.2f} s")


if __name__ == "__main__":
    main()
