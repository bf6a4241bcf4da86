"""``radau5`` compiled on a second and a third structure, in one process: first, then warm.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/second_structure.py [--repeats 30] [--json]

Issue 27: a new structure (a new topology, a new combination of laws) should compile
nothing for ``radau5`` when its laws' templates are compiled. One process, whose
generated modules (``LUMPED_CACHE_DIR``) go to a new, empty temporary directory; numba's
disk cache of the shared loop (``NUMBA_CACHE_DIR``, else ``__pycache__`` beside the
sources) is left as it is, so run the script once before to fill it. CPU times
(:func:`time.process_time`) of:

1. the first run of the paper's scene (``forcing-F2``: a linear spring and a Bingham
   dashpot) with ``compiled=True``: the first structure, untimed in meaning (it loads
   the shared loop and compiles what the scene needs);
2. the first run of the 3-mass chain (:func:`lumped.bench.network_scenes.bingham_chain`,
   the same two laws on another topology, but Bingham dashpots whose ``gamma`` and
   ``tau`` are not 1: another law template) with ``compiled=True``: the second structure,
   with the numba functions compiled during it (numba's compile events, never times);
3. the same for the 2-mass chain: a third structure whose laws' templates the 3-mass
   chain compiled;
4. warm repeats of the three runs (the same scene objects): the minimum and the median.

Both runs on ``[0, 5]`` at ``rtol`` 1e-7 (``docs/benchmarks.md`` section 4c). Each time is
also given over the yardstick (:func:`lumped.bench.measure_unit`, the smaller of before
and after). The script uses the public API only, so it runs on older trees too (for a
before/after comparison).
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import sys
import tempfile
import time

os.environ["LUMPED_CACHE_DIR"] = tempfile.mkdtemp(prefix="lumped-second-structure-")

from numba.core import event  # noqa: E402

from lumped import simulate  # noqa: E402
from lumped.bench.network_scenes import bingham_chain  # noqa: E402
from lumped.bench.scenes import SCENES, generic_scene  # noqa: E402
from lumped.bench.timing import measure_unit  # noqa: E402

KW = {"method": "radau5", "t_end": 5.0, "rtol": 1e-7, "compiled": True}


def _run(scene) -> tuple[float, dict]:
    t0 = time.process_time()
    sol = simulate(scene, **KW)
    cpu = time.process_time() - t0
    return cpu, {"loop": str(sol.stats["loop"]), "steps": int(sol.stats["steps"]),
                 "ok": bool(sol.ok)}


def _first_run(scene) -> dict:
    """The run's CPU time and the functions numba compiled during it."""
    with event.install_recorder("numba:compile") as rec:
        cpu, info = _run(scene)
    names = sorted({f"{ev.data['dispatcher'].py_func.__module__}."
                    f"{ev.data['dispatcher'].py_func.__qualname__}"
                    for _, ev in rec.buffer if ev.is_start})
    return {"cpu_s": cpu, "compiled": names, **info}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=30, help="warm repeats per scene")
    parser.add_argument("--json", action="store_true", help="print a JSON record")
    args = parser.parse_args()
    unit = measure_unit()
    paper = generic_scene(next(s for s in SCENES if s.name == "forcing-F2"))
    chain = bingham_chain(3)
    short = bingham_chain(2)
    firsts = {"first structure (forcing-F2)": paper, "second structure (chain-3)": chain,
              "third structure (chain-2)": short}
    record = {name: _first_run(scene) for name, scene in firsts.items()}
    warm: dict[str, list[float]] = {"forcing-F2": [], "chain-3": [], "chain-2": []}
    for _ in range(args.repeats):  # interleaved, one of each per round
        for name, scene in zip(warm, firsts.values(), strict=True):
            warm[name].append(_run(scene)[0])
    unit = min(unit, measure_unit())
    record["warm"] = {name: {"min_s": min(ts), "median_s": statistics.median(ts)}
                      for name, ts in warm.items()}
    record["unit_s"] = unit
    if args.json:
        print(json.dumps(record))
        return
    print(f"python {sys.version.split()[0]}, yardstick Y = {unit * 1e3:.2f} ms, "
          f"load {os.getloadavg()[0]:.1f}")
    for name in firsts:
        r = record[name]
        mods = sorted({n.rsplit(".", 1)[0] for n in r["compiled"]})
        print(f"{name}: first run {r['cpu_s']:.3f} s CPU = {r['cpu_s'] / unit:.3g} Y, "
              f"{r['steps']} steps, loop {r['loop']!r}; numba compiled "
              f"{len(r['compiled'])} functions in {len(mods)} modules: {', '.join(mods)}")
    for name, w in record["warm"].items():
        print(f"warm {name}: min {w['min_s'] * 1e3:.2f} ms = {w['min_s'] / unit:.3g} Y, "
              f"median {w['median_s'] * 1e3:.2f} ms = {w['median_s'] / unit:.3g} Y "
              f"({args.repeats} repeats)")


if __name__ == "__main__":
    main()
