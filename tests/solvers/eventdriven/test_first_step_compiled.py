"""The first step after an event in ``radau5``'s compiled loop
(:mod:`lumped.solvers.eventdriven.first_step_jit`): the same numbers as the Python loop's pass.

After an event the state's forces are the mode probe's; the first step's dense output
starts from the stage forces' quadratic where a lock holds a mass (moved back until its
guards admit it) and the step is redone shorter when that output's defect against the
held laws exceeds 1. The compiled loop used to hand that step to the Python loop (one
pass of 60-75 us an event); it now takes it when its check is compiled.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.codegen.jit import numba_enabled
from lumped.scene.forcing import SineBurst
from lumped.solvers.eventdriven import fast as fast_mod
from lumped.solvers.eventdriven.first_step_jit import compiled_first_step
from lumped.solvers.eventdriven.run import Radau5Run
from lumped.solvers.modes.on_demand import OnDemand
from lumped.solvers.radau.dense_defect import norm2

needs_numba = pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")


def _paper(k: float = 100.0) -> Scene:
    """The paper's oscillator under F2: it sticks and breaks out again and again (a
    Bingham dashpot locked on the mass: its start force is the quadratic's, admitted)."""
    return Scene([Mass("mass", m=1.0, x0=0.0)],
                 [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground",
                          "mass")],
                 {"mass": SineBurst(10.0, 5.0 * np.pi, 1.0)})


def _junction_breakout(n: float) -> Scene:
    """A junction on a Herschel-Bulkley ``n < 1`` dashpot to ground, pulled through a spring
    by a moving mass: it breaks out with a rate ``~ (t - t*)^n``, which the first step's
    defect catches (issue 11's case, without locks in parallel: the compiled loop's)."""
    return Scene([Junction("j", x0=0.0), Mass("m", m=1.0, x0=0.0, v0=1.5)],
                 [Element("d", get_law("herschel_bulkley").bind(gamma=8.9, tau=0.22, n=n),
                          "ground", "j"),
                  Element("s", get_law("linear_spring").bind(k=1.0), "j", "m")])


def _python_first_steps(monkeypatch) -> list[int]:
    """A counter of the Python loop's passes over a first step after an event."""
    count = [0]
    step = Radau5Run._step

    def counted(self):
        if self.ms.forces_from_probe and self.target is None:
            count[0] += 1
        return step(self)

    monkeypatch.setattr(Radau5Run, "_step", counted)
    return count


def _same(a, b) -> None:
    assert np.array_equal(a.data, b.data)
    for key in ("steps", "rejected", "newton_iterations", "factorizations"):
        assert a.stats[key] == b.stats[key], key
    assert a.stats.get("defect_rejected") == b.stats.get("defect_rejected")
    assert [(e.t, e.element, e.kind, e.to_branch) for e in a.events] == [
        (e.t, e.element, e.kind, e.to_branch) for e in b.events]


@needs_numba
@pytest.mark.parametrize("rtol", [1e-3, 1e-8])
def test_the_compiled_loop_takes_the_first_step_after_an_event(monkeypatch, rtol):
    monkeypatch.setattr(fast_mod, "_FIRST_STEP", OnDemand(compiled_first_step, after=1))
    kw = dict(method="radau5", t_end=2.0, rtol=rtol, atol=rtol * 1e-2)
    ref = simulate(_paper(), compiled=False, **kw)
    python_passes = _python_first_steps(monkeypatch)
    got = simulate(_paper(), compiled=True, **kw)
    assert got.stats["loop"] == "compiled" and got.ok
    assert len(got.events) >= 6
    _same(got, ref)
    # every first step after an event was the compiled loop's (before: one Python pass
    # an event)
    assert python_passes[0] == 0


def _compiled_defect_rejections(monkeypatch) -> list[int]:
    """A counter of the first steps the compiled loop's defect check rejected."""
    count = [0]
    run = fast_mod.CompiledLoop.run

    def counted(self, st, modes, watched, stats, dense, rows):
        before = stats.get("defect_rejected", 0)
        why = run(self, st, modes, watched, stats, dense, rows)
        count[0] += stats.get("defect_rejected", 0) - before
        return why

    monkeypatch.setattr(fast_mod.CompiledLoop, "run", counted)
    return count


@needs_numba
@pytest.mark.parametrize("n, rtol, rejected", [(0.3, 6.25e-4, 2), (0.3, 1e-4, 2),
                                               (0.5, 6.25e-4, 1)])
def test_a_first_step_the_defect_rejects_in_the_compiled_loop(monkeypatch, n, rtol, rejected):
    monkeypatch.setattr(fast_mod, "_FIRST_STEP", OnDemand(compiled_first_step, after=1))
    kw = dict(method="radau5", t_end=3.0, rtol=rtol, atol=rtol * 1e-2)
    ref = simulate(_junction_breakout(n), compiled=False, **kw)
    compiled_rejections = _compiled_defect_rejections(monkeypatch)
    got = simulate(_junction_breakout(n), compiled=True, **kw)
    assert got.stats["loop"] == "compiled" and got.ok
    assert ref.stats["defect_rejected"] == rejected
    _same(got, ref)
    # the compiled loop's check rejected at least the first try (the Python loop takes
    # the pass after eight Newton failures in a row: its line search)
    assert compiled_rejections[0] >= 1


@needs_numba
def test_without_its_compiled_check_python_takes_the_first_step(monkeypatch):
    # a machine that never compiled the check (OnDemand: until a process asks often)
    monkeypatch.setattr(fast_mod, "_FIRST_STEP", OnDemand(lambda compile: None))
    kw = dict(method="radau5", t_end=2.0, rtol=1e-6, atol=1e-8)
    ref = simulate(_paper(), compiled=False, **kw)
    python_passes = _python_first_steps(monkeypatch)
    got = simulate(_paper(), compiled=True, **kw)
    assert got.stats["loop"] == "compiled"
    _same(got, ref)
    assert python_passes[0] >= len(got.events) - 1  # (one an event)


_values = st.floats(allow_nan=False, allow_infinity=False, min_value=-1e300, max_value=1e300)


@given(a=_values, b=_values)
def test_norm2_is_hypot_to_rounding_without_overflow(a, b):
    got = norm2(a, b)
    want = math.hypot(a, b)
    assert math.isfinite(got)
    assert got == pytest.approx(want, rel=4e-16, abs=0.0)


def test_norm2_at_zero_infinity_and_nan():
    assert norm2(0.0, -0.0) == 0.0
    assert norm2(math.inf, 1.0) == math.inf and norm2(1.0, -math.inf) == math.inf
    assert math.isnan(norm2(math.nan, 1.0)) and math.isnan(norm2(1.0, math.nan))
    assert norm2(3e300, 4e300) == pytest.approx(5e300, rel=1e-15)
