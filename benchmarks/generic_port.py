"""``jit-bdf1``/``jit-bdf2``'s faithful port on the structure-generic step system against a
structure's own module: warm step speed, and a new structure's first short run.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/generic_port.py [--repeats 40] [--json]

Issue 27: the port (:mod:`lumped.solvers.bdf.core_jit`, compiled once per machine) calls
the scene's step system through two callbacks. They were the scene's generated module's
``evaluate`` and ``element_law`` (:mod:`lumped.codegen.jit`, compiled once per
structure); they are now :mod:`lumped.codegen.step_dispatch`'s, compiled once for every
scene, which reach each element's law through its template's law module (one direct
call through an address per law evaluation, where the scene module's is inlined). One
process, its generated modules (``LUMPED_CACHE_DIR``) in a new, empty temporary
directory; numba's disk cache of the shared code left as it is (run the script once
before to fill it). CPU times (:func:`time.process_time`), each also over the yardstick
(:func:`lumped.bench.measure_unit`, the smaller of before and after):

1. warm: the port alone (``fast=False``: :func:`~lumped.solvers.bdf.core_jit.run_bdf_core`
   called directly on one run's arguments) on ``forcing-F2`` and the 3-mass chain, BDF1
   and BDF2 at ``dt`` 1e-4 on ``[0, 5]`` (50 000 steps), with the generic and with the
   scene module's callbacks, interleaved (each first in every other round); the minimum
   and median of each, the ratio of the medians (generic over per structure), and
   whether the two gave the same arrays bit for bit;
2. a new structure's first short run (``jit-bdf2``, ``dt`` 1e-2 on ``[0, 5]``: 500 steps,
   the default ``fast=None``, which takes the port for a short run of a structure whose
   fast loop was never built) after forcing-F2's run warmed the port: the 3-mass chain
   (its Bingham dashpots a law template the paper's is not) and a 2-mass chain of the
   paper's laws (no new template), each with the generic callbacks (now) and with the
   scene module's (before), and the functions numba compiled in each. The laws' sympy
   derivation is done first, untimed, so the two rows differ by numba's work only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time

os.environ["LUMPED_CACHE_DIR"] = tempfile.mkdtemp(prefix="lumped-generic-port-")

import numpy as np  # noqa: E402
from numba.core import event  # noqa: E402

from lumped import Element, Mass, Scene, get_law, simulate  # noqa: E402
from lumped.bench.network_scenes import bingham_chain  # noqa: E402
from lumped.bench.scenes import SCENES, generic_scene  # noqa: E402
from lumped.bench.timing import measure_unit  # noqa: E402
from lumped.codegen.jit import jit_scene, scene_templates  # noqa: E402
from lumped.scene import SineBurst  # noqa: E402
from lumped.solvers.bdf import fixed_step_jit  # noqa: E402
from lumped.solvers.bdf.core_jit import compiled_run_bdf_core, loop_workspace  # noqa: E402
from lumped.solvers.bdf.fixed_step_jit import Port, loop_arguments  # noqa: E402
from lumped.solvers.newton.options import NewtonOptions  # noqa: E402

DT, N_STEPS = 1e-4, 50_000


def _module_port(scene):
    """The port's parts on the scene's generated module (as before)."""
    js = jit_scene(scene)
    return js, Port(js.consts, lambda: (js.module.evaluate, js.module.element_law))


def _calls(scene, formula: str) -> dict:
    """``{kind: (callbacks, args)}`` of one run of the port, generic and per structure."""
    js, port, args, _ = loop_arguments(scene, formula, DT, N_STEPS, NewtonOptions())
    _, mport = _module_port(scene)
    N, E = len(scene.nodes), len(scene.elements)
    margs = args[:-8] + loop_workspace(N, E, mport.consts.shape[0]) + (mport.consts,)
    return {"per structure": (mport.callbacks(), margs), "generic": (port.callbacks(), args)}


def warm(scene, formula: str, repeats: int) -> dict:
    loop = compiled_run_bdf_core()
    calls = _calls(scene, formula)
    outs = {}
    for kind, (fns, args) in calls.items():  # (each compiled or loaded, untimed)
        rows = loop(*fns, *args, 0, -1)
        outs[kind] = [a[:rows].copy() for a in args[19:22]]
    same = all(np.array_equal(a, b) for a, b in zip(*outs.values(), strict=True))
    times: dict[str, list[float]] = {kind: [] for kind in calls}
    order = list(calls.items())
    for k in range(repeats):
        for kind, (fns, args) in (order if k % 2 == 0 else order[::-1]):
            t0 = time.process_time()
            loop(*fns, *args, 0, -1)
            times[kind].append(time.process_time() - t0)
    out = {kind: {"min_s": min(ts), "median_s": statistics.median(ts)}
           for kind, ts in times.items()}
    out["ratio"] = out["generic"]["median_s"] / out["per structure"]["median_s"]
    out["same"] = same
    return out


def _paper_chain() -> Scene:
    """Two masses on the paper's laws (``linear_spring``, ``bingham(1, 1)``)."""
    damp = get_law("bingham").bind(gamma=1.0, tau=1.0)
    lin = get_law("linear_spring")
    return Scene([Mass("a", m=1.0), Mass("b", m=1.5)],
                 [Element("k1", lin.bind(k=80.0), "ground", "a"),
                  Element("d1", damp, "ground", "a"),
                  Element("k2", lin.bind(k=50.0), "a", "b"),
                  Element("d2", damp, "a", "b")], {"b": SineBurst(9.0, 6.0, 0.8)})


