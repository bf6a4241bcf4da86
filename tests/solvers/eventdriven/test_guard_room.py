"""The compiled loops keep room for :data:`~lumped.codegen.templates.GUARD_ROOM` guard values
of one branch (numba checks no bounds): a scene with a law that has more runs ``radau5``'s
Python loop, and says why."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.codegen.jit import numba_enabled
from lumped.codegen.templates import GUARD_ROOM, law_template
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.eventdriven import fast_parts, loop_jit
from lumped.solvers.modes import mode_guess_jit


def _scene(x0: float) -> Scene:
    bingham = get_law("bingham").bind(gamma=2.0, tau=0.5)
    spring = get_law("linear_spring").bind(k=30.0)
    return Scene([Mass("m", m=1.0, x0=x0)],
                 [Element("d", bingham, "ground", "m"), Element("s", spring, "ground", "m")])


@pytest.mark.parametrize(("name", "values", "guards"), [
    ("bingham", {"gamma": 1.0, "tau": 0.5}, 2), ("coulomb", {"tau": 0.5, "r": 1.0}, 2),
    ("string_spring", {"k": 1.0, "L": 1.0}, 1), ("linear_spring", {"k": 1.0}, 0)])
def test_a_template_counts_the_most_guards_of_a_branch(name, values, guards):
    assert law_template(get_law(name).bind(**values)).guards == guards
    # a law bound again with other numbers takes its class's template: the same count
    other = {p: v * 1.2345 for p, v in values.items()}
    assert law_template(get_law(name).bind(**other)).guards == guards


def test_the_work_arrays_keep_the_room():
    assert loop_jit.loop_workspace(1, 1, 1, 1)[1].shape[1] >= GUARD_ROOM
    assert mode_guess_jit.probe_workspace(1, 1)[1].shape[1] >= GUARD_ROOM


@pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")
def test_a_law_with_more_guards_than_the_room_runs_in_python(monkeypatch):
    # (the scene's plan keeps why it runs in Python: numbers no other test uses)
    monkeypatch.setattr(fast_parts, "GUARD_ROOM", 1)  # (Bingham's stuck branch has 2)
    ours = simulate(_scene(0.1234567), method="radau5", t_end=0.5, compiled=True)
    assert ours.stats["loop"] == (
        "python: a law with 2 guards on one branch (the compiled loop has room for 1)")
    python = simulate(_scene(0.1234567), method="radau5", t_end=0.5, compiled=False)
    assert np.array_equal(ours.data, python.data)
    monkeypatch.undo()
    compiled = simulate(_scene(0.1234568), method="radau5", t_end=0.5, compiled=True)
    assert compiled.stats["loop"] == "compiled"
