"""When ``radau5`` with ``compiled=None`` builds its compiled loop
(:mod:`lumped.solvers.eventdriven.compile_when`, issue 27): on a machine whose shared
loop is not compiled (neither in the process nor in numba's disk cache), runs stay in the
Python loop until the Python steps of the process's runs reach ``SHARED_COMPILE_AFTER``
(a fresh machine's first run at rtol 1e-11 on the paper's scene took 13.2 s of CPU,
compiling after 2000 steps, against 1.2 s in Python); then the loop is compiled mid-run
with the Python loop's numbers, and later runs start compiled. The counts of steps are
patched small; no time is measured."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.codegen.jit import numba_enabled
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.scene.forcing import SineBurst
from lumped.solvers.eventdriven import compile_when, loop_jit

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="numba is disabled")

KW = dict(method="radau5", t_end=1.0, rtol=1e-9, atol=1e-12)


def _scene(k: float) -> Scene:
    """The paper's oscillator under F2 with numbers no other test runs (a plan of its own,
    no compiled loop kept on it: each test here passes its own ``k``)."""
    return Scene([Mass("mass", m=1.0625)],
                 [Element("s", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("d", get_law("bingham").bind(gamma=1.125, tau=0.9375), "ground",
                          "mass")],
                 forces={"mass": SineBurst(10.0, 5.0 * math.pi, 1.0)})


@pytest.fixture
def fresh_machine(monkeypatch):
    """The shared loop not compiled in this process and not in numba's disk cache (the
    cache looked at already), ``COMPILE_AFTER = 100``, no Python steps waited yet."""
    monkeypatch.setattr(loop_jit, "_COMPILED", [])
    monkeypatch.setattr(loop_jit, "_LOOKED", [True])
    monkeypatch.setattr(compile_when, "COMPILE_AFTER", 100)
    monkeypatch.setattr(compile_when, "_WAITED", [0])
    return monkeypatch


def test_runs_wait_for_the_shared_loop_then_compile_it_once(fresh_machine):
    scene = _scene(97.375)
    ref = simulate(scene, compiled=False, **KW)
    n = ref.stats["steps"]
    assert n > 300
    fresh_machine.setattr(compile_when, "SHARED_COMPILE_AFTER", n + n // 2)
    assert not compile_when.shared_compiled()
    # the first run: past COMPILE_AFTER, short of SHARED_COMPILE_AFTER: Python throughout
    first = simulate(scene, **KW)
    assert first.stats["loop"].startswith(compile_when.WAITING)
    assert "`lumped warm`" in first.stats["loop"]
    assert np.array_equal(first.data, ref.data)
    assert compile_when._WAITED[0] == n
    # the second: compiled once its steps and the first run's reach SHARED_COMPILE_AFTER
    second = simulate(scene, **KW)
    assert second.stats["loop"] == f"compiled from step {n // 2}"
    assert np.array_equal(second.data, ref.data) and second.stats["nfev"] == ref.stats["nfev"]
    assert compile_when.shared_compiled() and compile_when._WAITED[0] == n
    # every later run, any numbers: compiled from step 0
    assert simulate(scene, **KW).stats["loop"] == "compiled"


def test_a_run_of_its_own_compiles_after_shared_compile_after_steps(fresh_machine):
    """A long run on a fresh machine compiles mid-run (not after ``COMPILE_AFTER``)."""
    scene = _scene(96.625)
    ref = simulate(scene, compiled=False, **KW)
    n = ref.stats["steps"]
    fresh_machine.setattr(compile_when, "SHARED_COMPILE_AFTER", n // 2)
    run = simulate(scene, **KW)
    assert run.stats["loop"] == f"compiled from step {n // 2}"
    assert np.array_equal(run.data, ref.data)


def test_the_shared_loop_compiled_is_seen():
    loop_jit.compiled_advance()
    assert compile_when.shared_compiled()
