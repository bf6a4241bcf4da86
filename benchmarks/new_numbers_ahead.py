"""What removing each part of a run's per-number work would give (issue 27's 1.3x).

Usage, from the repository root::

    python benchmarks/new_numbers_ahead.py [--repeats 300] [--scene viscous-soft]
        [--case "radau5 compiled=True"]

:mod:`new_numbers_parts` times the parts of a run with new numbers with wrappers, which
cost time themselves and count nested parts twice. Here nothing is wrapped: for each
part a scene with new numbers (:func:`lumped.bench.new_numbers.scene_with_new_numbers`)
has that part done *ahead*, untimed (the laws' kernels, branches and templates; the
plan; ``dispatch_scene`` for ``radau5``, ``port_parts`` for the BDFs; the consistent initial state,
with the run's own arguments; all of them), and then its run is timed (CPU,
:func:`time.process_time`). The difference to the run with nothing done ahead is what
the part costs inside a run, caches and all: the most that taking that part's
per-number work away can give. The kinds of run are interleaved, one of each per round,
and the median of each is printed over the median warm repeat.
"""

from __future__ import annotations

import os
import statistics
import time

from new_numbers import CASES, SCENES, T_END, _cpu
from new_numbers_parts import arguments

import lumped.solvers.eventdriven.run as run_module
from lumped.bench.new_numbers import scene_with_new_numbers
from lumped.codegen.branches import law_branches
from lumped.codegen.dispatch import dispatch_scene
from lumped.codegen.templates import law_template
from lumped.solvers.bdf import fixed_step_jit
from lumped.solvers.bdf.fixed_step_jit import port_parts
from lumped.solvers.eventdriven.setup import scene_plan


def _driver(method: str):
    """The module whose ``consistent_initial_state`` a run of ``method`` calls."""
    return run_module if method == "radau5" else fixed_step_jit


def _initial_state_arguments(base, method: str, options: dict) -> dict:
    """The keywords a run passes to the consistent initial state (its ``time_scale`` and
    Newton options), read off a run of ``base``."""
    seen: dict = {}
    module = _driver(method)
    solve = module.consistent_initial_state

    def recording(scene, **kwargs):
        seen.update(kwargs)
        return solve(scene, **kwargs)

    module.consistent_initial_state = recording
    try:
        _cpu(scene_with_new_numbers(base), method, options)
    finally:
        module.consistent_initial_state = solve
    if not seen:
        raise SystemExit("the run asked for no consistent initial state (a run at rest?)")
    return seen


def _laws(scene) -> None:
    for el in scene.elements:
        assert callable(el.law.kernel)
        law_template(el.law)
        lb = law_branches(el.law)
        for i in range(lb.count):
            lb.stage_kernel_for(i), lb.stage_guards_for(i)


def main() -> None:
    args = arguments(__doc__.splitlines()[0], 300)
    method, options = CASES[args.case]
    base = SCENES[args.scene]()
    for _ in range(3):  # warm: the structure's module, the code paths of new numbers
        scene = scene_with_new_numbers(base)
        _cpu(scene, method, options), _cpu(scene, method, options)
    state = _initial_state_arguments(base, method, options)
    initial = _driver(method).consistent_initial_state

    # (radau5's compiled loop takes the structure-generic kernels' scene, the BDFs' port
    # the structure-generic step system's)
    parts = dispatch_scene if method == "radau5" else port_parts

    def everything(scene) -> None:
        _laws(scene), scene_plan(scene), parts(scene), initial(scene, **state)

    ahead = {"nothing": lambda scene: None, "the laws' functions": _laws,
             "the plan": scene_plan, parts.__name__: parts,
             "the initial state": lambda scene: initial(scene, **state),
             "all four": everything}
    runs: dict[str, list[float]] = {name: [] for name in ahead}
    warm: list[float] = []
    for _ in range(args.repeats):
        for name, part in ahead.items():
            scene = scene_with_new_numbers(base)
            part(scene)
            runs[name].append(_cpu(scene, method, options))
        warm.append(_cpu(scene, method, options))
    w = statistics.median(warm)
    none = statistics.median(runs["nothing"])
    print(f"{time.strftime('%Y-%m-%d %H:%M')}, load {os.getloadavg()[0]:.1f}; {args.scene}, "
          f"{args.case}, t_end {T_END}; {args.repeats} rounds; warm repeat (median) "
          f"{w * 1e6:.0f} us")
    print("| done ahead | new run (median) | saved | new / warm |\n|---|---|---|---|")
    for name, times in runs.items():
        t = statistics.median(times)
        print(f"| {name} | {t * 1e6:.0f} us | {(none - t) * 1e6:.0f} us | {t / w:.2f} |")


if __name__ == "__main__":
    main()
