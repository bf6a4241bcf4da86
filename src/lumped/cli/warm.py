"""``lumped warm SCENE.toml [--method M ...]``: compile a scene file's structure ahead of time.

The compiled methods compile code for a scene the first time they meet it on a machine
and keep it in the disk cache (``$LUMPED_CACHE_DIR``, else ``$XDG_CACHE_HOME/lumped``,
else ``~/.cache/lumped``; numba's cache of the shared loops beside the package, or in
``$NUMBA_CACHE_DIR``). This command pays that cost now: it runs each ``--method``
(default ``radau5`` and ``jit-bdf2``; repeatable) on the scene for a few steps
(``[0, 5 dt]``, ``dt`` the file's ``[solver] dt`` or 1e-3) -- ``radau5`` with
``compiled=True`` and its event helpers (:mod:`lumped.solvers.modes.on_demand`),
``jit-bdf1``/``jit-bdf2`` with the fast path and then the faithful port -- and prints,
per method, what runs compiled (or that this scene runs on a Python loop, e.g. moving
supports) and the CPU seconds it took (a warm cache takes a fraction
of a second). Exit code 0 when every method ran, 1 when one failed (it says why); a bad
file exits with 2 and a message naming it.

The generated modules are keyed by the scene's structure (the laws' expressions, the
topology, the kinds of forcing), not its numbers: a file whose numbers change compiles
nothing new.
"""

from __future__ import annotations

import argparse
import sys
import time

__all__ = ["COMPILED_METHODS", "DEFAULT_METHODS", "add_arguments", "run"]

#: The methods that compile code per scene structure.
COMPILED_METHODS = ("radau5", "jit-bdf1", "jit-bdf2")
#: What ``lumped warm`` compiles without ``--method``.
DEFAULT_METHODS = ("radau5", "jit-bdf2")
#: Steps of the short run (``t_end = STEPS * dt``).
STEPS = 5


def add_arguments(parser: argparse.ArgumentParser) -> None:
    """Arguments of ``lumped warm``."""
    parser.add_argument("scene", help="scene file (TOML), see docs/scenes.md")
    parser.add_argument("--method", action="append", choices=COMPILED_METHODS, default=None,
                        help="a compiled method to warm (repeatable; default: "
                             + " and ".join(DEFAULT_METHODS) + ")")


def run(args: argparse.Namespace) -> int:
    """Warm the cache for each method; see the module notes for the exit codes."""
    from ..codegen.module_cache import cache_dir
    from ..io.scenefile import load_scene

    try:
        scene, settings = load_scene(args.scene)
    except OSError as err:  # a directory, no permission: name the file
        raise ValueError(f"{args.scene}: cannot read the scene file: "
                         f"{err.strerror or err}") from None
    dt = settings.get("dt") or 1e-3
    tol = {k: settings[k] for k in ("rtol", "atol") if settings.get(k) is not None}
    methods = tuple(dict.fromkeys(args.method or DEFAULT_METHODS))
    print(f"lumped warm {args.scene}: {len(scene.nodes)} nodes, {len(scene.elements)} "
          f"elements; compiled, or loaded from the cache {cache_dir()}:")
    failed, total = 0, 0.0
    for method in methods:
        t0 = time.process_time()
        try:
            what = _warm(scene, method, dt, tol)
        except (ValueError, TypeError, RuntimeError, FloatingPointError) as err:
            spent = time.process_time() - t0
            print(f"lumped warm: {method}: not warmed ({spent:.2f} s CPU): {err}",
                  file=sys.stderr)
            failed += 1
            continue
        spent = time.process_time() - t0
        total += spent
        print(f"  {method:9s} {spent:7.2f} s CPU  {what}")
    print(f"  {'total':9s} {total:7.2f} s CPU")
    return 1 if failed else 0


def _warm(scene, method: str, dt: float, tol: dict) -> str:
    """Run ``method`` on ``scene`` for :data:`STEPS` steps; what it compiled, in words."""
    from ..simulate import simulate

    t_end = STEPS * dt
    if method == "radau5":
        from ..solvers.eventdriven.fast import compiled_loop
        from ..solvers.eventdriven.setup import scene_plan
        from ..solvers.modes.on_demand import compile_all

        simulate(scene, method="radau5", t_end=t_end, compiled=True, **tol)
        # the loop for the runs that move, whether or not this one did (a scene held at
        # rest runs no loop): every kernel it calls, though the short run may have stepped
        # or probed not at all
        fast, loop = compiled_loop(scene, scene_plan(scene), True)
        if fast is None:  # e.g. locked elements in parallel
            return f"the Python loop runs this scene: {loop or 'no loop named'}"
        fast.compile_kernels()
        compile_all()  # (a first run compiles them only once a process needs them often)
        return "the event-driven Radau IIA loop and its event helpers"
    sol = simulate(scene, method=method, dt=dt, t_end=t_end, fast=True)
    if "fallback" in sol.stats:  # e.g. moving supports: the Python reference runs it
        return f"runs on the Python solver: {sol.stats['fallback']}"
    parts = ["the fast loop" if "fast_steps" in sol.stats else None]
    simulate(scene, method=method, dt=dt, t_end=t_end, fast=False)
    parts.append("the faithful port")
    return " and ".join(p for p in parts if p)
