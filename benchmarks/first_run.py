"""What a user gets on a fresh machine: ``import lumped``, the first run, new numbers.

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/first_run.py [--quick] [--json] [--case CASE ...] [--second]

For each case (method and scene) a fresh Python process starts with **empty caches**:
``LUMPED_CACHE_DIR`` and ``XDG_CACHE_HOME`` (the generated modules of ``lumped``) and
``NUMBA_CACHE_DIR`` (numba's cache of the shared compiled loops, which otherwise lives in
``__pycache__`` beside the package's sources) each point to a new temporary directory.
Inside it, CPU times (:func:`time.process_time`, all threads of that process) of:

1. ``import lumped`` (``from lumped import simulate``);
2. the first run, ``simulate(scene, ...)`` (import excluded: issue 27's target is at most
   5 s of CPU for ``radau5`` and ``jit-bdf2`` on both scenes);
3. a run with new numbers: a new scene object with every spring's ``k`` times 1.03 (a
   user edits a number and runs again);
4. the warm repeat: that run once more on the same scene object.

Cases: ``radau5`` at ``rtol`` 1e-7 (default ``atol``, default options: what ``auto``
runs), ``radau5`` with ``compiled=True`` (the compiled loop from step 0, whatever the
length of the run), ``jit-bdf2`` at ``dt`` 1e-4, and ``radau5`` at ``rtol`` 1e-11
(``atol`` 1e-14, default options: a run of thousands of steps, past the 2000 after which
a run of a structure whose law templates are new compiles them;
:mod:`lumped.solvers.eventdriven.compile_when`); on the paper's scene (``forcing-F2``
of :mod:`lumped.scenarios`: m = 1, k = 100, gamma = 1, tau = 1, F2 = 10 sin(5 pi t) on
[0, 1]) and the 3-mass chain (:func:`lumped.bench.network_scenes.bingham_chain`), both
on ``[0, 5]``. ``--quick``: the paper's scene, ``radau5`` (default options) and
``jit-bdf2`` only. The child builds its scene from plain numbers (given here) with
``lumped.laws`` and ``lumped.scene`` only, so that no import of the benchmark package
moves a cost out of the first run. Each time is also given over the yardstick
(:func:`lumped.bench.measure_unit`, measured here before and after the cases; the smaller
is the unit). ``--json`` prints the records instead of the table; ``--case`` runs only
the cases named; ``--second`` adds, per case, the chain run in a process whose paper
scene ran first (a second structure: the shared code compiled, its own kernels not).
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import subprocess
import sys
import tempfile
import time

from lumped.bench.network_scenes import CHAIN_FORCING, CHAIN_LINKS
from lumped.bench.timing import measure_unit
from lumped.scenarios import get_scenario

T_END = 5.0
RTOL = 1e-7
DT = 1e-4
NEW_K = 1.03  # "changes one number (k by a few %)"

#: name -> (simulate method, keywords)
CASES = {
    "radau5": ("radau5", {"rtol": RTOL}),
    "radau5 compiled=True": ("radau5", {"rtol": RTOL, "compiled": True}),
    "jit-bdf2": ("jit-bdf2", {"dt": DT}),
    "radau5 rtol=1e-11": ("radau5", {"rtol": 1e-11, "atol": 1e-14}),
}
QUICK_CASES = ("radau5", "jit-bdf2")

_CHILD = r"""
import json, sys, time
t0 = time.process_time()
from lumped import simulate
import_s = time.process_time() - t0
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.scene.forcing import SineBurst

spec = json.loads(sys.argv[1])


def build(k_factor, spec=spec):
    nodes = [Mass(name, m=m, x0=x0) for name, m, x0 in spec["nodes"]]
    elements = []
    for name, law, a, b, params in spec["elements"]:
        params = {p: v * k_factor if p == "k" else v for p, v in params.items()}
        elements.append(Element(name, get_law(law).bind(**params), a, b))
    node, amplitude, omega, t_off = spec["force"]
    return Scene(nodes, elements, {node: SineBurst(amplitude, omega, t_off)})


if spec.get("before"):  # another structure first, untimed: the shared code compiled
    simulate(build(1.0, spec["before"]), method=spec["method"], t_end=spec["t_end"],
             throw=False, **spec["options"])


def run(scene):
    w0, c0 = time.perf_counter(), time.process_time()
    sol = simulate(scene, method=spec["method"], t_end=spec["t_end"], throw=False,
                   **spec["options"])
    cpu, wall = time.process_time() - c0, time.perf_counter() - w0
    st = sol.stats
    if "loop" in st:  # radau5
        path = str(st["loop"])
    elif "fallback" in st:  # jit-*: run whole on the reference solver
        path = f"fallback: {st['fallback']}"
    elif "fast_steps" in st:  # jit-*: the compiled fast path and its hand-over
        path = f"compiled, fast path {st['fast_steps']} of {st['steps']} steps"
    else:
        path = ""
    return {"cpu_s": cpu, "wall_s": wall, "ok": bool(sol.ok), "steps": int(st["steps"]),
            "path": path}


