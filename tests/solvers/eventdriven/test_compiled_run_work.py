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
from lumped.scene.forcing import SineBurst
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


@pytest.mark.parametrize("compiled", [True, None])
def test_new_numbers_make_no_compiled_loop_part_of_the_structure_again(monkeypatch, compiled):
    """A run with new law numbers on a structure run before makes none of the compiled
    loop's parts that depend on the structure or the forcing objects alone (before: the
    forcing's arrays, the locks-in-parallel test and the disk cache's lookup of the
    structure's module, once per run), and gives the numbers of a run from scratch."""
    from lumped.bench.new_numbers import scene_with_new_numbers
    from lumped.codegen import module_cache
    from lumped.scene import forcing_jit
    from lumped.solvers.eventdriven.setup import clear_plans
    from lumped.solvers.nonsmooth import locks

    base = generic_scene(next(s for s in SCENES if s.name == "forcing-F2"))
    kw = dict(method="radau5", t_end=1.0, rtol=1e-7, compiled=compiled)
    simulate(base, **kw)  # (the structure's module compiled or loaded)
    for _ in range(3):  # a class's first two laws are derived; the third is its class's
        simulate(scene_with_new_numbers(base), **kw)
    calls = {"forcing": 0, "cycles": 0, "cached": 0}

    def counted(module, name, what):
        real = getattr(module, name)
        monkeypatch.setattr(module, name, lambda *a, **k: calls.__setitem__(
            what, calls[what] + 1) or real(*a, **k))

    counted(forcing_jit, "forcing_arrays", "forcing")
    counted(locks, "on_cycles", "cycles")
    counted(module_cache, "module_cached", "cached")
    scenes = [scene_with_new_numbers(base) for _ in range(2)]
    got = [simulate(scene, **kw) for scene in scenes]
    assert all(s.stats["loop"] == "compiled" and len(s.events) >= 2 for s in got)
    assert calls == {"forcing": 0, "cycles": 0, "cached": 0}
    monkeypatch.undo()
    clear_plans()
    for scene, sol in zip(scenes, got, strict=True):
        again = simulate(scene, **kw)
        assert np.array_equal(again.data, sol.data) and again.stats == sol.stats


def test_a_network_with_no_free_cycle_never_looks_for_indeterminate_forces(monkeypatch):
    """The chain's springs and dashpots lie on cycles, but no two of its elements that
    can be force-free (its Bingham dashpots) close one: no force can be indeterminate,
    and the driver does not look (before: once per event and per step the Python loop
    accepted). A scene whose stuck dashpots close a cycle still logs its intervals."""
    from lumped import Element, Mass, Scene, get_law
    from lumped.solvers.eventdriven import mode_state

    calls = []
    real = mode_state.indeterminate_elements
    monkeypatch.setattr(mode_state, "indeterminate_elements",
                        lambda *a: calls.append(1) or real(*a))
    got = simulate(bingham_chain(3), method="radau5", t_end=3.5, rtol=1e-6, compiled=False)
    assert len(got.events) >= 10 and got.indeterminate == {}
    assert calls == []
    bing = get_law("bingham")
    parallel = Scene([Mass("m", m=1.0, x0=0.0)],
                     [Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m"),
                      Element("d1", bing.bind(gamma=1.0, tau=1.0), "ground", "m"),
                      Element("d2", bing.bind(gamma=2.0, tau=0.5), "ground", "m")],
                     {"m": SineBurst(3.0, 6.0, 1.0)})
    sol = simulate(parallel, method="radau5", t_end=2.0, rtol=1e-6)
    assert calls and set(sol.indeterminate) == {"d1", "d2"}
