"""Code generation kept per law content and per structure (issue 27): a law whose
numbers have no parametric class (an integral ``k``, ``tau = 1``) is derived once per
process, a structure's module text once per structure, and each equals what a derivation
from scratch gives."""

from __future__ import annotations

import math

import numpy as np

from lumped import Element, Mass, Scene
from lumped.codegen import jit, templates
from lumped.codegen.jit import scene_source
from lumped.codegen.scene_key import law_key
from lumped.codegen.templates import law_template, template_from_scratch
from lumped.laws import ElementLaw, get_law

CUBIC = ElementLaw("cubic_kept", "spring", "F = k*q + c*q**3", ["k", "c"])


def test_an_integral_law_is_derived_once_and_as_from_scratch(monkeypatch):
    calls = []
    monkeypatch.setattr(templates, "template_from_scratch",
                        lambda bound, lb=None: calls.append(bound) or template_from_scratch(
                            bound, lb))
    first = law_template(CUBIC.bind(k=7.0, c=3.0))  # (integral: no class)
    again = law_template(CUBIC.bind(k=7.0, c=3.0))  # another bound law, equal numbers
    assert len(calls) == 1 and again is first
    assert first == template_from_scratch(CUBIC.bind(k=7.0, c=3.0))


def test_the_law_key_tells_every_bit_apart():
    lin = get_law("linear_spring")
    assert law_key(lin.bind(k=2.0)) == law_key(lin.bind(k=2.0))
    assert law_key(lin.bind(k=2.0)) != law_key(lin.bind(k=math.nextafter(2.0, 3.0)))
    assert law_key(CUBIC.bind(k=1.0, c=0.0)) != law_key(CUBIC.bind(k=1.0, c=-0.0))
    assert law_key(CUBIC.bind(k=1.0, c=2.0)) != law_key(CUBIC.bind(k=2.0, c=1.0))
    assert law_key(object()) is None


def _chain(k: float, c: float, m2: float = 2.0) -> Scene:
    return Scene(
        [Mass("m", 1.0), Mass("n", m2)],
        [Element("d", get_law("bingham").bind(gamma=2.0, tau=1.5), "ground", "m"),
         Element("s", get_law("linear_spring").bind(k=k), "m", "n"),
         Element("c", CUBIC.bind(k=k, c=c), "ground", "n")],
    )


def test_a_structures_text_is_kept_and_equals_the_text_from_scratch():
    a, b = scene_source(_chain(3.5, 0.25)), scene_source(_chain(5.5, 0.75))
    assert a.source is b.source  # one text per structure
    assert not np.array_equal(a.consts, b.consts)
    jit._STRUCTURES.clear()
    templates._BY_LAW.clear()
    fresh = scene_source(_chain(5.5, 0.75))
    assert fresh.source == b.source and fresh.source is not b.source
    assert np.array_equal(fresh.consts, b.consts)
    assert (fresh.law_index, fresh.offsets) == (b.law_index, b.offsets)


def test_another_structure_gets_another_text():
    base = scene_source(_chain(3.5, 0.25)).source
    assert scene_source(_chain(3.5, 0.25, m2=3.0)).source is base  # a number
    flipped = Scene(
        [Mass("m", 1.0), Mass("n", 2.0)],
        [Element("d", get_law("bingham").bind(gamma=2.0, tau=1.5), "ground", "m"),
         Element("s", get_law("linear_spring").bind(k=3.5), "n", "m"),  # other ends
         Element("c", CUBIC.bind(k=3.5, c=0.25), "ground", "n")],
    )
    assert scene_source(flipped).source != base


def test_a_branchs_stage_root_is_read_once(monkeypatch):
    from lumped.codegen import branches

    calls = []
    flat_root = branches.flat_root
    monkeypatch.setattr(branches, "flat_root", lambda r: calls.append(r) or flat_root(r))
    residual = get_law("herschel_bulkley").bind(gamma=3.0, tau=2.0, n=2.0).kernel.expressions[0]
    lb = branches.LawBranches(residual)
    first = [lb.stage_guards_for(i) for i in range(lb.count)]
    read = len(calls)
    assert read >= 1  # (a branch without an inverse form reads its flat root)
    again = [lb.stage_guards_for(i) for i in range(lb.count)]
    assert len(calls) == read and all(a is b for a, b in zip(first, again, strict=True))
    fresh = branches.LawBranches(residual)  # from scratch: the same guards' values
    for q, F in ((0.1, 2.5), (-0.3, -2.2), (0.0, 0.5)):
        assert [fresh.stage_guards_for(i)(q, F) for i in range(lb.count)] == [
            g(q, F) for g in again]
