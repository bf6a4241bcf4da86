"""radau5 beyond one mass: 2- and 3-mass Bingham chains and the Maxwell example (issue 8).

For each scene of :data:`lumped.bench.network_scenes.NETWORK_SCENES`:

1. the reference, ``radau5`` at ``rtol`` 1e-12 (``atol`` 1e-14), checked against
   ``radau5`` at 1e-11 and, for Maxwell (a linear system), against its matrix exponential;
2. ``radau5`` at ``rtol`` 1e-4 .. 1e-12 (``atol = 1e-3 rtol``): ``max |x - x_ref|`` over
   every node on the 1e-3 grid through the dense output, steps, events, CPU time; beside
   it the fastest scipy LSODA run on the tanh-smoothed network
   (:mod:`lumped.bench.network_peers`, ``eps`` x ``rtol`` ladder) that reaches the same
   error, and the ratio ours / LSODA's;
3. the fixed-step BDF2 ladder (``jit-bdf2``, the same numbers as ``bdf2``) on
   ``[0, bdf_t_end]``, its observed orders, the order-2 and order-1 Richardson
   extrapolants, and the limit the data support (:func:`lumped.bench.network_study.
   bdf2_limit`), against which ``radau5`` at ``rtol`` 1e-10 is compared (target 1e-7).

Times are CPU seconds over the yardstick measured in the same process
(:func:`lumped.bench.timing.measure_unit`), best of up to three calls; both sides are
timed up to ``x`` of every node on the grid (radau5 through its dense output, LSODA through
``solve_ivp``'s). Beside each warm ``radau5`` time, the user's column: one run with new
numbers (every spring's ``k`` never run before in the process, on a new scene object;
:func:`lumped.bench.new_numbers.scene_with_new_numbers`), timed once, its ratio to the
warm time, and its ratio to the same LSODA run.

Run: ``PYTHONPATH=src python benchmarks/multi_mass.py [--out FILE.md]`` (about 1 min of
CPU, 2.5 min wall on the shared 2-core machine; plus about 20 s of CPU once per chain to
compile ``jit-bdf2``'s kernels when their disk cache is cold). ``--option KEY=VALUE``
(repeatable) passes a further keyword to every ``radau5`` run, e.g. ``compiled=True``.
"""

from __future__ import annotations

import argparse
import ast

import numpy as np

from lumped import simulate
from lumped.bench.network_peers import solve_tanh_network
from lumped.bench.network_scenes import NETWORK_SCENES, NetworkScene, maxwell_exact
from lumped.bench.network_study import bdf2_ladder, bdf2_limit, grid, node_x, richardson
from lumped.bench.new_numbers import scene_with_new_numbers
from lumped.bench.report import print_and_save
from lumped.bench.timing import measure_unit, time_call

GRID_DT = 1e-3
RTOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
REF_RTOL, REF_ATOL = 1e-12, 1e-14
PEER_EPS = (1e-5, 1e-7, 1e-9, 1e-11)
PEER_RTOLS = (1e-4, 1e-6, 1e-8, 1e-10, 1e-12)
CHECK_RTOL = 1e-10
TARGET = 1e-7


#: Further ``simulate`` keywords for every radau5 run (``--option KEY=VALUE``).
RADAU_OPTIONS: dict = {}


def radau(scene, t_end, rtol, atol):
    return simulate(scene, method="radau5", t_end=t_end, rtol=rtol, atol=atol, throw=False,
                    **RADAU_OPTIONS)


def _option(text: str) -> tuple[str, object]:
    key, sep, value = text.partition("=")
    if not sep or not key.isidentifier():
        raise argparse.ArgumentTypeError(f"expected KEY=VALUE, got {text!r}")
    try:
        return key, ast.literal_eval(value)
    except (ValueError, SyntaxError):
        return key, value


def reference(ns: NetworkScene, g: np.ndarray, lines: list[str]) -> np.ndarray:
    scene = ns.build()
    ref = radau(scene, ns.t_end, REF_RTOL, REF_ATOL)
    if not ref.ok:
        raise RuntimeError(f"{ns.name}: the reference run stopped: {ref.message}")
    x_ref = node_x(ref, scene, g)
    loose = radau(scene, ns.t_end, 1e-11, 1e-13)
    check = f"| {ns.name} | {ref.stats['steps']} | {len(ref.events)} | "
    check += f"{np.max(np.abs(node_x(loose, scene, g) - x_ref)):.2e} | "
    if ns.name == "maxwell":
        check += f"{np.max(np.abs(maxwell_exact(g) - x_ref)):.2e} |"
    else:
        check += "- |"
    lines.append(check)
    return x_ref


def peers(ns: NetworkScene, g: np.ndarray, x_ref: np.ndarray, unit: float) -> list:
    scene = ns.build()
    out = []
    for eps in PEER_EPS:
        for rtol in PEER_RTOLS:
            def run(eps=eps, rtol=rtol):
                return solve_tanh_network(scene, ns.t_end, g, eps=eps, rtol=rtol,
                                          atol=1e-3 * rtol, max_nfev=100_000)[0]
            try:
                x, cpu, _ = time_call(run, min_time=0.02, max_repeats=3)
            except RuntimeError:  # a failed or over-budget peer run is skipped, as in bench
                continue
            out.append((float(np.max(np.abs(x - x_ref))), cpu / unit, eps, rtol))
    return out


