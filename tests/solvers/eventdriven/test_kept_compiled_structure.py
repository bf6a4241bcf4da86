"""The compiled loop's parts kept per *structure* (issue 27): a scene with new numbers takes
its structure's arrays and header (``radau5``'s :func:`~lumped.codegen.dispatch.
dispatch_scene`), or its module and arrays (:func:`~lumped.codegen.jit.jit_scene`), without
making its templates' list or the module's text again, and reads its own numbers (never a
kept scene's). Counted, never timed; every run equals a run from scratch."""

from __future__ import annotations

import numpy as np

from lumped import simulate
from lumped.codegen import dispatch, jit, templates
from lumped.codegen.dispatch import dispatch_scene
from lumped.codegen.jit import jit_scene
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven.setup import clear_plans, scene_plan
from lumped.solvers.implicit import initial_kept

KW = {"t_end": 0.6, "method": "radau5", "rtol": 1e-6, "compiled": True}


def _released(k: float, m: float = 1.0) -> Scene:
    """The bench's ``viscous-soft`` (``k = 10``, ``gamma = 0.2``, ``tau = 0.5``, released
    from ``x0 = 0.3``) with spring ``k`` and mass ``m``."""
    return Scene([Mass("mass", m=m, x0=0.3)],
                 [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=0.2, tau=0.5), "ground",
                          "mass")])


def _string(L: float, k: float) -> Scene:
    """A string (its lock value ``L``) between two masses, a Bingham dashpot to ground."""
    return Scene(
        [Mass("m", m=1.0, x0=0.0), Mass("n", m=2.0, x0=0.05)],
        [Element("s", get_law("string_spring").bind(k=k, L=L), "m", "n"),
         Element("d", get_law("bingham").bind(gamma=1.3, tau=0.7), "ground", "m")],
    )


def _from_scratch() -> None:
    clear_plans()
    templates._BY_LAW.clear()
    jit._ARRAYS.clear()
    initial_kept.forget()


def _same_run(a, b) -> None:
    assert np.array_equal(a.data, b.data) and a.columns == b.columns
    assert a.stats == b.stats and a.events == b.events


def _counting_modules(monkeypatch) -> list:
    calls: list = []
    real = jit.scene_module
    monkeypatch.setattr(jit, "scene_module", lambda s: calls.append(s) or real(s))
    return calls


def _counting_templates(monkeypatch) -> list:
    """The calls of :func:`~lumped.codegen.jit.scene_templates` by ``dispatch_scene``."""
    calls: list = []
    real = dispatch.scene_templates
    monkeypatch.setattr(dispatch, "scene_templates", lambda s: calls.append(s) or real(s))
    return calls


def test_new_numbers_take_their_structures_parts_and_their_own_numbers(monkeypatch):
    for j in (1, 2, 3):  # (the spring's law class: made from its first laws)
        simulate(_released(10.0 * (1.0 + 1e-6 * j)), **KW)
    scenes = [_released(10.0 * (1.0 + 1e-6 * j), m=1.0 + 0.125 * j) for j in range(4, 8)]
    simulate(scenes[0], **KW)  # (a law of the class: the structure's parts are kept)
    calls = _counting_modules(monkeypatch)
    listed = _counting_templates(monkeypatch)
    runs = [simulate(s, **KW) for s in scenes[1:]]
    # new numbers: the structure's arrays and header, its templates not listed again; no
    # scene module at all (radau5's kernels are the structure-generic ones)
    assert calls == [] and listed == []
    assert all(r.stats["loop"] == "compiled" for r in runs)
    kept = scene_plan(scenes[1]).structure
    got = [dispatch_scene(s, kept) for s in scenes]
    assert calls == [] and listed == []
    monkeypatch.undo()
    for s, js in zip(scenes, got, strict=True):  # each scene's own numbers, not a kept one's
        alone = dispatch_scene(s)
        assert js.module is None and js.ea is alone.ea
        assert np.array_equal(js.consts, alone.consts)
        head = 4 * len(s.elements)  # (the header, then the laws' constants)
        assert np.array_equal(js.consts[head:], jit_scene(s).consts)
        assert np.array_equal(js.masses, alone.masses)
        assert np.array_equal(js.lock_q, alone.lock_q, equal_nan=True)
    assert len({js.consts.tobytes() for js in got}) == len(got)
    assert [js.masses[0] for js in got] == [1.5, 1.625, 1.75, 1.875]
    for s, r in zip(scenes[1:], runs, strict=True):
        _from_scratch()
        _same_run(r, simulate(s, **KW))


