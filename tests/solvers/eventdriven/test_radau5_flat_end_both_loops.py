"""A mass that comes to rest at a Herschel-Bulkley ``n = 1.5`` dashpot's yield force, under
a load equal to it (seed 22818 of the property of both loops, issue 29): after its velocity
reverses it sits on the backward slip branch at that branch's flat end, where a step's
stage guess starts on the branch (:mod:`lumped.solvers.radau.flat_start`). The compiled
loop took such steps itself with the constant guess, so the two loops parted by round-off
(``1.2e-12`` in force, an event at ``t = 0.4887`` in one loop only); it now leaves them to
the Python loop (``loop_jit.FLAT``) and the two give the same numbers."""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.codegen.jit import numba_enabled
from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")


def _resting_at_the_yield_force() -> Scene:
    hb = get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=1.5)
    return Scene([Mass("m0", m=1.0, v0=1.0)], [Element("e0", hb, "ground", "m0")],
                 {"m0": -1.0})


@pytest.mark.parametrize("level", [0, 1, 2])
def test_both_loops_agree_at_a_flat_end(level):
    dt = 0.025 / 2**level
    runs = [simulate(_resting_at_the_yield_force(), method="radau5", dt=dt, t_end=0.5,
                     rtol=dt**2, atol=dt**3, compiled=compiled) for compiled in (False, True)]
    ours, compiled = runs
    assert ours.ok and compiled.ok
    assert compiled.stats["loop"] == "compiled"
    assert np.array_equal(ours.data, compiled.data)
    assert [(ev.t, ev.element, ev.kind) for ev in ours.events] == [
        (ev.t, ev.element, ev.kind) for ev in compiled.events]
    # at rest from the stop on (the load equals the yield force), at the velocity's
    # tolerance, the force at the yield force
    after = ours.t > 0.39
    assert np.abs(ours.v["m0"][after]).max() < 1e-12
    assert np.abs(np.abs(ours.F["e0"][after]) - 1.0).max() < 1e-9
