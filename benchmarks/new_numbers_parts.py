"""What a run with new numbers adds over its warm repeat, part by part (issue 27).

Usage, from the repository root::

    python benchmarks/new_numbers_parts.py [--repeats 400] [--scene viscous-soft]
        [--case "radau5 compiled=True"]

The pairs of :mod:`new_numbers` (a scene with a new ``k``, run once, *new*, then again,
*warm*), with CPU timers (:func:`time.thread_time`) around the parts a new scene pays
for: each named function is replaced, in every ``lumped`` module that holds it, by a
wrapper that adds its inclusive time (nested parts are counted in both). Printed: the
median run of each kind, and per part its mean time in a new run and in a warm one, in
microseconds and in yardstick iterations (``u``, :func:`lumped.bench.measure_unit`'s
loop, measured in the same process before and after; the comparison across runs on a
noisy machine). The wrappers cost about a microsecond a call.
"""

from __future__ import annotations

import argparse
import importlib
import os
import statistics
import sys
import time

from new_numbers import CASES, SCENES, _cpu

from lumped.bench.new_numbers import scene_with_new_numbers
from lumped.bench.timing import YARDSTICK_ITERATIONS, measure_unit

#: The parts timed: ``module:function``, and a short name.
PARTS = {
    "lumped.solvers.implicit.initial_state:consistent_initial_state": "initial state",
    "lumped.solvers.implicit.initial_state:_limit_system": "  its Newton (limit system)",
    "lumped.solvers.implicit.initial_state:initial_rest_forces": "  its try at rest",
    "lumped.solvers.eventdriven.setup:scene_plan": "plan (content key, new plan)",
    "lumped.solvers.eventdriven.fast_parts:loop_parts": "compiled loop's parts",
    "lumped.solvers.bdf.fixed_step_jit:port_parts": "  port_parts",
    "lumped.codegen.dispatch:dispatch_scene": "  dispatch_scene",
    "lumped.solvers.eventdriven.mode_parts:mode_parts": "mode kernels and guards",
}
def timed(spec: str, totals: dict) -> None:
    """Replace function ``spec`` (``module:function``) by a timing wrapper wherever a
    loaded ``lumped`` module holds it."""
    module_name, name = spec.rsplit(":", 1)
    fn = getattr(importlib.import_module(module_name), name)

    def wrapper(*args, **kwargs):
        t0 = time.thread_time()
        try:
            return fn(*args, **kwargs)
        finally:
            totals[spec] = totals.get(spec, 0.0) + time.thread_time() - t0

    for module in list(sys.modules.values()):
        if getattr(module, "__name__", "").startswith("lumped") \
                and getattr(module, name, None) is fn:
            setattr(module, name, wrapper)


def arguments(description: str, repeats: int) -> argparse.Namespace:
    """``--repeats`` (default ``repeats``), ``--scene`` and ``--case`` of the command line
    (this script's, and :mod:`new_numbers_ahead`'s)."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--repeats", type=int, default=repeats)
    parser.add_argument("--scene", default="viscous-soft", choices=list(SCENES))
    parser.add_argument("--case", default="radau5 compiled=True", choices=list(CASES))
    return parser.parse_args()


def main() -> None:
    args = arguments(__doc__.splitlines()[0], 400)
    method, options = CASES[args.case]
    import lumped.solvers.eventdriven.runner  # noqa: F401 - (the modules that hold them)

    totals: dict[str, float] = {}
    for spec in PARTS:
        timed(spec, totals)
    unit = measure_unit()
    base = SCENES[args.scene]()
    for _ in range(3):  # warm: the structure's module, the code paths of new numbers
        scene = scene_with_new_numbers(base)
        _cpu(scene, method, options), _cpu(scene, method, options)
    runs: dict[str, list[float]] = {"new": [], "warm": []}
    parts: dict[str, dict[str, float]] = {"new": {}, "warm": {}}
    for _ in range(args.repeats):
        scene = scene_with_new_numbers(base)
        for kind in ("new", "warm"):
            totals.clear()
            runs[kind].append(_cpu(scene, method, options))
            for spec, t in totals.items():
                parts[kind][spec] = parts[kind].get(spec, 0.0) + t
    unit = min(unit, measure_unit())
    u = unit / YARDSTICK_ITERATIONS
    new, warm = (statistics.median(runs[k]) for k in ("new", "warm"))
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.1f}; "
          f"{args.scene}, {args.case}; {args.repeats} pairs; u = {u * 1e9:.0f} ns")
    print(f"median new {new * 1e6:.0f} us = {new / u:.0f} u, warm {warm * 1e6:.0f} us = "
          f"{warm / u:.0f} u, new / warm {new / warm:.2f}")
    print("| part | new run | warm run | added |\n|---|---|---|---|")
    for spec, label in PARTS.items():
        n, w = (parts[k].get(spec, 0.0) / args.repeats for k in ("new", "warm"))
        print(f"| {label} | {n * 1e6:.1f} us | {w * 1e6:.1f} us | {(n - w) / u:.0f} u |")


if __name__ == "__main__":
    main()