def ladder_rows(ns: NetworkScene, g, x_ref, unit, lines: list[str]) -> None:
    scene = ns.build()
    cands = peers(ns, g, x_ref, unit)
    for rtol in RTOLS:
        def run(rtol=rtol):  # like the peer's run: the solution, then x on the grid
            sol = radau(scene, ns.t_end, rtol, 1e-3 * rtol)
            return sol, (node_x(sol, scene, g) if sol.ok else None)

        (sol, x), cpu, _ = time_call(run, min_time=0.02, max_repeats=3)
        if not sol.ok:
            lines.append(f"| {ns.name} | {rtol:.0e} | stopped: {sol.status.value} at "
                         f"t = {float(sol.t[-1]):.6g} | {sol.stats['steps']} | "
                         f"{len(sol.events)} | - | - | - | - | - |")
            continue
        new = new_numbers_time(scene, ns.t_end, rtol, g)
        err = float(np.max(np.abs(x - x_ref)))
        ok = [p for p in cands if p[0] <= err]
        best = min(ok, default=None, key=lambda p: p[1])
        peer = "none reaches it" if best is None else (
            f"{best[1]:.2f} (eps {best[2]:.0e}, rtol {best[3]:.0e}, err {best[0]:.1e})")
        ratio = "-" if best is None else f"{cpu / unit / best[1]:.2f}"
        ratio_new = "-" if best is None else f"{new / unit / best[1]:.2f}"
        lines.append(f"| {ns.name} | {rtol:.0e} | {err:.2e} | {sol.stats['steps']} | "
                     f"{len(sol.events)} | {cpu / unit:.2f} | {new / unit:.2f} "
                     f"({new / cpu:.3g}x) | {peer} | {ratio} | {ratio_new} |")


def new_numbers_time(scene, t_end: float, rtol: float, g: np.ndarray) -> float:
    """CPU seconds of one radau5 run with new numbers (every spring's ``k`` never run
    before in the process, a new scene object), timed once, x on the grid included."""
    fresh = scene_with_new_numbers(scene)

    def run():
        sol = radau(fresh, t_end, rtol, 1e-3 * rtol)
        return node_x(sol, fresh, g) if sol.ok else None

    return time_call(run, min_time=0.0, max_repeats=1)[1]


def bdf_rows(ns: NetworkScene, x_ref_full, g_full, bdf_lines, summary) -> None:
    scene = ns.build()
    g = grid(ns.bdf_t_end, GRID_DT)
    x_ref = x_ref_full[: len(g)]
    assert np.allclose(g_full[: len(g)], g)
    dts = [GRID_DT / 2 ** j for j in range(2, ns.bdf_finest + 1)]
    lad = bdf2_ladder(scene, ns.bdf_t_end, dts, GRID_DT)
    orders = [float("nan"), float("nan"), *lad.orders()]
    for i, dt in enumerate(lad.dts):
        err = np.max(np.abs(lad.x[i] - x_ref))
        r2 = r1 = "-"
        if i >= 1:
            r2 = f"{np.max(np.abs(richardson(lad.x[i - 1], lad.x[i], 2.0) - x_ref)):.2e}"
            r1 = f"{np.max(np.abs(richardson(lad.x[i - 1], lad.x[i], 1.0) - x_ref)):.2e}"
        p = "-" if not np.isfinite(orders[i]) else f"{orders[i]:.2f}"
        bdf_lines.append(f"| {ns.name} | {dt:.3e} | {lad.steps[i]} | {err:.2e} | {p} | "
                         f"{r2} | {r1} |")
    lim = bdf2_limit(lad)
    ours = radau(scene, ns.bdf_t_end, CHECK_RTOL, 1e-3 * CHECK_RTOL)
    diff = float(np.max(np.abs(node_x(ours, scene, g) - lim.x)))
    ref_diff = float(np.max(np.abs(x_ref - lim.x)))
    verdict = "yes" if diff <= TARGET else "no"
    summary.append(f"| {ns.name} | [0, {ns.bdf_t_end:g}] | {lim.how} (dt {lad.dts[-1]:.2e}) | "
                   f"{lim.error_estimate:.1e} | {diff:.2e} | {ref_diff:.2e} | {verdict} |")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default=None, help="also write the tables to this file")
    parser.add_argument("--option", type=_option, action="append", default=[],
                        metavar="KEY=VALUE",
                        help="a further simulate keyword for radau5 (e.g. compiled=True)")
    args = parser.parse_args()
    RADAU_OPTIONS.update(args.option)
    unit = measure_unit()
    ref_lines = ["| scene | ref steps | ref events | vs radau5 rtol 1e-11 | vs exact |",
                 "|---|---|---|---|---|"]
    lad_lines = ["| scene | rtol | radau5 max err | steps | events | radau5 time (units) "
                 "| with new numbers (units; / warm) "
                 "| best LSODA-tanh time at that error (units) | ratio | ratio, new numbers |",
                 "|---|---|---|---|---|---|---|---|---|---|"]
    bdf_lines = ["| scene | dt | steps | BDF2 err | observed order | Richardson p=2 err "
                 "| Richardson p=1 err |", "|---|---|---|---|---|---|---|"]
    summary = [f"| scene | span | BDF2 limit used | its error estimate | radau5 rtol "
               f"{CHECK_RTOL:.0e} vs limit | reference vs limit | within {TARGET:.0e} |",
               "|---|---|---|---|---|---|---|"]
    for ns in NETWORK_SCENES:
        g = grid(ns.t_end, GRID_DT)
        x_ref = reference(ns, g, ref_lines)
        ladder_rows(ns, g, x_ref, unit, lad_lines)
        bdf_rows(ns, x_ref, g, bdf_lines, summary)
        print(f"{ns.name} done", flush=True)
    text = "\n".join([f"yardstick unit: {unit * 1e3:.2f} ms", "", *ref_lines, "",
                      *lad_lines, "", *bdf_lines, "", *summary])
    print_and_save(text, args.out)


if __name__ == "__main__":
    main()
