"""The compiled inner loop of ``radau5`` (:mod:`lumped.solvers.eventdriven.loop_jit`) against the
pure-Python loop it ports (``compiled=False``, the readable reference): the same steps,
dense output, events and counters; the fallback to Python and its reasons; exact sticking.

The shared loop is compiled once per machine (numba's disk cache); each scene here
compiles only its own small kernels.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _lock_scenes import loaded_string_chain

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.bench.impact_scenes import impact_scene, lock_scene
from lumped.codegen.jit import numba_enabled
from lumped.laws import ElementLaw
from lumped.scenarios import scenario_scene
from lumped.scene.forcing import SineBurst
from lumped.solvers.eventdriven import creep, mode_state
from lumped.solvers.eventdriven.at_rest import REST_LOOP

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")


def _chain() -> Scene:
    """Two masses with Bingham dashpots in a chain: stick-slip of both, several events."""
    lin, bing = get_law("linear_spring"), get_law("bingham")
    return Scene(
        [Mass("a", m=1.0, x0=0.3), Mass("b", m=0.7, x0=-0.1)],
        [Element("s1", lin.bind(k=50.0), "ground", "a"),
         Element("d1", bing.bind(gamma=0.5, tau=1.5), "ground", "a"),
         Element("s2", lin.bind(k=30.0), "a", "b"),
         Element("d2", bing.bind(gamma=2.0, tau=0.8), "a", "b")])


def _user_law_scene() -> Scene:
    """A user's Bingham written another way (``sign * Max(|F| - tau, 0)``), forced by a sine
    burst, and a Maxwell arm through a junction (a massless node)."""
    user = ElementLaw("my_bingham", "dashpot",
                      "gamma*q - sign(F)*Max(Abs(F) - tau, 0)", ["gamma", "tau"])
    lin, newt = get_law("linear_spring"), get_law("newtonian")
    return Scene(
        [Mass("m", m=1.0, x0=0.0), Junction("j", x0=0.0)],
        [Element("s", lin.bind(k=100.0), "ground", "m"),
         Element("d", user.bind(gamma=1.0, tau=1.0), "ground", "m"),
         Element("k3", lin.bind(k=60.0), "j", "m"),
         Element("c3", newt.bind(c=2.0), "ground", "j")],
        {"m": SineBurst(2.0, 2.0 * math.pi, 1.5)})


def _constant_force() -> Scene:
    base = scenario_scene("release-0.5")
    return Scene(base.nodes, base.elements, {"mass": 0.7})


CASES = {
    "forcing-F2": (lambda: scenario_scene("forcing-F2"), 3.0, 1e-8),
    "release-0.5": (lambda: scenario_scene("release-0.5"), 3.0, 1e-6),
    "constant-force": (_constant_force, 3.0, 1e-8),
    "impact": (impact_scene, 1.5, 1e-8),
    "chain": (_chain, 1.5, 1e-7),
    "user-law+junction": (_user_law_scene, 2.5, 1e-7),
}


def _pair(name: str):
    build, t_end, rtol = CASES[name]
    scene = build()
    kw = dict(method="radau5", t_end=t_end, rtol=rtol, atol=1e-3 * rtol)
    return simulate(scene, compiled=False, **kw), simulate(scene, compiled=True, **kw)


@pytest.mark.parametrize("name", sorted(CASES))
def test_the_compiled_loop_gives_the_python_loop_run(name):
    ref, fast = _pair(name)
    assert fast.stats["loop"] == "compiled"
    assert ref.stats["loop"] == "python: compiled=False"
    assert ref.ok and fast.ok
    counters = ("steps", "rejected", "newton_iterations", "factorizations", "nfev", "njev",
                "events", "max_newton_iterations")
    assert {k: fast.stats[k] for k in counters} == {k: ref.stats[k] for k in counters}
    assert len(ref.events) >= (1 if name == "impact" else 2)
    assert [(ev.element, ev.kind, ev.from_branch, ev.to_branch) for ev in fast.events] == [
        (ev.element, ev.kind, ev.from_branch, ev.to_branch) for ev in ref.events]
    scale = np.maximum(np.abs(ref.data).max(axis=0), 1e-300)
    # round-off only: the same steps and events; a stuck element's force after an event is
    # set by the balance, where the compiled and Python arithmetic (e.g. ``y**2`` as a
    # product or a ``pow``) differ in the last bits -- up to 1.7e-12 of the column's size
    # on the chain
    assert np.all(np.abs(fast.data - ref.data) <= 1e-11 * scale)
    t_end = ref.t[-1]
    assert np.allclose([ev.t for ev in fast.events], [ev.t for ev in ref.events],
                       rtol=0.0, atol=1e-12 * t_end)
    # the dense output everywhere, including inside the steps
    t = np.linspace(0.0, t_end, 2001)
    assert np.all(np.abs(fast.sol(t) - ref.sol(t)) <= 1e-11 * scale)


def test_the_old_impact_rule_on_the_loaded_chain_is_the_python_loop_one(monkeypatch):
    """With the mode after an impact read off the probe alone (the balance of
    accelerations off, :func:`~lumped.solvers.modes.after_impact.hold_impacted_locks`),
    the loaded chain reaches t = 0.19476 with both strings taut and a step near its floor:
    on one machine it bridged there (steps of 1.6e-8 s, the longest step 1.6e-3 s being
    the compiled loop's), on another its last bits take it through. Either way both loops
    give the same run, bit for bit, on one machine. That a bridge scales with the compiled
    loop's steps is checked where a bridge is forced on every machine (the creep test
    below: 20 compiled steps, then 7 bridges)."""
    monkeypatch.setattr(mode_state, "hold_impacted_locks", lambda *args: None)
    kw = dict(method="radau5", t_end=0.195, rtol=1e-10, atol=1e-13)
    ref = simulate(loaded_string_chain(), compiled=False, **kw)
    fast = simulate(loaded_string_chain(), compiled=True, **kw)
    assert fast.stats.pop("loop") == "compiled"
    assert ref.stats.pop("loop") == "python: compiled=False"
    assert ref.ok, ref.message
    assert fast.message == ref.message and fast.stats == ref.stats
    assert np.array_equal(fast.data, ref.data)


def test_a_run_that_creeps_stops_in_the_compiled_loop_as_in_the_python_loop(monkeypatch):
    """The creep test of the Python loop's accepted steps (20 in a row below the creep
    floor, :mod:`lumped.solvers.eventdriven.creep`) is the compiled loop's too: with the
    floor raised to 0.9 % of the run, the released mass's steps creep from the start;
    both loops stop at the 20th step, are bridged 7 times and give the same run, bit for
    bit. (The compiled loop had no creep test: it went on to ``t_end`` with no bridge.)"""
    monkeypatch.setattr(creep, "_CREEP_FRACTION", 9e-3)
    kw = dict(method="radau5", t_end=0.5, rtol=1e-8, atol=1e-11)
    ref = simulate(scenario_scene("release-0.5"), compiled=False, **kw)
    fast = simulate(scenario_scene("release-0.5"), compiled=True, **kw)
    assert fast.stats.pop("loop") == "compiled"
    assert ref.stats.pop("loop") == "python: compiled=False"
    assert ref.ok and ref.stats["bridges"] == 7 and "the run creeps" in ref.message
    assert fast.message == ref.message and fast.stats == ref.stats
    assert np.array_equal(fast.data, ref.data)


def test_exact_sticking_is_kept_in_the_compiled_loop():
    # eq. (17a): the mass never moves (held without steps, lumped.solvers.modes.stuck);
    # release-0.5: it sticks for good after its last event
    stuck = simulate(scenario_scene("forcing-F1"), method="radau5", t_end=3.0, rtol=1e-8,
                     compiled=True)
    assert stuck.stats["held_intervals"] == 2 and stuck.stats["steps"] == 0
    assert np.all(stuck.v["mass"] == 0.0) and np.all(stuck.x["mass"] == 0.0)
    sol = simulate(scenario_scene("release-0.5"), method="radau5", t_end=5.0, rtol=1e-8,
                   compiled=True)
    last = sol.events[-1]  # the mass comes to rest for good, stretched, at t = 3.1455
    after = sol.t > last.t
    assert sol.stats["loop"] == "compiled" and after.sum() >= 2
    assert np.all(sol.v["mass"][after] == 0.0)
    assert np.all(sol.x["mass"][after] == sol.x["mass"][after][0])
    dense = sol.sol(np.linspace(last.t, 5.0, 101)[1:])
    assert np.all(dense[:, 2] == 0.0)


def test_the_steps_to_a_stop_are_compiled(monkeypatch):
    """The step that ends on a forcing breakpoint or on ``t_end`` is the compiled loop's:
    a run without guard events makes no single attempts from Python, and gives the Python
    loop's run (the breakpoint at t = 1.5 is a time event in both)."""
    from lumped.solvers.eventdriven.fast import CompiledLoop

    base = scenario_scene("release-0.005")  # at rest throughout: held, no loop runs
    attempts = []
    real = CompiledLoop.attempt
    monkeypatch.setattr(CompiledLoop, "attempt",
                        lambda self, *a: attempts.append(a[0]) or real(self, *a))
    sol = simulate(base, method="radau5", t_end=2.0, rtol=1e-6, compiled=True)
    assert sol.ok and sol.stats["loop"] == REST_LOOP and not sol.events
    assert sol.t[-1] == 2.0 and attempts == []
    kw = dict(method="radau5", t_end=2.0, rtol=1e-7, atol=1e-10)
    scene = _user_law_scene()
    ref, fast = simulate(scene, compiled=False, **kw), simulate(scene, compiled=True, **kw)
    assert [ev.t for ev in fast.events if ev.kind == "time"] == [1.5]
    assert np.array_equal(fast.data, ref.data) and fast.stats["nfev"] == ref.stats["nfev"]


