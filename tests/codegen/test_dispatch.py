"""The structure-generic kernels of :mod:`lumped.codegen.dispatch` against a scene module's.

``radau5``'s compiled loop calls ``branch_law``, ``branch_guards`` and ``active_branch``
compiled once for every scene, which reach each element's law template module
(:mod:`lumped.codegen.template_module`) through the header of the constants: at every
element, branch and point they give a scene module's values bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest

from lumped import Element, Junction, Mass, Scene, get_law
from lumped.bench.impact_scenes import impact_scene
from lumped.bench.network_scenes import bingham_chain
from lumped.codegen.dispatch import (
    HEADER_WIDTH,
    active_branch_address,
    dispatch_addresses,
    dispatch_scene,
)
from lumped.codegen.function_types import branch_type, function_at, guards_type, law_type
from lumped.codegen.jit import jit_scene, njit, numba_enabled
from lumped.codegen.template_module import template_addresses
from lumped.codegen.templates import law_template

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the kernels need numba")

if numba_enabled():
    _law_at, _guards_at = function_at(law_type()), function_at(guards_type())
    _branch_at = function_at(branch_type())


@njit(cache=True)
def _through(law, guards, branch, e, i, q, F, c, out):
    """The three kernels at their addresses (as the compiled loop calls them)."""
    R, Rq, RF = _law_at(law)(e, i, q, F, c)
    k = _guards_at(guards)(e, i, q, F, out, c)
    return R, Rq, RF, k, _branch_at(branch)(e, q, F, c)


def _mixed() -> Scene:
    """Coulomb, a string, an S-shaped spring and a Bingham dashpot through a junction."""
    return Scene([Mass("m", m=1.0, x0=0.1), Junction("j"), Mass("n", m=0.5, x0=0.0)],
                 [Element("c", get_law("coulomb").bind(tau=0.3, r=1.0), "ground", "m"),
                  Element("s", get_law("string_spring").bind(k=20.0, L=0.2), "m", "j"),
                  Element("b", get_law("bingham").bind(gamma=2.0, tau=0.4), "j", "n"),
                  Element("z", get_law("s_shaped").bind(q0=1.0, F0=1.0), "ground", "n")])


@pytest.mark.parametrize("make", [lambda: bingham_chain(3), impact_scene, _mixed],
                         ids=["chain-3", "impact", "mixed"])
def test_the_generic_kernels_are_the_scene_modules_bit_for_bit(make):
    scene = make()
    js, jg = jit_scene(scene), dispatch_scene(scene)
    module = js.module
    law, guards = dispatch_addresses()
    branch = active_branch_address()
    E = len(scene.elements)
    # the header: each element's template's addresses and where its constants start
    for e, el in enumerate(scene.elements):
        row = jg.consts[HEADER_WIDTH * e:HEADER_WIDTH * (e + 1)]
        assert tuple(int(v) for v in row[:3]) == template_addresses(law_template(el.law))
        assert int(row[3]) == HEADER_WIDTH * E + js.offsets[e]
    assert np.array_equal(jg.consts[HEADER_WIDTH * E:], js.consts)
    rng = np.random.default_rng(7)
    points = np.concatenate([rng.normal(0.0, 1.0, (40, 2)), rng.normal(0.0, 1e-3, (10, 2)),
                             [[0.0, 0.0], [0.2, 0.3], [-0.2, -0.3], [0.0, 0.4]]])
    out, ref = np.zeros(16), np.zeros(16)
    checked = 0
    for e in range(E):
        for i in range(module.branch_count(e)):
            for q, F in points:
                got = _through(law, guards, branch, e, i, q, F, jg.consts, out)
                want = module.branch_law(e, i, q, F, js.consts)
                k = module.branch_guards(e, i, q, F, ref, js.consts)
                assert np.array_equal(got[:3], want, equal_nan=True), (e, i, q, F)
                assert got[3] == k and np.array_equal(out[:k], ref[:k], equal_nan=True)
                assert got[4] == module.active_branch(e, q, F, js.consts)
                checked += 1
    assert checked >= 2 * len(points)  # (every branch of every element)