first = run(build(1.0))
fresh = build(spec["new_k"])
new = run(fresh)
warm = run(fresh)
print(json.dumps({"import_s": import_s, "first": first, "new": new, "warm": warm}))
"""


def paper_spec() -> dict:
    s = get_scenario("forcing-F2")
    f = s.forcing
    return {"nodes": [["mass", s.osc.m, s.x0]],
            "elements": [["spring", "linear_spring", "ground", "mass", {"k": s.osc.k}],
                         ["dashpot", "bingham", "ground", "mass",
                          {"gamma": s.osc.gamma, "tau": s.osc.tau}]],
            "force": ["mass", f.amplitude, f.omega, f.t_off]}


def chain_spec(n: int = 3) -> dict:
    nodes, elements = [], []
    for i, (m, k, gamma, tau) in enumerate(CHAIN_LINKS[:n], start=1):
        a, b = ("ground" if i == 1 else f"m{i - 1}"), f"m{i}"
        nodes.append([b, m, 0.0])
        elements += [[f"s{i}", "linear_spring", a, b, {"k": k}],
                     [f"d{i}", "bingham", a, b, {"gamma": gamma, "tau": tau}]]
    f = CHAIN_FORCING
    return {"nodes": nodes, "elements": elements,
            "force": [f"m{n}", f.amplitude, f.omega, f.t_off]}


SCENES = {"paper forcing-F2": paper_spec, "chain-3": chain_spec}


def run_case(scene: str, case: str, before: str | None = None) -> dict:
    """One fresh process with empty caches; its record (times in CPU seconds). With
    ``before``, that scene runs first in the process, untimed (a second structure on a
    machine whose shared code is compiled)."""
    method, options = CASES[case]
    spec = {**SCENES[scene](), "method": method, "options": options, "t_end": T_END,
            "new_k": NEW_K, "before": SCENES[before]() if before else None}
    with tempfile.TemporaryDirectory(prefix="lumped-first-run-") as tmp:
        env = dict(os.environ)
        for var, sub in (("LUMPED_CACHE_DIR", "lumped"), ("XDG_CACHE_HOME", "xdg"),
                         ("NUMBA_CACHE_DIR", "numba")):
            env[var] = os.path.join(tmp, sub)
        w0 = time.perf_counter()
        res = subprocess.run([sys.executable, "-c", _CHILD, json.dumps(spec)], env=env,
                             capture_output=True, text=True)
        wall = time.perf_counter() - w0
    if res.returncode != 0:
        raise RuntimeError(f"{scene}, {case}: the child failed:\n{res.stderr}")
    record = json.loads(res.stdout.strip().splitlines()[-1])
    return {"scene": scene if before is None else f"{scene} after {before}", "case": case,
            "method": method, "options": options, "process_wall_s": wall, **record}


def table(records: list[dict], unit: float) -> str:
    head = ("| scene | case | import | first run | new numbers | warm | new / warm | "
            "loop of the first run |")
    lines = [head, "|---" * 8 + "|"]
    for r in records:
        cells = [f"{r['import_s']:.2f} s"]
        for key in ("first", "new", "warm"):
            run = r[key]
            flag = "" if run["ok"] else " (stopped)"
            cells.append(f"{run['cpu_s']:.3g} s = {run['cpu_s'] / unit:.3g} Y{flag}")
        warm = r["warm"]["cpu_s"]
        ratio = r["new"]["cpu_s"] / warm if warm > 0 else float("nan")
        cells.append(f"{ratio:.3g}")
        cells.append(r["first"]["path"] or "-")
        lines.append(f"| {r['scene']} | {r['case']} | " + " | ".join(cells) + " |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true",
                        help="the paper's scene, radau5 and jit-bdf2 only")
    parser.add_argument("--json", action="store_true", help="print JSON records")
    parser.add_argument("--case", action="append", choices=tuple(CASES),
                        help="only this case (repeatable)")
    parser.add_argument("--second", action="store_true",
                        help="also chain-3 after the paper scene in one process (a second "
                             "structure on a machine whose shared code is compiled)")
    args = parser.parse_args()
    scenes = ("paper forcing-F2",) if args.quick else tuple(SCENES)
    cases = tuple(args.case) if args.case else (QUICK_CASES if args.quick else tuple(CASES))
    unit = measure_unit()
    records = [run_case(scene, case) for scene in scenes for case in cases]
    if args.second:
        records += [run_case("chain-3", case, before="paper forcing-F2") for case in cases]
    unit = min(unit, measure_unit())
    import numba

    info = {"date": time.strftime("%Y-%m-%d %H:%M"), "cpus": os.cpu_count(),
            "load": os.getloadavg()[0], "python": platform.python_version(),
            "numba": numba.__version__, "yardstick_s": unit}
    if args.json:
        print(json.dumps({"machine": info, "records": records}, indent=1))
        return
    print(f"date {info['date']}, {info['cpus']} cpus, load {info['load']:.1f}, python "
          f"{info['python']}, numba {info['numba']}; CPU times of the child process; "
          f"Y = the yardstick, {unit * 1e3:.1f} ms")
    print(table(records, unit))


if __name__ == "__main__":
    main()
