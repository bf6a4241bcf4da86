"""Scenes: validation errors that name the culprit, the DAE residual, forcing specs."""

from __future__ import annotations

import math

import pytest
import sympy
from _fake_laws import law

from lumped.scene import Element, Junction, Mass, Scene, SineBurst, as_forcing


def spring(name="spring", a="ground", b="mass", k=100.0):
    return Element(name, law("linear_spring", k=k), a, b)


def dashpot(name="dashpot", a="ground", b="mass"):
    return Element(name, law("bingham", gamma=1.0, tau=1.0), a, b)


def test_paper_scene_structure():
    sc = Scene([Mass("mass", 1.0, x0=0.5)], [spring(), dashpot()])
    assert sc.columns() == ("t", "x_mass", "v_mass", "F_spring", "F_dashpot")
    assert sc.elem_a == (-1, -1) and sc.elem_b == (0, 0)
    assert len(sc.laws) == 2


def test_scene_holds_only_its_laws():
    shared = law("linear_spring", k=3.0)
    sc = Scene([Mass("a", 1.0), Mass("b", 2.0)],
               [Element("s1", shared, "ground", "a"), Element("s2", shared, "a", "b")])
    assert len(sc.laws) == 1


@pytest.mark.parametrize(
    "nodes, elements, match",
    [
        ([Mass("mass", 1.0)], [spring(b="nowhere")], "unknown node 'nowhere'"),
        ([Mass("mass", 1.0)], [spring(a="mass", b="mass")], "joins node 'mass' to itself"),
        ([Mass("mass", 1.0)], [spring(a="ground", b="ground")], "to itself"),
        ([Junction("j")], [spring(b="j")], "at least one Mass"),
        ([Mass("mass", 1.0), Mass("mass", 2.0)], [], "duplicate node name 'mass'"),
        ([Mass("mass", 1.0)], [spring(), spring()], "duplicate element name 'spring'"),
        ([Mass("ground", 1.0)], [], "reserved"),
        ([Mass("mass", 1.0), Junction("j")], [spring()], "junction 'j' is not joined"),
    ],
)
def test_bad_scenes_name_the_culprit(nodes, elements, match):
    with pytest.raises(ValueError, match=match):
        Scene(nodes, elements)


def test_bad_node_and_element_values():
    with pytest.raises(ValueError, match="mass of node 'm'"):
        Mass("m", 0.0)
    with pytest.raises(ValueError, match="x0 of node 'm'"):
        Mass("m", 1.0, x0=math.nan)
    with pytest.raises(TypeError, match="bound law"):
        Element("e", "linear_spring", "ground", "m")
    with pytest.raises(ValueError, match="may contain only"):
        Mass("a b", 1.0)
    with pytest.raises(ValueError, match="unknown node 'zz'"):
        Scene([Mass("mass", 1.0)], [spring()], {"zz": 1.0})


def test_forcing_specs():
    t = sympy.Symbol("t")
    f = as_forcing(2 * sympy.sin(t))
    assert f(0.5) == pytest.approx(2 * math.sin(0.5), rel=1e-15)
    assert as_forcing(3.0)(7.0) == 3.0
    burst = SineBurst(1.0, 2.0, 1.0)
    assert as_forcing(burst) is burst
    with pytest.raises(ValueError, match="only depend on `t`"):
        as_forcing(sympy.Symbol("y") * t)
    with pytest.raises(TypeError, match="forcing"):
        as_forcing([1, 2])


def test_dae_residual_is_eqs_4a_to_4d():
    """m v' = F - F_s - F_d, x' = v, F_s = k x, Bingham law."""
    sc = Scene([Mass("mass", 2.0)], [spring(k=10.0), dashpot()], {"mass": 5.0})
    x, v, F = [0.3], [0.0], [3.0, 0.5]
    vdot = [(5.0 - 3.0 - 0.5) / 2.0]
    assert sc.dae_residual(0.0, x, v, [0.0], vdot, F) == pytest.approx([0, 0, 0, 0], abs=1e-15)
    G = sc.dae_residual(0.0, x, v, [0.0], [0.0], F)
    assert G[0] == pytest.approx(-(5.0 - 3.5))


def test_orientation_of_forces():
    """+F acts on a, -F on b: an element from the mass to ground pulls the other way."""
    sc = Scene([Mass("m1", 1.0), Mass("m2", 1.0)], [spring("s", a="m1", b="m2")])
    assert sc.net_forces(0.0, [2.0]) == [2.0, -2.0]
    assert sc.elongations([1.0, 1.5], [0.0, 0.0]) == [0.5]


@pytest.mark.parametrize("text", ["__import__('os').system('true')", "t.__class__",
                                  "(lambda: 1)()", "open('x')", "t" + "+t" * 5000,
                                  "(" * 200 + "t" + ")" * 200])
def test_hostile_forcing_strings_are_refused(text):
    with pytest.raises(ValueError, match="force on node 'mass'"):
        Scene([Mass("mass", 1.0)], [spring()], {"mass": text})


def test_forcing_string_is_compiled_safely():
    sc = Scene([Mass("mass", 1.0)], [spring()], {"mass": "2*sin(3*t) + Abs(t - 1)"})
    assert sc.forcing[0](0.5) == pytest.approx(2 * math.sin(1.5) + 0.5, rel=1e-15)


@pytest.mark.parametrize("value", [math.nan, math.inf, float("-inf"), "0.5", None])
def test_a_forcing_that_returns_no_finite_number_is_refused(value):
    # (a finite float takes a shortcut past the abstract-class check: the rest must not)
    scene = Scene([Mass("m", m=1.0)], [Element("s", law("linear_spring", k=1.0),
                                               "ground", "m")],
                  {"m": lambda t: value})
    with pytest.raises(ValueError, match="force on node 'm' returned"):
        scene.external_forces(0.5)


def test_a_forcing_may_return_any_real_number():
    import numpy as np

    for value in (0.25, np.float64(0.25), 1, np.int32(1), True):
        scene = Scene([Mass("m", m=1.0)], [Element("s", law("linear_spring", k=1.0),
                                                   "ground", "m")],
                      {"m": lambda t, value=value: value})
        got = scene.external_forces(0.5)
        assert got == [float(value)] and type(got[0]) is float