def test_the_fallback_to_python_says_why():
    base = scenario_scene("release-0.5")
    tabulated = Scene(base.nodes, base.elements, {"mass": lambda t: 0.1 * t})
    sol = simulate(tabulated, method="radau5", t_end=0.5, compiled=True)
    assert sol.ok and "function of t" in sol.stats["loop"] and "'mass'" in sol.stats["loop"]
    # locked elements in parallel: the minimum-norm split of their forces is Python's
    sol = simulate(lock_scene(), method="radau5", t_end=1.0, compiled=True)
    assert sol.ok and "in parallel" in sol.stats["loop"]
    # a spring and a Bingham dashpot in parallel: only one of them can lock, compiled
    assert simulate(base, method="radau5", t_end=0.5, compiled=True).stats["loop"] == "compiled"


def test_a_fold_stops_the_compiled_run_as_the_python_run():
    """``s_shaped`` pushed past its turning point: the fold check (a law that is not a known
    monotone one) runs in the compiled loop, and the stop is the Python loop's."""
    scene = Scene([Mass("mass", m=0.01, x0=-6.0)],
                  [Element("s", get_law("s_shaped").bind(q0=1.0, F0=1.0), "ground", "mass"),
                   Element("damper", get_law("newtonian").bind(c=0.05), "ground", "mass")],
                  forces={"mass": SineBurst(9.0, 0.25)})
    kw = dict(method="radau5", t_end=8.0, rtol=1e-8, throw=False)
    ref, fast = simulate(scene, compiled=False, **kw), simulate(scene, compiled=True, **kw)
    assert fast.stats["loop"] == "compiled"
    assert fast.status is ref.status and fast.status.value == "branch_lost"
    assert fast.message == ref.message and "'s'" in fast.message
    assert fast.stats["steps"] == ref.stats["steps"] > 3
    assert np.array_equal(fast.data, ref.data)


