"""Known failures, kept as strict expected failures so that a fix shows (XPASS fails the
run: then drop the marker). Each names its diagnosis; see CHANGELOG "Known issues"."""

from __future__ import annotations

import pytest

from lumped import SolverError, simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene


def _string_to_a_held_junction() -> Scene:
    # a loaded mass on a string to a junction held by Coulomb friction and a dashpot: the
    # load (2.65) is below the friction's yield (3.94), so the mass comes to rest with the
    # string taut and the junction stuck (t = 1.3236)
    return Scene([Mass("m", m=1.0, v0=1.4061113287668847), Junction("j")],
                 [Element("s", get_law("string_spring").bind(k=0.19164306754609922,
                                                             L=0.22357337016105375), "j", "m"),
                  Element("d", get_law("coulomb").bind(tau=3.9413367058075166, r=1.0),
                          "ground", "j"),
                  Element("c", get_law("newtonian").bind(c=0.25034763590404496),
                          "ground", "j")],
                 {"m": 2.6517535238691945})


@pytest.mark.xfail(strict=True, raises=SolverError, reason=(
    "q = x_m - x_j lies on a lattice of spacing ulp(x_m) = 2.2e-16 that misses L by "
    "2.8e-17, and the spring row's round-off scale reads |q| = 0.22 rather than "
    "|x_m| + |x_j|: Newton cannot meet the test (session 13)"))
@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_a_taut_string_on_a_stuck_junction_at_rest_runs(method):
    sol = simulate(_string_to_a_held_junction(), method=method, dt=1e-4, t_end=1.5)
    assert sol.ok
    assert abs(sol.v["m"][-1]) <= 1e-9
