"""The warm cost of ``radau5``'s structure-generic kernels against a structure's own module.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/dispatch_overhead.py [--repeats 40]

``radau5``'s compiled loop reaches the laws through :mod:`lumped.codegen.dispatch` (one
compiled ``branch_law``, ``branch_guards`` and ``active_branch`` for every scene, which
call each element's law template module through the header of the constants: one
indirect call more per law evaluation). Before, it took the ``branch_law`` and
``branch_guards`` of the scene's own generated module (:mod:`lumped.codegen.jit`, one
module per structure). In one process, on the same scene object, the two are swapped
into the scene's plan (``plan.fast``, the compiled loop's parts) run after run,
interleaved (each first in every other round), so that both see the same load; the
runs must give the same numbers bit for bit. Printed per scene: the minimum and median
CPU time of each (:func:`time.process_time`) and the ratio of the medians (generic over
per structure).
Scenes: the paper's ``forcing-F2`` and the 3-mass chain, on ``[0, 5]`` at ``rtol`` 1e-7,
``compiled=True``.
"""

from __future__ import annotations

import argparse
import os
import statistics
import time

import numpy as np

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.bench.scenes import SCENES, generic_scene
from lumped.codegen.function_types import branch_type, guards_type, law_type
from lumped.codegen.jit import jit_scene
from lumped.solvers.eventdriven.fast_parts import pointer
from lumped.solvers.eventdriven.setup import scene_plan

KW = {"method": "radau5", "t_end": 5.0, "rtol": 1e-7, "compiled": True}


def _per_structure_parts(scene, generic: tuple) -> tuple:
    """``generic`` (the loop's parts) with the scene module's kernels and constants."""
    js = jit_scene(scene)
    module = js.module
    return (js, pointer(module.branch_law, law_type()),
            pointer(module.branch_guards, guards_type()), *generic[3:6],
            lambda: pointer(module.active_branch, branch_type()))


def _timed(scene) -> tuple[float, np.ndarray]:
    t0 = time.process_time()
    sol = simulate(scene, **KW)
    return time.process_time() - t0, sol.data


def compare(scene, repeats: int) -> dict:
    simulate(scene, **KW)  # the generic parts made and kept on the plan
    plan = scene_plan(scene)
    generic = plan.fast
    parts = {"per structure": _per_structure_parts(scene, generic), "generic": generic}
    times: dict[str, list[float]] = {name: [] for name in parts}
    data: dict[str, np.ndarray] = {}
    for name, got in parts.items():  # (each compiled or loaded, untimed)
        plan.fast = got
        data[name] = _timed(scene)[1]
    same = np.array_equal(data["per structure"], data["generic"])
    order = list(parts.items())
    for k in range(repeats):  # (each kind first in every other round)
        for name, got in (order if k % 2 == 0 else order[::-1]):
            plan.fast = got
            times[name].append(_timed(scene)[0])
    plan.fast = generic
    out = {name: (min(ts), statistics.median(ts)) for name, ts in times.items()}
    out["ratio"] = out["generic"][1] / out["per structure"][1]
    out["same"] = same
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=40, help="runs of each kind")
    args = parser.parse_args()
    scenes = {"forcing-F2": generic_scene(next(s for s in SCENES if s.name == "forcing-F2")),
              "chain-3": bingham_chain(3)}
    print(f"load {os.getloadavg()[0]:.1f}, {args.repeats} interleaved runs of each kind")
    for name, scene in scenes.items():
        r = compare(scene, args.repeats)
        cells = ", ".join(f"{kind}: min {r[kind][0] * 1e3:.2f} ms, median "
                          f"{r[kind][1] * 1e3:.2f} ms" for kind in ("per structure", "generic"))
        print(f"{name}: {cells}; generic / per structure (medians) {r['ratio']:.3f}; "
              f"same numbers bit for bit: {r['same']}")


if __name__ == "__main__":
    main()