#: A law no other test uses: its structure is compiled only by the test below.
_ONLY_HERE = ElementLaw("only_in_the_compile_test", "spring", "F = k*q + c*q**3", ["k", "c"])


def test_by_default_a_new_structure_compiles_once_then_every_run_is_compiled(
        monkeypatch, tmp_path):
    """``compiled=None``, the shared loop compiled: a structure with no compiled modules
    yet (its laws' templates' modules: none loaded, an empty disk cache) starts in the
    Python loop and switches to the compiled loop after ``COMPILE_AFTER`` steps,
    seamlessly (the same run as the Python loop's); a short run stays in Python; then
    every run of that structure, with any numbers, starts compiled, and new numbers build
    no module."""
    from lumped.codegen import module_cache
    from lumped.codegen.template_module import template_module
    from lumped.codegen.templates import law_template
    from lumped.solvers.eventdriven import compile_when
    from lumped.solvers.eventdriven.loop_jit import compiled_advance

    compiled_advance()  # (the shared loop: compiled in this process, or loaded)
    COMPILE_AFTER = 200  # a shorter run than the default's
    monkeypatch.setattr(compile_when, "COMPILE_AFTER", COMPILE_AFTER)
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))

    def scene(k, c, gamma, tau):
        return Scene([Mass("m", m=1.0, x0=0.5)],
                     [Element("s", _ONLY_HERE.bind(k=k, c=c), "ground", "m"),
                      Element("d", get_law("bingham").bind(gamma=gamma, tau=tau), "ground",
                              "m")])

    first = scene(123.25, 0.5, 0.75, 1.25)
    short = simulate(first, method="radau5", t_end=0.2, rtol=1e-6)
    assert short.stats["loop"] == "python: not compiled yet (a short run)"
    kw = dict(method="radau5", t_end=3.0, rtol=1e-9, atol=1e-12)
    ref = simulate(first, compiled=False, **kw)
    modules = len(module_cache.LOADED_MODULES)
    lazy = simulate(first, **kw)
    # the structure's modules: one per law template (the new law's and Bingham's, in the
    # empty cache)
    assert len(module_cache.LOADED_MODULES) == modules + 2
    assert ref.stats["steps"] > COMPILE_AFTER + 50
    assert lazy.stats["loop"] == f"compiled from step {COMPILE_AFTER}"
    assert np.array_equal(lazy.data, ref.data) and lazy.stats["nfev"] == ref.stats["nfev"]
    assert simulate(first, **kw).stats["loop"] == "compiled"
    # new numbers, never run before: compiled from step 0, no module built, and the
    # compiled run is the Python loop's
    dispatchers = [getattr(template_module(law_template(el.law)), name)
                   for el in first.elements for name in ("t_law", "t_guards", "t_select")]
    signatures = [len(d.signatures) for d in dispatchers]
    assert signatures == [1] * 6
    for numbers in [(97.5, 0.25, 0.8, 1.5), (140.0, 1.75, 0.6, 0.9)]:
        other = scene(*numbers)
        new = simulate(other, method="radau5", t_end=0.2, rtol=1e-6)
        assert new.stats["loop"] == "compiled"
        assert np.array_equal(new.data, simulate(other, method="radau5", t_end=0.2,
                                                 rtol=1e-6, compiled=False).data)
    assert len(module_cache.LOADED_MODULES) == modules + 2
    assert [len(d.signatures) for d in dispatchers] == signatures