def first_run(scene, generic: bool) -> dict:
    """A first short ``jit-bdf2`` run of ``scene``: CPU time, what numba compiled."""
    real = fixed_step_jit.port_parts
    if not generic:
        fixed_step_jit.port_parts = _module_port
    try:
        with event.install_recorder("numba:compile") as rec:
            t0 = time.process_time()
            sol = simulate(scene, method="jit-bdf2", dt=1e-2, t_end=5.0)
            cpu = time.process_time() - t0
    finally:
        fixed_step_jit.port_parts = real
    names = sorted({f"{ev.data['dispatcher'].py_func.__module__}."
                    f"{ev.data['dispatcher'].py_func.__qualname__}"
                    for _, ev in rec.buffer if ev.is_start})
    return {"cpu_s": cpu, "compiled": names, "port": "fast_steps" not in sol.stats,
            "ok": bool(sol.ok)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=40, help="warm runs per variant")
    parser.add_argument("--json", action="store_true", help="print a JSON record")
    args = parser.parse_args()
    unit = measure_unit()
    paper = generic_scene(next(s for s in SCENES if s.name == "forcing-F2"))
    simulate(paper, method="jit-bdf2", dt=1e-2, t_end=0.5, fast=False)  # the port, warm
    record: dict = {"first": {}, "warm": {}}
    for name, make in (("chain-3 (a new law template)", lambda: bingham_chain(3)),
                       ("chain-2 of the paper's laws", _paper_chain)):
        for generic in (True, False):
            scene = make()  # (a new scene object, its laws derived untimed)
            scene_templates(scene)
            record["first"][f"{name}, {'generic' if generic else 'per structure'}"] = (
                first_run(scene, generic))
    for label, scene in (("forcing-F2", paper), ("chain-3", bingham_chain(3))):
        for formula in ("bdf1", "bdf2"):
            record["warm"][f"{label} {formula}"] = warm(scene, formula, args.repeats)
    unit = min(unit, measure_unit())
    record["unit_s"] = unit
    record["load"] = os.getloadavg()[0]
    if args.json:
        print(json.dumps(record))
        return
    print(f"python {sys.version.split()[0]}, yardstick Y = {unit * 1e3:.2f} ms, "
          f"load {record['load']:.1f}")
    for name, r in record["first"].items():
        mods = sorted({n.rsplit(".", 1)[0] for n in r["compiled"]})
        print(f"first short run, {name}: {r['cpu_s']:.3f} s CPU = {r['cpu_s'] / unit:.3g} Y"
              f" (port: {r['port']}); numba compiled {len(r['compiled'])} functions in "
              f"{len(mods)} modules: {', '.join(mods) or '-'}")
    for name, w in record["warm"].items():
        g, p = w["generic"], w["per structure"]
        print(f"warm port {name}: generic median {g['median_s'] * 1e3:.2f} ms "
              f"(min {g['min_s'] * 1e3:.2f}), per structure median "
              f"{p['median_s'] * 1e3:.2f} ms (min {p['min_s'] * 1e3:.2f}); "
              f"ratio {w['ratio']:.3f}; "
              f"same numbers: {w['same']}; {N_STEPS} steps, {args.repeats} repeats")


if __name__ == "__main__":
    main()
