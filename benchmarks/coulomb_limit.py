"""The Coulomb limit: ``radau5`` on the paper's two scenes as Bingham's ``gamma`` grows.

Issue 29's table. The paper's oscillator (``m = 1``, ``k = 100``, ``tau = 1``) released
from ``x0 = 0.5`` and forced by ``F2`` (``10 sin(5 pi t)`` on ``[0, 1]``), with the
``bingham`` law at ``gamma`` = 1e4, 1e6, 1e9, 1e12 and with the ``coulomb`` law (its
``gamma -> infinity`` limit, Remark 2.1), run by ``simulate(scene, method="radau5",
rtol=r, atol=1e-3 r, t_end=5)`` through the public API. Each cell: ``max |x - x_exact|``
on the 1e-3 grid through the dense output ``sol.sol(t)`` against :mod:`lumped.reference`
(the exact event-driven solution; ``coulomb=True`` for the Coulomb law), and the number
of accepted steps. A run that ends without ``Status.SUCCESS`` reads ``stops (<status>)``;
one that needed backward-Euler bridges says how many; one that takes longer than
``--timeout`` seconds (run in a child process) reads ``> <timeout> s``.

Run: ``python benchmarks/coulomb_limit.py [--timeout 120] [--out FILE.md]``.
"""

from __future__ import annotations

import argparse
import math
import multiprocessing as mp
import platform
import subprocess
import time
from datetime import UTC, datetime
from pathlib import Path

import numpy as np

from lumped import simulate
from lumped.laws import get_law
from lumped.reference import reference_for_grid
from lumped.scene import Element, Mass, Scene, paper_F2
from lumped.solvers.closed.closed_form import BinghamOscillator

GAMMAS = (1e4, 1e6, 1e9, 1e12)
RTOLS = (1e-4, 1e-7, 1e-10)
SCENES = (("release-0.5", 0.5, None), ("forcing-F2", 0.0, paper_F2))
M, K, TAU, T_END, GRID_DT = 1.0, 100.0, 1.0, 5.0, 1e-3


def scene_for(law: str, gamma: float, x0: float, forcing) -> Scene:
    """The paper's oscillator with a ``bingham`` (``gamma``) or ``coulomb`` dashpot."""
    bound = (get_law("coulomb").bind(tau=TAU, r=1.0) if law == "coulomb"
             else get_law("bingham").bind(gamma=gamma, tau=TAU))
    return Scene([Mass("mass", m=M, x0=x0)],
                 [Element("spring", get_law("linear_spring").bind(k=K), "ground", "mass"),
                  Element("dashpot", bound, "ground", "mass")],
                 {} if forcing is None else {"mass": forcing})


def one_run(law: str, gamma: float, x0: float, forcing, rtol: float) -> dict:
    """Error, steps, bridges, status and CPU time of one ``radau5`` run."""
    grid = np.arange(int(round(T_END / GRID_DT)) + 1) * GRID_DT
    osc = BinghamOscillator(M, K, 1.0 if law == "coulomb" else gamma, TAU)
    x_ref = reference_for_grid(osc, x0=x0, forcing=forcing, dt=GRID_DT, t_end=T_END,
                               coulomb=law == "coulomb").x
    scene = scene_for(law, gamma, x0, forcing)
    t0 = time.process_time()
    sol = simulate(scene, method="radau5", rtol=rtol, atol=1e-3 * rtol, t_end=T_END)
    cpu = time.process_time() - t0
    ok = sol.status.name == "SUCCESS"
    err = float(np.max(np.abs(sol.sol(grid)[:, sol.columns.index("x_mass")] - x_ref))) \
        if ok else math.nan
    return {"ok": ok, "status": sol.status.name, "err": err, "steps": sol.stats["steps"],
            "bridges": sol.stats.get("bridges", 0), "cpu": cpu}


def _child(conn, args) -> None:
    try:
        conn.send(one_run(*args))
    except Exception as err:  # noqa: BLE001 - reported in the table
        conn.send({"ok": False, "status": f"{type(err).__name__}", "err": math.nan,
                   "steps": 0, "bridges": 0, "cpu": math.nan})


def timed_run(args: tuple, timeout: float) -> dict | None:
    """:func:`one_run` in a child process; ``None`` when it outlasts ``timeout``."""
    parent, child = mp.Pipe(duplex=False)
    proc = mp.get_context("fork").Process(target=_child, args=(child, args))
    proc.start()
    got = parent.recv() if parent.poll(timeout) else None
    if got is None:
        proc.kill()
    proc.join()
    return got


def cell(r: dict | None, timeout: float) -> str:
    if r is None:
        return f"> {timeout:g} s"
    if not r["ok"]:
        return f"**stops** ({r['status']})"
    out = f"{r['err']:.1e} ({r['steps']}"
    if r["bridges"]:
        out += f", {r['bridges']} bridges"
    return out + ")"


def commit() -> str:
    try:
        return subprocess.run(["git", "rev-parse", "--short", "HEAD"], capture_output=True,
                              text=True, check=True, cwd=Path(__file__).parent).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timeout", type=float, default=120.0,
                        help="seconds a run may take before it is reported as such")
    parser.add_argument("--out", default=None, help="also write the table to this file")
    args = parser.parse_args()
    stamp = datetime.now(UTC).strftime("%Y-%m-%d %H:%M UTC")
    lines = [f"{stamp}, {platform.node()} ({platform.machine()}, {platform.processor() or '-'}"
             f", Python {platform.python_version()}), commit {commit()}", "",
             "max |x - x_exact| on the 1e-3 grid (accepted steps); radau5, atol = 1e-3 rtol",
             "", "| law | " + " | ".join(f"{name}: rtol {r:.0e}" for name, _, _ in SCENES
                                          for r in RTOLS) + " |",
             "|---|" + "---|" * (len(SCENES) * len(RTOLS))]
    rows = [("bingham", g) for g in GAMMAS] + [("coulomb", math.inf)]
    for law, gamma in rows:
        cells = []
        for _, x0, forcing in SCENES:
            for rtol in RTOLS:
                cells.append(cell(timed_run((law, gamma, x0, forcing, rtol), args.timeout),
                                  args.timeout))
        label = "coulomb" if law == "coulomb" else f"bingham, gamma {gamma:.0e}"
        lines.append(f"| {label} | " + " | ".join(cells) + " |")
        print(lines[-1], flush=True)
    text = "\n".join(lines)
    print()
    print(text)
    if args.out:
        Path(args.out).write_text(text + "\n", encoding="utf-8")


if __name__ == "__main__":
    main()
