"""The Python work of ``radau5``'s compiled runs at its events (issue 27): counted, never
timed. A compiled run finds every guard crossing with its compiled root finder, the first
step after an event included, and gives the Python loop's run."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.bench.scenes import SCENES, generic_scene
from lumped.codegen.jit import numba_enabled
from lumped.solvers.eventdriven import checks
from lumped.solvers.modes import on_demand

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")


def _same_run(got, ref) -> None:
    """The Python loop's run: its steps, counters and events, its output to round-off
    (as in ``test_compile_counts``)."""
    for key in ("steps", "rejected", "newton_iterations", "factorizations", "events"):
        assert got.stats[key] == ref.stats[key], key
    assert [(e.t, e.element, e.kind, e.to_branch) for e in got.events] == [
        (e.t, e.element, e.kind, e.to_branch) for e in ref.events]
    scale = np.maximum(np.abs(ref.data).max(axis=0), 1e-300)
    assert np.all(np.abs(got.data - ref.data) <= 1e-11 * scale)


@pytest.mark.parametrize("case", ["chain", "forcing-F2"])
def test_a_compiled_run_locates_no_crossing_in_python(monkeypatch, case):
    """The first step after an event reads its guards from the stage forces, not the
    probe's: that second test runs compiled too (before: the Python root finder,
    ``first_root_py``, once per event, a tenth of the chain's sweep)."""
    monkeypatch.setattr(on_demand, "AFTER", 1)  # the event helpers compiled at first need
    scene, kw = (bingham_chain(3), dict(t_end=3.5, rtol=1e-6)) if case == "chain" else (
        generic_scene(next(s for s in SCENES if s.name == case)),
        dict(t_end=2.0, rtol=1e-8, atol=1e-11))
    ref = simulate(scene, method="radau5", compiled=False, **kw)
    simulate(scene, method="radau5", compiled=True, **kw)  # (the helpers compiled)
    calls = []
    real = checks.first_root_py
    monkeypatch.setattr(checks, "first_root_py", lambda *a: calls.append(1) or real(*a))
    got = simulate(scene, method="radau5", compiled=True, **kw)
    assert got.stats["loop"] == "compiled" and got.ok
    assert len(got.events) >= 3
    assert calls == []
    _same_run(got, ref)
