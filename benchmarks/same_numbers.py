"""Same numbers: fingerprint what the solvers compute, to check a refactor bit for bit.

Runs, through the public API only (so it survives a move of the solver modules):

* the 10 bench scenes (``lumped.bench.scenes.SCENES`` as generic scenes) with ``radau5``
  at three tolerances, in the Python loop (``compiled=False``) and the compiled loop
  (``compiled=True``);
* 150 random networks (numpy ``default_rng(seed)``, seeds 0..149: 1-4 nodes, every
  built-in passive law) with ``bdf1``, ``bdf2`` and ``radau5`` (Python loop) at three
  levels;
* the impact and lock scenes with every generic method at two steps.

Every run's samples (``t`` and the state columns), status and message are saved to an
``.npz``; ``--compare OLD.npz`` reports every run whose arrays are not identical to the
last bit (these are same-machine checks: the last bits may differ between machines).

Usage::

    python benchmarks/same_numbers.py --out before.npz
    python benchmarks/same_numbers.py --out after.npz --compare before.npz
"""

from __future__ import annotations

import argparse
import math
import time

import numpy as np

from lumped import simulate
from lumped.bench.impact_scenes import impact_scene, lock_scene
from lumped.bench.scenes import SCENES, generic_scene
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

TOLERANCES = (1e-4, 1e-7, 1e-10)
NETWORKS = 150
LEVELS = (0.05, 0.025, 0.0125)
SPRINGS = ("linear_spring", "string_spring", "implicit_spring")
DASHPOTS = ("newtonian", "bingham", "coulomb", "herschel_bulkley")


def _decade(rng, lo: float, hi: float) -> float:
    return 10.0 ** rng.uniform(math.log10(lo), math.log10(hi))


def _law(rng, name: str, q0: float):
    law = get_law(name)
    if name == "linear_spring":
        return law.bind(k=_decade(rng, 1.0, 1e3))
    if name == "string_spring":
        return law.bind(k=_decade(rng, 1.0, 1e3), L=max(q0, 0.0) + rng.uniform(0.05, 1.0))
    if name == "implicit_spring":
        return law.bind(k=_decade(rng, 1.0, 1e3), L0=_decade(rng, 1e-3, 1.0),
                        F0=_decade(rng, 1.0, 100.0))
    if name == "newtonian":
        return law.bind(c=_decade(rng, 0.1, 10.0))
    if name == "bingham":
        return law.bind(gamma=_decade(rng, 0.1, 1e3), tau=_decade(rng, 0.01, 1.0))
    if name == "coulomb":
        return law.bind(tau=_decade(rng, 0.01, 1.0), r=_decade(rng, 1.0, 100.0))
    return law.bind(gamma=_decade(rng, 0.1, 10.0), tau=_decade(rng, 0.01, 1.0),
                    n=float(rng.choice([0.5, 1.5, 2.0])))


def random_network(seed: int) -> Scene:
    """A random passive network; the first node is a mass, every node is tied to ground
    or to an earlier node by a spring, and a dashpot joins half the spring's ends."""
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 5))
    nodes, x0 = [], rng.uniform(-0.5, 0.5, n)
    for i in range(n):
        if i == 0 or rng.random() < 0.6:
            nodes.append(Mass(f"m{i}", m=_decade(rng, 0.1, 10.0), x0=float(x0[i]),
                              v0=float(rng.uniform(-2.0, 2.0))))
        else:
            nodes.append(Junction(f"j{i}", x0=float(x0[i])))
    elements = []
    for i in range(n):
        j = int(rng.integers(-1, i)) if i else -1
        a, qa = ("ground", 0.0) if j < 0 else (nodes[j].name, float(x0[j]))
        q0 = float(x0[i]) - qa
        spring = SPRINGS[int(rng.integers(len(SPRINGS)))]
        if not isinstance(nodes[i], Mass) or rng.random() < 0.5:
            dash = DASHPOTS[int(rng.integers(len(DASHPOTS)))]
            elements.append(Element(f"d{i}", _law(rng, dash, q0), a, nodes[i].name))
        elements.append(Element(f"s{i}", _law(rng, spring, q0), a, nodes[i].name))
    return Scene(nodes, elements)


def _record(out: dict, key: str, run) -> None:
    try:
        sol = run()
    except Exception as exc:  # noqa: BLE001 - the error is part of the fingerprint
        out[key + "/error"] = np.array(f"{type(exc).__name__}: {exc}")
        return
    out[key + "/t"] = np.asarray(sol.t)
    out[key + "/data"] = np.asarray(sol.data)
    out[key + "/status"] = np.array(str(sol.status))
    out[key + "/message"] = np.array(str(sol.message))


def fingerprint(quick: bool = False) -> dict:
    out: dict = {}
    for scene in SCENES:
        for rtol in TOLERANCES:
            for compiled in (False, True):
                _record(out, f"bench/{scene.name}/{rtol:g}/{compiled}",
                        lambda s=scene, r=rtol, c=compiled: simulate(
                            generic_scene(s), method="radau5", t_end=s.t_end, rtol=r,
                            atol=r * 1e-3, compiled=c, throw=False))
    for seed in range(10 if quick else NETWORKS):
        for method in ("bdf1", "bdf2", "radau5"):
            for dt in LEVELS:
                extra = ({"rtol": dt ** 3, "atol": dt ** 3, "compiled": False}
                         if method == "radau5" else {"dt": dt})
                _record(out, f"net/{seed}/{method}/{dt:g}",
                        lambda s=seed, m=method, e=extra: simulate(
                            random_network(s), method=m, t_end=0.5, throw=False, **e))
    for name, factory in (("impact", impact_scene), ("lock", lock_scene)):
        for method in ("bdf1", "bdf2", "jit-bdf1", "jit-bdf2", "radau5"):
            for dt in (1e-3, 1e-4):
                extra = {"rtol": dt, "atol": dt * 1e-3} if method == "radau5" else {"dt": dt}
                _record(out, f"{name}/{method}/{dt:g}",
                        lambda f=factory, m=method, e=extra: simulate(
                            f(), method=m, t_end=3.0, throw=False, **e))
    return out


def compare(new: dict, old_path: str) -> int:
    old = dict(np.load(old_path, allow_pickle=False))
    bad = sorted(k for k in set(old) | set(new)
                 if k not in old or k not in new or old[k].shape != new[k].shape
                 or not np.array_equal(old[k], new[k], equal_nan=old[k].dtype.kind == "f"))
    runs = {k.rsplit("/", 1)[0] for k in new}
    print(f"{len(runs)} runs, {len(new)} arrays; {len(bad)} differ from {old_path}")
    for k in bad[:40]:
        print("  differs:", k)
    return 1 if bad else 0


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--out", required=True)
    p.add_argument("--compare")
    p.add_argument("--quick", action="store_true")
    args = p.parse_args()
    t0 = time.perf_counter()
    new = fingerprint(quick=args.quick)
    np.savez(args.out, **new)
    print(f"wrote {args.out} in {time.perf_counter() - t0:.0f} s")
    return compare(new, args.compare) if args.compare else 0


if __name__ == "__main__":
    raise SystemExit(main())
