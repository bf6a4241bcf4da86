"""The compiled mode probe (:mod:`lumped.solvers.modes.mode_guess_jit`) against the Python one
(:func:`lumped.solvers.modes.mode_guess.try_modes`, the reference) on the probes that real
``radau5`` runs make: the same mode, velocities and forces, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest
from _string_beside_stick import string_thrown
from _yielding_junction import yielding_junction

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.bench.scenes import OWN_SCENES, PAPER_SCENES, generic_scene
from lumped.codegen.branches import law_branches
from lumped.codegen.jit import numba_enabled
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven import mode_state as adaptive_modes
from lumped.solvers.eventdriven import runner
from lumped.solvers.modes import mode_guess

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="needs numba")


def _bench(name: str) -> tuple[Scene, float]:
    scene = {s.name: s for s in PAPER_SCENES + OWN_SCENES}[name]
    return generic_scene(scene), scene.t_end


def _junction_scene() -> Scene:
    """A Coulomb element holding a junction behind a spring, and a Herschel-Bulkley
    dashpot (n = 1.5) between two masses."""
    return Scene([Junction("j0", x0=0.0), Mass("m1", m=0.15, x0=0.0, v0=1.2),
                  Mass("m2", m=1.0, x0=0.0, v0=0.0001)],
                 [Element("e0", get_law("coulomb").bind(tau=0.08, r=1.5), "ground", "j0"),
                  Element("e1", get_law("linear_spring").bind(k=5.85), "j0", "m1"),
                  Element("e2", get_law("herschel_bulkley").bind(gamma=0.7, tau=0.3, n=1.5),
                          "m1", "m2"),
                  Element("e3", get_law("linear_spring").bind(k=8.57), "ground", "m2")])


def _recorded_probes() -> list[tuple]:
    """The arguments of every probe of compiled ``radau5`` runs on a few scenes (events
    of every kind: stick, slip, reversal, break-out, at masses and junctions)."""
    calls = []
    keep = adaptive_modes.try_modes

    def record(scene, branches, candidates, t, x, v, F, h_p, current=None, longer=1,
               fast=None, used=None):
        assert fast is not None  # compiled runs
        calls.append((scene, branches, [list(c) for c in candidates], t, list(x), list(v),
                      list(F), h_p, None if current is None else list(current), longer,
                      fast))
        return keep(scene, branches, candidates, t, x, v, F, h_p, current, longer, fast,
                    used=used)

    runs = [(*_bench("stick-breakout"), 1e-6), (*_bench("forcing-F2"), 1e-8),
            (*_bench("release-0.5"), 1e-4), (*_bench("forcing-F1"), 1e-4),
            (bingham_chain(3), 5.0, 1e-6), (_junction_scene(), 2.0, 1e-6),
            (yielding_junction(), 0.5, 6.25e-4),  # (a steep branch read by its rate)
            (string_thrown(), 3.0, 1e-8)]  # (a taut string: its lock's velocity form)
    adaptive_modes.try_modes = record
    rest_run, runner.rest_run = runner.rest_run, lambda scene, settings: None  # (Python)
    try:
        for scene, t_end, rtol in runs:
            sol = simulate(scene, method="radau5", t_end=t_end, rtol=rtol, atol=1e-2 * rtol,
                           compiled=True)
            assert sol.ok, sol.message
    finally:
        adaptive_modes.try_modes = keep
        runner.rest_run = rest_run
    return calls


def test_compiled_probe_agrees_with_the_python_probe():
    calls = _recorded_probes()
    assert len(calls) >= 40
    outcomes = set()
    for scene, branches, candidates, t, x, v, F, h_p, current, longer, fast in calls:
        # every candidate alone, then all of them in order, at the recorded probe sizes
        for cands in [[c] for c in candidates] + [candidates]:
            for size in (1, longer):
                py = mode_guess.try_modes(scene, branches, cands, t, x, v, F, h_p, current,
                                          size)
                jit = mode_guess.try_modes(scene, branches, cands, t, x, v, F, h_p, current,
                                           size, fast)
                assert py == jit, (t, cands, py, jit)  # lists of floats: bit for bit
                outcomes.add(py is None)
    assert outcomes == {True, False}  # both confirmed and refused guesses were compared


def test_lock_rows_hold_only_strings_at_their_length():
    """A guess's taut string is held on the velocity level where it is at its length to
    ``sqrt(eps)`` of the positions (a drift of ``1.6e-14`` included), in positions' form
    where it is not (a guess that makes a slack string taut)."""
    scene = string_thrown()
    branches = [law_branches(el.law) for el in scene.elements]
    taut, slack = [0, 1, 0], [0, 0, 0]
    L = 0.35
    for x1, held in ((0.3 + L, True), (0.3 + L + 1.6e-14, True), (0.3 + L - 1e-6, False)):
        rows = mode_guess.lock_rows(scene, branches, [taut, slack], [0.3, x1])
        if held:
            assert rows[0, 1] == L
        else:
            assert np.isnan(rows[0, 1])
        assert np.isnan(rows[1]).all()  # (no lock on the slack branch, nor elsewhere)
        assert np.isnan(rows[0, 0]) and np.isnan(rows[0, 2])