def test_a_kept_module_is_not_taken_for_another_structure_or_cache(monkeypatch, tmp_path):
    """A law whose template has other functions than the kept ones (a string's lock value
    of 0 drops its term from the code) makes its own module; a kept module loaded for
    another cache directory is not taken for this one."""
    first = _string(0.25, 50.0)
    kept: dict = {}
    jit_scene(first, kept)
    calls = _counting_modules(monkeypatch)
    other = _string(0.0, 50.0)
    js = jit_scene(other, kept)
    assert calls == [other] and js.module is jit_scene(other).module
    assert kept["jit_scene"][1] is js.module  # kept now: the latest structure's
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))
    calls.clear()
    again = _string(0.0, 51.0)
    assert np.array_equal(jit_scene(again, kept).consts, jit_scene(again).consts)
    assert calls == [again, again]


def test_kept_dispatch_parts_are_not_taken_for_another_structure_or_cache(monkeypatch,
                                                                          tmp_path):
    """As above for ``dispatch_scene``: another template (a string's lock value of 0)
    lists its templates again and gets its own constants and header; parts kept for
    another cache directory are not taken for this one (its templates' modules are
    that cache's)."""
    first = _string(0.25, 50.0)
    kept: dict = {}
    dispatch_scene(first, kept)
    listed = _counting_templates(monkeypatch)
    other = _string(0.0, 50.0)
    js = dispatch_scene(other, kept)
    assert listed == [other] and np.array_equal(js.consts, dispatch_scene(other).consts)
    assert listed == [other, other]
    assert not np.array_equal(js.consts[:8], dispatch_scene(first).consts[:8])  # (headers)
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))
    listed.clear()
    again = _string(0.0, 51.0)
    assert np.array_equal(dispatch_scene(again, kept).consts, dispatch_scene(again).consts)
    assert listed == [again, again]


def test_the_drivers_node_and_element_kinds_are_kept_per_structure():
    """``setup.structure``: which nodes are masses, which elements springs or massless
    dashpots, shared by the plans of a structure; the masses and the lightest one are each
    scene's own."""
    from lumped.solvers.eventdriven.setup import structure

    for j in (1, 2, 3):  # (the spring's law class: made from its first laws)
        simulate(_released(10.0 * (1.0 + 1e-6 * j)), **KW)
    a, b = (_released(10.0 * (1.0 + 1e-6 * j), m=m) for j, m in ((4, 1.5), (5, 0.25)))
    got_a, got_b = structure(a, scene_plan(a)), structure(b, scene_plan(b))
    assert scene_plan(a).structure is scene_plan(b).structure
    assert got_a[0] is got_b[0] and got_a[2] is got_b[2] and got_a[3] is got_b[3]
    assert (got_a[0], got_a[2], got_a[3]) == ([True], [True, False], [False, False])
    assert (got_a[1], got_a[4]) == ((1.5,), 1.5) and (got_b[1], got_b[4]) == ((0.25,), 0.25)
    c = Scene([Mass("mass", m=2.0, x0=0.3), Junction("j")],
              [Element("spring", get_law("linear_spring").bind(k=10.0), "ground", "mass"),
               Element("d1", get_law("bingham").bind(gamma=0.2, tau=0.5), "mass", "j"),
               Element("d2", get_law("bingham").bind(gamma=0.3, tau=0.5), "j", "ground")])
    got_c = structure(c, scene_plan(c))  # another structure: its own kinds
    assert (got_c[0], got_c[2], got_c[3], got_c[4]) == (
        [True, False], [True, False, False], [False, False, True], 2.0)
