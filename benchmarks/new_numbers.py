"""New numbers against the warm repeat, in one warm process (issue 27's 1.3x target).

Usage, from the repository root::

    python benchmarks/new_numbers.py [--repeats 7] [--params k] [--json]
        [--scenes "paper forcing-F2,chain-3"] [--cases "radau5 compiled=True"]

For each case (method and scene) the scene is first run twice (its structure's compiled
module is loaded, the process is warm); then, ``--repeats`` times, a scene with **new
numbers** (:func:`lumped.bench.new_numbers.scene_with_new_numbers`: every law parameter
named in ``--params``, default the springs' ``k``, times a factor never used before in the
process) is run once (*new*) and again on the same scene object (*warm*). Printed: the
smallest CPU time (:func:`time.process_time`) of each over the repeats, their ratio (the
target is at most 1.3) and both over the yardstick (:func:`lumped.bench.measure_unit`,
the smaller of two measurements, before and after). Cases: ``radau5`` at ``rtol`` 1e-7
(default options, what ``auto`` runs), ``radau5`` with ``compiled=True``, ``jit-bdf2`` at
``dt`` 1e-4; on the paper's scene (``forcing-F2``, ``[0, 5]``) and the 3-mass chain
(:func:`lumped.bench.network_scenes.bingham_chain`, ``[0, 5]``); with ``--scenes``, also
the bench's ``viscous-soft`` (released from ``x0 = 0.3``, one event).
"""

from __future__ import annotations

import argparse
import json
import os
import time

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.bench.new_numbers import scene_with_new_numbers
from lumped.bench.scenes import SCENES as BENCH_SCENES
from lumped.bench.scenes import generic_scene
from lumped.bench.timing import measure_unit
from lumped.scenarios import scenario_scene

T_END = 5.0
CASES = {
    "radau5": ("radau5", {"rtol": 1e-7}),
    "radau5 compiled=True": ("radau5", {"rtol": 1e-7, "compiled": True}),
    "jit-bdf2": ("jit-bdf2", {"dt": 1e-4}),
}
SCENES = {"paper forcing-F2": lambda: scenario_scene("forcing-F2"),
          "chain-3": lambda: bingham_chain(3),
          "viscous-soft": lambda: generic_scene(
              next(s for s in BENCH_SCENES if s.name == "viscous-soft"))}
#: The scenes run without ``--scenes``.
DEFAULT_SCENES = ("paper forcing-F2", "chain-3")


def _cpu(scene, method: str, options: dict) -> float:
    c0 = time.process_time()
    simulate(scene, method=method, t_end=T_END, throw=False, **options)
    return time.process_time() - c0


def measure(scene_name: str, case: str, repeats: int, params: tuple[str, ...]) -> dict:
    """The smallest CPU times (s) of a run with new numbers and of its warm repeat."""
    method, options = CASES[case]
    base = SCENES[scene_name]()
    for _ in range(2):
        _cpu(base, method, options)
    new, warm = [], []
    for _ in range(repeats):
        scene = scene_with_new_numbers(base, parameters=params)
        new.append(_cpu(scene, method, options))
        warm.append(_cpu(scene, method, options))
    return {"scene": scene_name, "case": case, "new_s": min(new), "warm_s": min(warm)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--params", default="k",
                        help="comma-separated law parameters to change (default: k)")
    parser.add_argument("--json", action="store_true", help="print JSON records")
    parser.add_argument("--scenes", default=",".join(DEFAULT_SCENES),
                        help=f"comma-separated, of: {', '.join(SCENES)}")
    parser.add_argument("--cases", default=",".join(CASES),
                        help=f"comma-separated, of: {', '.join(CASES)}")
    args = parser.parse_args()
    params = tuple(p for p in args.params.split(",") if p)
    scenes = [s for s in args.scenes.split(",") if s]
    cases = [c for c in args.cases.split(",") if c]
    unit = measure_unit()
    records = [measure(s, c, args.repeats, params) for s in scenes for c in cases]
    unit = min(unit, measure_unit())
    if args.json:
        print(json.dumps({"yardstick_s": unit, "params": params, "records": records},
                         indent=1))
        return
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, {os.cpu_count()} cpus, load "
          f"{os.getloadavg()[0]:.1f}; new numbers in {', '.join(params)}; min of "
          f"{args.repeats}; Y = the yardstick, {unit * 1e3:.1f} ms")
    print("| scene | case | new numbers | warm repeat | new / warm |")
    print("|---|---|---|---|---|")
    for r in records:
        print(f"| {r['scene']} | {r['case']} | {r['new_s'] * 1e3:.2f} ms = "
              f"{r['new_s'] / unit:.3g} Y | {r['warm_s'] * 1e3:.2f} ms = "
              f"{r['warm_s'] / unit:.3g} Y | {r['new_s'] / r['warm_s']:.2f} |")


if __name__ == "__main__":
    main()