def test_the_compiled_keyword_is_checked():
    with pytest.raises(TypeError, match=r"`compiled` must be True, False or None, got 'yes'"):
        simulate(scenario_scene("release-0.5"), method="radau5", t_end=0.5, compiled="yes")


def test_the_compiled_dense_output_is_the_numpy_one(monkeypatch):
    """``sol(t)`` of ``radau5`` evaluated by the compiled loop of
    :mod:`lumped.solvers.radau.dense` gives the numpy evaluation's numbers, also at the
    step points and events (the later step: right limits)."""
    import lumped.solvers.radau.dense as out

    sol = simulate(scenario_scene("forcing-F2"), method="radau5", t_end=3.0, rtol=1e-7,
                   compiled=True)
    t = np.concatenate([np.linspace(0.0, 3.0, 3001), sol.t, [ev.t for ev in sol.events]])
    fast = sol.sol(t)
    monkeypatch.setattr(out, "numba_enabled", lambda: False)
    assert np.array_equal(sol.sol(t), fast)


def test_the_compiled_loop_is_called_without_python_calls_per_argument(monkeypatch):
    """The scene's kernels reach the compiled loop as addresses: numba passes a first-class
    function argument through ``_get_wrapper_address`` and ``_get_jit_address`` (Python
    calls that unpickle the signature, about 3.5 us each) on every call, and the loop is
    called once per landing attempt."""
    from numba.experimental import function_type

    scene = scenario_scene("forcing-F2")
    kw = dict(method="radau5", t_end=3.0, rtol=1e-6, compiled=True)
    first = simulate(scene, **kw)  # the scene's parts and their addresses, once
    calls = []
    for name in ("_get_wrapper_address", "_get_jit_address"):
        real = getattr(function_type, name)
        monkeypatch.setattr(function_type, name,
                            lambda f, sig, real=real, name=name: calls.append(name)
                            or real(f, sig))
    sol = simulate(scene, **kw)
    assert sol.stats["loop"] == "compiled" and len(sol.events) >= 2
    assert calls == []
    assert np.array_equal(sol.data, first.data)
