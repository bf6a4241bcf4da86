"""The faithful port of ``jit-bdf1``/``jit-bdf2`` is compiled only when the fast loop
hands a step over (issue 27: a first run on a fresh machine). It is numba's largest
shared loop (about 30 s of CPU to compile, once per machine); a run the scene's fast loop
takes whole must not ask for it. Counted, not timed: the port's getter is replaced by one
that records its calls."""

from __future__ import annotations

import pytest

from lumped import simulate
from lumped.codegen import scene_numbers
from lumped.scenarios import scenario_scene
from lumped.solvers.bdf import core_jit


@pytest.fixture
def port_calls(monkeypatch):
    calls: list[int] = []
    real = core_jit.compiled_run_bdf_core

    def counted():
        calls.append(1)
        return real()

    monkeypatch.setattr(core_jit, "compiled_run_bdf_core", counted)
    return calls


@pytest.mark.parametrize("method", ["jit-bdf1", "jit-bdf2"])
def test_a_run_the_fast_loop_takes_whole_never_asks_for_the_faithful_port(method,
                                                                          port_calls):
    sol = simulate(scenario_scene("forcing-F2"), method=method, dt=1e-3, t_end=2.0,
                   fast=True)
    assert sol.ok, sol.message
    assert sol.stats["handovers"] == 0
    assert sol.stats["fast_steps"] == sol.stats["steps"] == 2000
    assert port_calls == []


def test_a_hand_over_still_gets_the_faithful_port(port_calls):
    # fast=False: the faithful port alone (the same getter)
    sol = simulate(scenario_scene("forcing-F2"), method="jit-bdf2", dt=1e-3, t_end=0.5,
                   fast=False)
    assert sol.ok, sol.message
    assert port_calls == [1]


@pytest.mark.parametrize("cached", [False, True])
def test_a_short_run_takes_the_fast_loop_where_the_port_was_never_compiled(cached,
                                                                           monkeypatch):
    # fast=None below FAST_MIN_STEPS steps, a structure whose fast loop is not cached:
    # the faithful port if numba's disk cache has it, else the fast loop (a few seconds
    # to compile, against about 30 s for the port on a fresh machine)
    from lumped.solvers.bdf import fast_codegen

    monkeypatch.setattr(core_jit, "port_cached", lambda: cached)
    monkeypatch.setattr(fast_codegen, "fast_module_cached", lambda scene, key=None: False)
    sol = simulate(scenario_scene("forcing-F2"), method="jit-bdf2", dt=1e-2, t_end=5.0)
    assert sol.ok, sol.message
    assert sol.stats["steps"] == 500
    assert ("fast_steps" in sol.stats) is (not cached)


def test_the_port_is_not_cached_on_a_fresh_machine(tmp_path):
    # numba's cache directory empty: no index for the port (a fresh process, nothing run)
    import os
    import subprocess
    import sys

    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path))
    code = ("from lumped.solvers.bdf.core_jit import port_cached; "
            "print(port_cached())")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "False"


@pytest.mark.parametrize("method", ["jit-bdf1", "jit-bdf2"])
def test_a_run_the_fast_loop_takes_whole_makes_no_port_callbacks(method, monkeypatch):
    # the port's structure-generic step system (and the laws' law modules its header
    # points to) are made at the first hand-over only, like the port itself
    from lumped.codegen import step_dispatch

    made: list[str] = []

    def counted(name, real):
        def wrapper(*args, **kwargs):
            made.append(name)
            return real(*args, **kwargs)
        return wrapper

    monkeypatch.setattr(step_dispatch, "step_callbacks",
                        counted("step_callbacks", step_dispatch.step_callbacks))
    monkeypatch.setattr(step_dispatch, "step_header",
                        counted("step_header", step_dispatch.step_header))
    monkeypatch.setattr(scene_numbers, "_STRUCTURES", {})  # (no header kept from before)
    sol = simulate(scenario_scene("forcing-F2"), method=method, dt=1e-3, t_end=2.0,
                   fast=True)
    assert sol.stats["handovers"] == 0 and sol.stats["fast_steps"] == 2000
    assert made == []
    sol = simulate(scenario_scene("forcing-F2"), method=method, dt=1e-3, t_end=0.5,
                   fast=False)
    assert made == ["step_header", "step_callbacks"]
