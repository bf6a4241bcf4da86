"""Two junctions tied by a dashpot, one of them between springs (issue 29).

A draw of the tight property (seed 22131 of the ``long`` profile, after 492 passing
draws): junction ``j0`` on a Newtonian dashpot and a spring to ground, tied by another
Newtonian dashpot (``c = 0.0103``) to junction ``j2``, which a string's spring and an
implicit spring to a mass hold; no event in the whole run. At ``t = 0.219`` the two
springs at ``j2`` carry 0.075 and 0.0785 and the dashpot between the junctions their
difference: ``j2``'s balance rounds that force, and ``j0``'s velocity carries it over its
own dashpot's ``c``. The stage Newton's floor for ``j0``'s velocity read that force at
its own size: every stage solve cycled just above the floor (corrections of ``3.1e-16``)
down to the step floor, and after 12 bridges by backward Euler ``radau5`` stopped
(:func:`lumped.solvers.radau.roundoff.linked_balances` now reads it at ``j2``'s balance).
"""

from __future__ import annotations

import numpy as np
import pytest

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene


def _junctions_tied_by_a_dashpot() -> Scene:
    def law(name, **values):
        return get_law(name).bind(**values)

    return Scene(
        [Junction("j0", x0=-0.15694842188117542),
         Mass("m1", m=1.1852495388978972, x0=8.772748370431503e-83, v0=-1.069350749303468),
         Junction("j2", x0=-0.559189378777689)],
        [Element("e0", law("newtonian", c=0.022507622126104763), "ground", "j0"),
         Element("e1", law("string_spring", k=1.0, L=0.010289212884574834), "ground", "m1"),
         Element("e2", law("newtonian", c=0.010289212884574834), "j0", "j2"),
         Element("e3", law("linear_spring", k=1.0), "ground", "j0"),
         Element("e4", law("string_spring", k=1.0, L=1.0), "ground", "j2"),
         Element("e5", law("implicit_spring", k=1.0, L0=1.0, F0=1.0), "m1", "j2")])


@pytest.mark.parametrize("compiled", [False, True])
def test_junctions_tied_by_a_dashpot_run_through_at_a_tight_tolerance(compiled):
    scene = _junctions_tied_by_a_dashpot()
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled, max_steps=5000)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0 and sol.stats["rejected"] <= 10  # (0)
    assert sol.stats["steps"] <= 1300 and not sol.events  # (1051)
    ref = simulate(scene, method="bdf2", dt=0.025 / 64, t_end=0.5)
    late = sol.t >= 0.1  # (j0's first 0.03 s: a fast transient, bdf2's own error 1e-4)
    for name in ("j0", "m1", "j2"):
        off = np.abs(sol.x[name] - ref.x[name][::16])
        assert off.max() <= 5e-4 and off[late].max() <= 1e-7  # (1.1e-4, 2.9e-10)
