"""The faithful port of ``jit-bdf1``/``jit-bdf2`` on the structure-generic step system
(:mod:`lumped.codegen.step_dispatch`) gives the scene module's numbers bit for bit.

The port takes ``evaluate`` and ``element_law`` from :mod:`lumped.codegen.step_dispatch`
(compiled once for every scene); a scene's generated module (:mod:`lumped.codegen.jit`)
defines the same two per structure, unrolled. Both do the same floating-point operations
in the same order on the same kernels, so every run here is made twice in one process,
once on each pair of callbacks, and the outputs (and counters and statuses) must be equal,
not close.
"""

from __future__ import annotations

import numpy as np
import pytest
from _lock_scenes import loaded_string_chain, two_strings_stopped_together
from hypothesis import HealthCheck, given, settings
from solvers.test_random_networks import grid, networks

from lumped import Element, Junction, Mass, Scene, get_law, simulate
from lumped.bench.network_scenes import bingham_chain
from lumped.codegen.jit import jit_scene, numba_enabled
from lumped.codegen.step_dispatch import STEP_WIDTH, step_callbacks, step_scene
from lumped.laws import ElementLaw
from lumped.scenarios import scenario_scene
from lumped.scene import SineBurst
from lumped.solvers.bdf import fixed_step_jit
from lumped.solvers.bdf.fixed_step_jit import Port, port_parts

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the generic port needs numba")

#: A user law (not a known monotone built-in: the port's fold check calls its kernel).
DRAG = ElementLaw("generic_port_drag", "dashpot", "F = c*q*Abs(q)", ["c"])


def _module_port(scene):
    js = jit_scene(scene)
    return js, Port(js.consts, lambda: (js.module.evaluate, js.module.element_law))


def _both(monkeypatch, run):
    """``run()`` on the generic callbacks, then on the scene module's."""
    got = run()
    with monkeypatch.context() as m:
        m.setattr(fixed_step_jit, "port_parts", _module_port)
        ref = run()
    return got, ref


def _same(got, ref) -> None:
    assert got.status == ref.status and got.message == ref.message
    assert got.stats == ref.stats
    assert np.array_equal(got.data, ref.data)


def _maxwell_drag() -> Scene:
    """A mass on a wall spring and, through a junction, a spring in series with the user
    drag law: a junction row, a ground end, a law that is not a built-in."""
    return Scene([Mass("mass", m=1.0, x0=0.1), Junction("j", x0=0.0)],
                 [Element("drag", DRAG.bind(c=0.7), "ground", "j"),
                  Element("spring", get_law("linear_spring").bind(k=50.0), "j", "mass"),
                  Element("wall", get_law("implicit_spring").bind(k=20.0, L0=0.3, F0=5.0),
                          "ground", "mass")],
                 {"mass": SineBurst(6.0, 4.0, 1.0)})


def _long_chain(n: int = 6) -> Scene:
    """``n`` masses in a chain on springs and Bingham dashpots: ``3 n`` unknowns, above
    the fast loop's 16 (the port alone runs it, also with ``fast=True``)."""
    nodes = [Mass(f"m{i}", m=1.0 + 0.1 * i) for i in range(n)]
    elements = []
    for i in range(n):
        a = "ground" if i == 0 else f"m{i - 1}"
        elements += [Element(f"s{i}", get_law("linear_spring").bind(k=30.0 + 5.0 * i), a,
                             f"m{i}"),
                     Element(f"d{i}", get_law("bingham").bind(gamma=0.5, tau=0.3), a,
                             f"m{i}")]
    return Scene(nodes, elements, {f"m{n - 1}": SineBurst(5.0, 6.0, 0.8)})


SCENES = {"forcing-F2": lambda: scenario_scene("forcing-F2"), "chain-3": lambda: bingham_chain(3),
          "maxwell-drag": _maxwell_drag, "chain-6": _long_chain}


