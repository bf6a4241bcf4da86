"""The compiled break-out root and scan of a held interval (:mod:`lumped.solvers.modes.stuck_jit`)
against the Python reference (:meth:`lumped.solvers.modes.stuck.StaticHold._root` with
:func:`scipy.optimize.brentq`, :meth:`~lumped.solvers.modes.stuck.StaticHold.breakout` without
the compiled loop): the same root and samples, bit for bit."""

from __future__ import annotations

import math
import random

import numpy as np
import pytest
from scipy.optimize import brentq

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.bench.scenes import OWN_SCENES, PAPER_SCENES, generic_scene
from lumped.codegen.jit import numba_enabled
from lumped.solvers.eventdriven import runner
from lumped.solvers.modes import stuck
from lumped.solvers.modes.stuck_jit import brent, compiled_breakout_root


def test_brent_takes_the_steps_of_scipy_brentq():
    rng = random.Random(7)
    compared = 0
    for _ in range(8000):
        A, w = rng.uniform(0.1, 10.0), rng.uniform(0.5, 30.0)
        c, tau = rng.uniform(-0.9, 0.9) * A, rng.uniform(0.01, 2.0)

        def f(t, A=A, w=w, c=c, tau=tau):
            return tau - abs(A * math.sin(w * t) + c)

        a = rng.uniform(0.0, 1.0)
        b = a + rng.uniform(1e-6, 1.0)
        if not f(a) > 0.0 > f(b):
            continue
        xtol = 4e-16 * max(1.0, b)
        assert brent(f, a, b, xtol, 1e-15) == brentq(f, a, b, xtol=xtol, rtol=1e-15)
        compared += 1
    assert compared > 800


def _runs_through(method: str, record, names: tuple[str, ...]) -> None:
    """Run ``radau5`` (compiled) on the bench scenes ``names`` at rtol 1e-4 and 1e-9 and
    on a 3-mass chain, with :class:`~lumped.solvers.modes.stuck.StaticHold`'s ``method``
    replaced by ``record`` for the runs; every run must succeed. The run at rest
    (:mod:`lumped.solvers.eventdriven.at_rest`, in Python) is off: ``forcing-F1`` runs
    its held intervals in the compiled driver."""
    scenes = {s.name: s for s in PAPER_SCENES + OWN_SCENES}
    runs = [(generic_scene(scenes[name]), rtol) for name in names for rtol in (1e-4, 1e-9)]
    runs.append((bingham_chain(3), 1e-6))
    keep, rest_run = getattr(stuck.StaticHold, method), runner.rest_run
    setattr(stuck.StaticHold, method, record)
    runner.rest_run = lambda scene, settings: None
    try:
        for scene, rtol in runs:
            sol = simulate(scene, method="radau5", t_end=5.0, rtol=rtol, atol=1e-2 * rtol,
                           compiled=True)
            assert sol.ok, sol.message
    finally:
        setattr(stuck.StaticHold, method, keep)
        runner.rest_run = rest_run


@pytest.mark.skipif(not numba_enabled(), reason="needs numba")
def test_compiled_breakout_root_agrees_with_the_reference():
    calls = []
    keep = stuck.StaticHold._root

    def record(self, e, j, guard, a, b, modes=None, fast=None):
        assert fast is not None
        calls.append((self, e, j, guard, a, b, list(modes), fast))
        return keep(self, e, j, guard, a, b, modes, fast)

    _runs_through("_root", record, ("stick-breakout", "forcing-F2", "high-yield-forced"))
    assert len(calls) >= 20
    root = compiled_breakout_root()
    for hold, e, j, guard, a, b, modes, fast in calls:
        ref = keep(hold, e, j, guard, a, b)
        _, fkind, fpar, c, minv, _ = hold.arrays()
        got = root(fast.guards.addr, fast.js.consts, e, modes[e], j, hold.q[e],
                   hold.free.index(e), fkind, fpar, c, minv, a, b, np.zeros(64))
        assert got == ref  # (not the fallback: nan)
        assert a < ref <= b


@pytest.mark.skipif(not numba_enabled(), reason="needs numba")
def test_compiled_breakout_scan_agrees_with_the_reference(monkeypatch):
    """The scan of a held interval's samples compiled (:func:`lumped.solvers.modes.stuck_jit.
    breakout_scan`, taken with a sine-burst forcing and more than two samples) and in
    Python (``fast=None``): the same break-out time and the same samples passed before it,
    and the same forces at each of them, bit for bit, on every held interval of runs that
    stick and break out again and again (one mass, a 3-mass chain) and of runs that never
    break out (a scan that passes every sample)."""
    calls = []
    keep = stuck.StaticHold.breakout
    scenes = {}  # id(hold) -> its scene (a hold keeps no reference to its scene)
    init = stuck.StaticHold.__init__

    def remember(self, scene, *args, **kwargs):
        init(self, scene, *args, **kwargs)
        scenes[id(self)] = scene

    monkeypatch.setattr(stuck.StaticHold, "__init__", remember)

    def record(self, t0, t1, guards, modes, fast=None, refine=True):
        calls.append((self, t0, t1, list(guards), list(modes), fast))
        return keep(self, t0, t1, guards, modes, fast, refine)

    _runs_through("breakout", record,
                  ("stick-breakout", "forcing-F1", "forcing-F2", "high-yield-forced"))
    scanned = broke = 0
    for hold, t0, t1, guards, modes, fast in calls:
        assert fast is not None
        N = len(hold.c)

        def again(hold=hold, N=N):
            return stuck.StaticHold(scenes[id(hold)], hold.y0[:N], hold.y0[N:2 * N], hold.F0,
                                    hold.free, hold.minv, hold.c, hold.fkind, hold.fpar)

        fresh, compiled = again(), again()
        ref = keep(fresh, t0, t1, guards, modes, None)
        got = keep(compiled, t0, t1, guards, modes, fast)
        assert got == ref
        samples = compiled.samples(t0, t1)
        if compiled.varying and len(samples) > 2:
            scanned += 1
            broke += got[0] is not None
            for s in got[1]:
                assert compiled.forces(s) == fresh.forces(s)
    assert scanned >= 10 and 0 < broke < scanned
