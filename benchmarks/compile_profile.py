"""Where a first run's compile time goes: CPU per compiled function and per phase.

Usage, from the repository root, in a process with empty caches (else numba loads what
it compiled before and this shows nothing)::

    d=$(mktemp -d); LUMPED_CACHE_DIR=$d/l XDG_CACHE_HOME=$d/x NUMBA_CACHE_DIR=$d/n \\
        python benchmarks/compile_profile.py [paper] [chain] [--method radau5]

Runs ``simulate`` on the paper scene (``forcing-F2``) and/or the 3-mass chain in turn
(``radau5`` at rtol 1e-7 with ``compiled=True`` by default, or ``--method jit-bdf2`` at
dt 1e-4), and prints, per run, the CPU (:func:`time.process_time`) of each function
numba compiled, *self* time (a function compiled while another is typed counts for
itself, not for the caller), split into numba's typing, its lowering to LLVM IR, its
other passes, LLVM's optimisation and LLVM's machine-code emission. Read from numba's
event API (``numba:compile``, ``numba:run_pass``) and from llvmlite's pass managers and
numba's JIT engine, wrapped for the run. A chain run after the paper scene is a second
structure: the shared code is compiled, its own kernels are not. The numbers carry the
machine's load (numba's Python-side work is most of it); read them in pairs.
"""

from __future__ import annotations

import argparse
import collections
import time

_PHASES = ("typing", "lowering", "passes", "llvm-opt", "llvm-emit", "other")


class _Profile:
    """Self CPU per ``(function, phase)``."""

    def __init__(self) -> None:
        self.stack: list[list] = []  # [key, t0, children]
        self.names: list[str] = []
        self.acc: dict = collections.defaultdict(float)

    def push(self, phase: str) -> None:
        name = self.names[-1] if self.names else "?"
        self.stack.append([(name, phase), time.process_time(), 0.0])

    def pop(self) -> None:
        key, t0, children = self.stack.pop()
        dt = time.process_time() - t0
        self.acc[key] += dt - children
        if self.stack:
            self.stack[-1][2] += dt

    def install(self) -> None:
        import llvmlite.binding.newpassmanagers as npm
        import numba.core.codegen as cg
        from numba.core import event

        prof = self

        class Compile(event.Listener):
            def on_start(self, ev) -> None:
                fn = getattr(ev.data["dispatcher"], "py_func", None)
                prof.names.append(getattr(fn, "__qualname__", "?"))
                prof.push("other")

            def on_end(self, ev) -> None:
                prof.pop()
                prof.names.pop()

        class Pass(event.Listener):
            def on_start(self, ev) -> None:
                name = ev.data["name"]
                prof.push("typing" if name.startswith("nopython_type_inference") else
                          "lowering" if name.startswith("native_lowering") else "passes")

            def on_end(self, ev) -> None:
                prof.pop()

        event.register("numba:compile", Compile())
        event.register("numba:run_pass", Pass())
        for cls, meth, phase in ((npm.ModulePassManager, "run", "llvm-opt"),
                                 (npm.FunctionPassManager, "run", "llvm-opt"),
                                 (cg.JitEngine, "finalize_object", "llvm-emit")):
            setattr(cls, meth, self._timed(getattr(cls, meth), phase))

    def _timed(self, fn, phase: str):
        def timed(*args, **kwargs):
            self.push(phase)
            try:
                return fn(*args, **kwargs)
            finally:
                self.pop()

        return timed

    def table(self, rows: int) -> str:
        by_fn: dict = collections.defaultdict(float)
        by_phase: dict = collections.defaultdict(float)
        for (fn, phase), v in self.acc.items():
            by_fn[fn] += v
            by_phase[phase] += v
        lines = ["phases: " + ", ".join(f"{p} {by_phase[p]:.2f} s" for p in _PHASES),
                 f"{'function':30s}" + "".join(f"{p:>10s}" for p in _PHASES) + "     total"]
        for fn, total in sorted(by_fn.items(), key=lambda kv: -kv[1])[:rows]:
            lines.append(f"{fn[:30]:30s}" + "".join(f"{self.acc[(fn, p)]:10.2f}"
                                                    for p in _PHASES) + f"{total:10.2f}")
        return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scenes", nargs="*", choices=("paper", "chain"), default=["paper"])
    parser.add_argument("--method", default="radau5", choices=("radau5", "jit-bdf2"))
    parser.add_argument("--rows", type=int, default=16)
    args = parser.parse_args()
    prof = _Profile()
    prof.install()
    from lumped import simulate
    from lumped.bench.network_scenes import bingham_chain
    from lumped.scenarios import scenario_scene

    options = ({"rtol": 1e-7, "compiled": True} if args.method == "radau5"
               else {"dt": 1e-4})
    for name in args.scenes:
        prof.acc.clear()
        scene = scenario_scene("forcing-F2") if name == "paper" else bingham_chain(3)
        c0 = time.process_time()
        sol = simulate(scene, method=args.method, t_end=5.0, **options)
        cpu = time.process_time() - c0
        print(f"== {name}, {args.method}: the run {cpu:.2f} s of CPU, "
              f"loop {sol.stats.get('loop', '-')}")
        print(prof.table(args.rows))


if __name__ == "__main__":
    main()