def test_the_generic_port_has_no_module_of_the_structure():
    scene = bingham_chain(3)
    js, port = port_parts(scene)
    assert js.module is None
    width = STEP_WIDTH * len(scene.elements) + len(scene.nodes)
    assert not port.consts[:width].any()  # the header: written when the callbacks are made
    assert port.callbacks() == step_callbacks()
    assert np.array_equal(port.consts, step_scene(scene)[1])


@pytest.mark.parametrize("name", sorted(SCENES))
def test_the_step_system_is_the_scene_modules_bit_for_bit(name):
    scene = SCENES[name]()
    js = jit_scene(scene)
    _, c = step_scene(scene)
    evaluate, element_law = step_callbacks()
    N, E = len(scene.nodes), len(scene.elements)
    n = N + E
    rng = np.random.default_rng(7)
    for roundoff in (False, True):
        for _ in range(20):
            u = rng.normal(size=n) * 10.0 ** rng.integers(-3, 3, size=n)
            head = np.concatenate([[1e-3], rng.uniform(0.5, 2.0, N) * 1e3 * (js.masses != 0),
                                   rng.normal(size=3 * N)])
            out = []
            for ev, consts in ((evaluate, c), (js.module.evaluate, js.consts)):
                G, S, J = np.full(n, 7.0), np.full(n, 7.0), np.zeros((n, n))
                ev(u, np.concatenate([head, consts]), G, J, S, roundoff)
                out.append((G, S, J))
            for a, b in zip(*out, strict=True):
                assert np.array_equal(a, b)
            for e in range(E):
                q, F = rng.normal(size=2)
                assert element_law(e, q, F, c) == js.module.element_law(e, q, F, js.consts)


@pytest.mark.parametrize("method", ["jit-bdf1", "jit-bdf2"])
@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("fast", [False, True])
def test_runs_on_the_generic_port_are_the_scene_modules_bit_for_bit(monkeypatch, method,
                                                                      name, fast):
    scene = SCENES[name]()
    got, ref = _both(monkeypatch, lambda: simulate(scene, method=method, dt=2e-3, t_end=1.2,
                                                   fast=fast, throw=False))
    assert got.ok, got.message
    _same(got, ref)


def test_a_run_with_hand_overs_from_the_fast_loop_is_bit_for_bit(monkeypatch):
    # the user drag law at rest from the start: the fast loop hands a step over to the
    # port (its callbacks and constants are the generic ones too)
    got, ref = _both(monkeypatch, lambda: simulate(_maxwell_drag(), method="jit-bdf2",
                                                   dt=2e-3, t_end=1.2, fast=True))
    assert got.stats["handovers"] >= 1
    _same(got, ref)


@pytest.mark.parametrize("scene", [loaded_string_chain, two_strings_stopped_together])
@pytest.mark.parametrize("fast", [False, True])
def test_strings_across_impacts_are_bit_for_bit(monkeypatch, scene, fast):
    # the compiled chunks between the reference's impacts (lock_handover)
    got, ref = _both(monkeypatch, lambda: simulate(scene(), method="jit-bdf2", dt=1e-3,
                                                   t_end=1.0, fast=fast, throw=False))
    assert got.stats["reference_steps"] > 0 and got.stats["compiled_steps"] > 0
    _same(got, ref)


@settings(max_examples=6, deadline=None, derandomize=True,
          suppress_health_check=[HealthCheck.function_scoped_fixture,
                                 HealthCheck.too_slow])
@given(scene=networks())
def test_random_networks_are_bit_for_bit(monkeypatch, scene):
    # (each drawn structure compiles its scene module for the comparison: a few examples)
    dt, t_end = grid(scene)
    for method in ("jit-bdf1", "jit-bdf2"):
        got, ref = _both(monkeypatch, lambda m=method: simulate(
            scene, method=m, dt=dt, t_end=t_end, fast=False, throw=False))
        _same(got, ref)
