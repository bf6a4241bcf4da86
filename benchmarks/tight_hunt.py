"""Hunt for random networks that ``radau5`` cannot finish at a tight tolerance (issue 29).

Draws scenes from the property suite's strategy (``networks`` in
``tests/solvers/test_random_networks.py``: 1-4 nodes, every built-in law, half of them
loaded on one mass), seed by seed (seed ``s`` is the draw of a ``random.Random(s)``, the
numbering of the known failures' scenes), and runs each as
``test_random_network_tight_tolerance`` does: ``radau5`` at ``rtol = 1e-10``,
``atol = 1e-13``, output every quarter of the suite's coarse step, the Python loop by
default. Each run gets a CPU budget; what does not finish cleanly is recorded with its
seed:

* ``stop``: the run ended early (``sol.ok`` false), with its message;
* ``bridged``: it finished, but backward Euler bridged spans the adaptive step could not
  cross (``sol.stats["bridges"]``);
* ``hang``: it ran out of its CPU budget;
* ``error``: it raised (a scene the method refuses is ``refused``, not a failure).

Usage::

    python benchmarks/tight_hunt.py --seeds 0 400 --loaded --budget 30 --out hunt.jsonl

Draw a seed's scene again with :func:`draw`. The machine is shared: run it under
``nice``. (It reaches into hypothesis's internals to draw without a test: a hypothesis
upgrade may need this file changed, nothing else.)
"""

from __future__ import annotations

import argparse
import json
import random
import signal
import sys
import time
from pathlib import Path

_ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(_ROOT / "tests"), str(_ROOT / "tests" / "solvers")]

from hypothesis.control import BuildContext  # noqa: E402
from hypothesis.internal.conjecture.data import ConjectureData  # noqa: E402

from lumped import simulate  # noqa: E402
from lumped.scene import Mass  # noqa: E402

RTOL, ATOL = 1e-10, 1e-13


def draw(seed: int):
    """The strategy's scene for ``seed`` (a fixed stream of random choices)."""
    import test_random_networks as suite

    data = ConjectureData(random=random.Random(seed))
    with BuildContext(data, is_final=True, wrapped_test=None):
        return data.draw(suite.networks())


class _OutOfTime(Exception):
    pass


def _alarm(signum, frame):  # pragma: no cover - a signal handler
    raise _OutOfTime


def run(seed: int, budget: float, compiled: bool) -> dict:
    """Run the tight-tolerance case of ``seed``; a record of what happened."""
    import test_random_networks as suite

    scene = draw(seed)
    masses = sum(isinstance(nd, Mass) for nd in scene.nodes)
    rec = {"seed": seed, "nodes": len(scene.nodes), "masses": masses,
           "laws": sorted({el.law_name for el in scene.elements}),
           "loaded": bool(scene.forcing and any(f is not None for f in scene.forcing))}
    dt, t_end = suite.grid(scene)
    signal.signal(signal.SIGPROF, _alarm)
    signal.setitimer(signal.ITIMER_PROF, budget)
    t0 = time.process_time()
    try:
        sol = simulate(scene, method="radau5", dt=dt / 4, t_end=t_end, rtol=RTOL,
                       atol=ATOL, compiled=compiled)
    except _OutOfTime:
        rec.update(outcome="hang", cpu=time.process_time() - t0)
        return rec
    except ValueError as err:
        msg = str(err)
        refused = "inconsistent initial state" in msg or "does not take" in msg
        rec.update(outcome="refused" if refused else "error", message=msg[:300],
                   cpu=time.process_time() - t0)
        return rec
    except Exception as err:  # noqa: BLE001 - recorded, the hunt goes on
        rec.update(outcome="error", message=f"{type(err).__name__}: {err}"[:300],
                   cpu=time.process_time() - t0)
        return rec
    finally:
        signal.setitimer(signal.ITIMER_PROF, 0.0)
    bridges = int(sol.stats.get("bridges", 0))
    outcome = "stop" if not sol.ok else ("bridged" if bridges else "ok")
    rec.update(outcome=outcome, cpu=time.process_time() - t0, bridges=bridges,
               steps=int(sol.stats.get("steps", 0)), events=int(sol.stats.get("events", 0)),
               message=(sol.message or "")[:300])
    return rec


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", type=int, nargs=2, default=(0, 200), metavar=("FIRST", "END"))
    ap.add_argument("--loaded", action="store_true", help="only the loaded draws")
    ap.add_argument("--budget", type=float, default=30.0, help="CPU seconds per scene")
    ap.add_argument("--compiled", action="store_true", help="the compiled loop")
    ap.add_argument("--out", type=Path, default=None, help="JSON lines, one per scene")
    args = ap.parse_args(argv)
    counts: dict[str, int] = {}
    out = args.out.open("a") if args.out else None
    for seed in range(*args.seeds):
        if args.loaded:
            scene = draw(seed)
            if not (scene.forcing and any(f is not None for f in scene.forcing)):
                continue
        rec = run(seed, args.budget, args.compiled)
        counts[rec["outcome"]] = counts.get(rec["outcome"], 0) + 1
        if rec["outcome"] not in ("ok", "refused"):
            print(json.dumps(rec), flush=True)
        if out:
            out.write(json.dumps(rec) + "\n")
            out.flush()
    print("counts:", counts)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
