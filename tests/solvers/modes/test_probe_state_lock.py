"""The held-mode probe (:func:`lumped.solvers.modes.mode_guess.probe_state`) holds a taut
string on the velocity level, as the stage solve does (issue 29)."""

from __future__ import annotations

import math

from lumped import Element, Junction, Mass, Scene, get_law
from lumped.codegen.branches import law_branches
from lumped.scene.forcing_spec import ConstantForce
from lumped.solvers.modes.mode_guess import probe_state

TAU = 0.11449813609920753
X = [0.1256234201796847, 0.12662342027968465]  # 4.6e-17 short of L: below ulp(x)


def _dragged_junction() -> Scene:
    # m1 pulls the junction j0 by a taut string; j0 slips on a Herschel-Bulkley n = 0.3
    # dashpot to the ground
    law = get_law
    els = [Element("e0", law("herschel_bulkley").bind(gamma=1.0, tau=TAU, n=0.3),
                   "ground", "j0"),
           Element("e1", law("string_spring").bind(k=5.824914987394342, L=0.0010000001),
                   "j0", "m1")]
    return Scene([Junction("j0", x0=X[0]), Mass("m1", m=1.0, x0=X[1])], els,
                 {"m1": ConstantForce(13.0)})


def test_a_taut_string_short_of_its_length_by_rounding_moves_the_junction_with_its_mass():
    # the rounding of the positions, held by the lock, was a rate of ulp(x) / h_p between
    # j0 and m1 and a force of m ulp(x) / h_p^2: Newton cycled and the probe failed; the
    # junction then kept a longer probe's rate (h_p a, 5.7e-4) off the steps' (issue 29)
    sc = _dragged_junction()
    lbs = [law_branches(el.law) for el in sc.elements]
    for h_p in (4.3e-11, 1e-9, 1e-7):
        got = probe_state(sc, lbs, [0, 1], 0.0, X, [0.0, 0.0], [TAU, TAU], h_p)
        assert got is not None
        (v_j, v_m), (F0, F1) = got
        a = 13.0 - TAU  # (the dashpot at its yield force to rounding: (h_p a)^(1/n) ~ 0)
        assert v_j == v_m and math.isclose(v_m, a * h_p, rel_tol=1e-9)
        assert math.isclose(F0, TAU, rel_tol=1e-12) and math.isclose(F1, TAU, rel_tol=1e-12)
