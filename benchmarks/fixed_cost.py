"""The fixed cost of a run on the bench's two scenes that never move (issue 27).

Usage, from the repository root (after ``pip install -e ".[test]"``)::

    python benchmarks/fixed_cost.py [--repeats 7] [--calls 2000]

``simulate(scene, t_end=5)`` and the :class:`~lumped.result.Solution` it returns, on
``release-0.005`` (k x0 = 0.5 < tau = 1, no forcing: at rest throughout) and
``forcing-F1`` (0.5 sin(5 pi t) on [0, 1], below tau: stuck throughout) of
:mod:`lumped.bench.scenes`, the scene object built once (its structure cached, as in a
benchmark or a study that runs one scene again and again). Cases: ``auto`` (no
tolerances: what ``simulate(scene, t_end=...)`` runs, ``radau5`` at its defaults),
``radau5`` at ``rtol`` 1e-7 and ``radau5`` at ``rtol`` 1e-7 with ``compiled=True`` (the
bench's setting), and, where the run at rest
(:mod:`lumped.solvers.eventdriven.at_rest`) exists, ``auto`` through the general driver
(the run at rest switched off in this process, for comparison). Two more rows time what a
user gets from a scene just written: ``auto`` on a **new scene object** at every call
(the same numbers, built before the timer) and on **new numbers** at every call (every
spring's ``k`` times a factor never run before in the process,
:func:`lumped.bench.new_numbers.scene_with_new_numbers`). Nothing kept per scene object
helps those; what is kept per scene content (the plan and the start at rest of
:mod:`lumped.solvers.eventdriven.setup`, keyed by
:func:`lumped.codegen.scene_key.scene_key`) serves the new object with the same numbers,
and only what is kept per structure or per law serves new numbers.

Each case is the CPU time (:func:`time.process_time`) of ``--calls`` calls, repeated
``--repeats`` times interleaved with the yardstick (:func:`lumped.bench.measure_unit`'s
loop, one call per repeat); printed are the median per call in microseconds and the
median over repeats of its ratio to one iteration of the yardstick loop (``u``), the
part of a call spent in Python's cyclic garbage collector (``gc us``: the wall time between
the collector's start and stop callbacks, :data:`gc.callbacks`, per call), and issue 27's
target (at most 50 us).
"""

from __future__ import annotations

import argparse
import gc
import os
import platform
import statistics
import time

from lumped import simulate
from lumped.bench.new_numbers import scene_with_new_numbers
from lumped.bench.scenes import PAPER_SCENES, YARDSTICK_ITERATIONS, generic_scene
from lumped.bench.timing import yardstick

SCENES = ("release-0.005", "forcing-F1")
#: name -> keywords of ``simulate``
CASES = {
    "auto": {},
    "radau5 rtol=1e-7": {"method": "radau5", "rtol": 1e-7},
    "radau5 rtol=1e-7 compiled=True": {"method": "radau5", "rtol": 1e-7, "compiled": True},
}
TARGET_US = 50.0


def _general_driver():
    """A context that switches the run at rest off (``None`` before it existed)."""
    try:
        from lumped.solvers.eventdriven import runner
    except ImportError:  # pragma: no cover
        return None
    if not hasattr(runner, "rest_run"):
        return None

    class Off:
        def __enter__(self):
            self.saved = runner.rest_run
            runner.rest_run = lambda scene, settings: None

        def __exit__(self, *exc):
            runner.rest_run = self.saved

    return Off()


class _GcClock:
    """The wall time Python's cyclic collector runs while the clock is on (its start and
    stop callbacks, :data:`gc.callbacks`)."""

    def __init__(self) -> None:
        self.total, self._start = 0.0, 0.0

    def __call__(self, phase: str, info: dict) -> None:
        if phase == "start":
            self._start = time.perf_counter()
        else:
            self.total += time.perf_counter() - self._start

    def __enter__(self) -> _GcClock:
        self.total = 0.0
        gc.callbacks.append(self)
        return self

    def __exit__(self, *exc) -> None:
        gc.callbacks.remove(self)


def _time(fn, calls: int) -> tuple[float, float]:
    """``(CPU seconds per call, collector seconds per call)`` of ``calls`` calls."""
    with _GcClock() as clock:
        t0 = time.process_time()
        for _ in range(calls):
            fn()
        cpu = time.process_time() - t0
    return cpu / calls, clock.total / calls


class _Fresh:
    """``simulate`` on a scene object made by ``make()`` for each call, the scenes made
    before the timer starts (:meth:`ready`)."""

    def __init__(self, make, t_end: float) -> None:
        self.make, self.t_end, self.scenes = make, t_end, []

    def ready(self, calls: int) -> None:
        self.scenes = [self.make() for _ in range(calls)]

    def __call__(self) -> None:
        simulate(self.scenes.pop(), t_end=self.t_end)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--calls", type=int, default=2000)
    args = parser.parse_args()

    by_name = {s.name: s for s in PAPER_SCENES}
    runs = {}
    for name in SCENES:
        bench = by_name[name]
        scene = generic_scene(bench)
        for case, kw in CASES.items():
            runs[(name, case)] = (lambda sc=scene, kw=kw, t=bench.t_end:
                                  simulate(sc, t_end=t, **kw), None)
        off = _general_driver()
        if off is not None:
            runs[(name, "auto, general driver")] = (lambda sc=scene, t=bench.t_end:
                                                    simulate(sc, t_end=t), off)
        runs[(name, "auto, new scene object")] = (
            _Fresh(lambda b=bench: generic_scene(b), bench.t_end), None)
        runs[(name, "auto, new numbers")] = (
            _Fresh(lambda sc=scene: scene_with_new_numbers(sc), bench.t_end), None)
    for fn, off in runs.values():  # warm: structure, kernels, compiled parts
        for _ in range(3):
            if isinstance(fn, _Fresh):
                fn.ready(1)
            if off is None:
                fn()
            else:
                with off:
                    fn()

    per_call: dict = {key: [] for key in runs}
    in_gc: dict = {key: [] for key in runs}
    ratios: dict = {key: [] for key in runs}
    units = []
    for _ in range(args.repeats):
        t0 = time.process_time()
        yardstick()
        unit = (time.process_time() - t0) / YARDSTICK_ITERATIONS
        units.append(unit)
        for key, (fn, off) in runs.items():
            if isinstance(fn, _Fresh):
                fn.ready(args.calls)
            if off is None:
                sec, collector = _time(fn, args.calls)
            else:
                with off:
                    sec, collector = _time(fn, args.calls)
            per_call[key].append(sec)
            in_gc[key].append(collector)
            ratios[key].append(sec / unit)

    unit_ns = statistics.median(units) * 1e9
    print(f"python {platform.python_version()}, load {os.getloadavg()[0]:.1f}; yardstick "
          f"{unit_ns:.1f} ns per iteration (u); median of {args.repeats} repeats of "
          f"{args.calls} calls; issue 27's target {TARGET_US:g} us")
    print(f"{'scene':15s} {'case':32s} {'us/run':>9s} {'u':>9s} {'gc us':>9s}")
    for name, case in runs:
        us = statistics.median(per_call[(name, case)]) * 1e6
        gc_us = statistics.median(in_gc[(name, case)]) * 1e6
        print(f"{name:15s} {case:32s} {us:9.1f} {statistics.median(ratios[(name, case)]):9.0f}"
              f" {gc_us:9.1f}")


if __name__ == "__main__":
    main()
