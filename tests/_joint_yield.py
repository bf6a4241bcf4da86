"""One mass held by three yield dashpots to ground (a Herschel-Bulkley ``n = 1``, a
Bingham and a shear-thickening Herschel-Bulkley ``n = 2``) under a constant load near the
sum of their yield forces: the 1960th draw of the ``LUMPED_LARGE`` tight-tolerance
property (issue 29), shared by the tests of loads beyond and within that sum."""

from __future__ import annotations

import itertools

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

TAUS = (0.024652579610771632, 1.0, 0.03594991084219946)
#: The sum of the yield forces as the balance adds them (in floating point).
JOINT = TAUS[0] + TAUS[1] + TAUS[2]
GAMMA_HB2 = 1.0000002302585358
M = 0.31622776601683794
X0 = -1.3356131035699072e-84
DT, T_END, RTOL, ATOL = 0.025 / 4, 0.5, 1e-10, 1e-13
PERMUTATIONS = list(itertools.permutations(range(3)))


def joint_yield_laws() -> list:
    """The three dashpots' laws (yield forces ``TAUS``)."""
    hb = get_law("herschel_bulkley")
    return [hb.bind(gamma=1.3282140456696148, tau=TAUS[0], n=1.0),
            get_law("bingham").bind(gamma=1.0, tau=TAUS[1]),
            hb.bind(gamma=GAMMA_HB2, tau=TAUS[2], n=2.0)]


def joint_yield_scene(load: float, order: tuple[int, ...] = (0, 1, 2),
                      spring: float = 0.0, x0: float = X0) -> Scene:
    """The scene, its dashpots ``e0, e1, e2`` in the law order ``order``; with ``spring >
    0`` a linear spring of that stiffness from ground to the mass as well (``s``)."""
    laws = joint_yield_laws()
    elements = [Element(f"e{k}", laws[i], "ground", "m0") for k, i in enumerate(order)]
    if spring:
        elements.append(Element("s", get_law("linear_spring").bind(k=spring), "ground", "m0"))
    return Scene([Mass("m0", m=M, x0=x0, v0=-7.931954298103801e-230)], elements, {"m0": load})
