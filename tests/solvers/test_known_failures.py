"""Known failures, kept as strict expected failures so that a fix shows (XPASS fails the
run: then drop the marker). Each names its diagnosis; see CHANGELOG "Known issues"."""

from __future__ import annotations

import pytest

from lumped import SolverError, simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene, SineBurst


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


def _string_between_two_herschel_bulkley_links() -> Scene:
    # a draw of the random-network suite at LUMPED_LARGE=2000 (bdf2, example 732; session
    # 14): a string between two masses, in parallel with a shear-thinning Herschel-Bulkley
    # link (n = 0.3), the first mass on a shear-thickening one (n = 2) to ground; the string
    # goes taut near t = 0.355 (radau5 bridges a stop there and finishes)
    hb = get_law("herschel_bulkley")
    return Scene([Mass("m0", m=1.0, x0=0.03, v0=-0.15255320740060307),
                  Mass("m1", m=2.1388827264253187, x0=-0.23474113247313055,
                       v0=1.4372197722803088),
                  Mass("m2", m=1.0, x0=1e-16, v0=-5.969384734197956e-279),
                  Mass("m3", m=1.0, x0=0.4204457137928099, v0=1.0632626670224887)],
                 [Element("e0", hb.bind(gamma=0.13213704058409728, tau=1.0, n=2.0),
                          "ground", "m0"),
                  Element("e1", get_law("string_spring").bind(k=1.0, L=0.027118745378267504),
                          "m0", "m1"),
                  Element("e2", get_law("linear_spring").bind(k=1.0), "ground", "m2"),
                  Element("e3", get_law("bingham").bind(gamma=1.0, tau=1.0), "m2", "m3"),
                  Element("e4", get_law("coulomb").bind(tau=0.040464348930028954,
                                                        r=39.34327808370772), "m3", "ground"),
                  Element("e5", hb.bind(gamma=0.6054672850903626, tau=0.0866247187423721,
                                        n=0.3), "m1", "m0")])


@pytest.mark.xfail(strict=True, raises=SolverError, reason=(
    "Newton fails at t = 0.375 where the string e1 locks beside the n = 0.3 "
    "Herschel-Bulkley link e5 (bdf2 at dt 0.025: diverged, residual 7.3e4 in e1; at dt "
    "0.0125 and bdf1: max_iters in a herschel_bulkley row); not diagnosed (session 14)"))
@pytest.mark.parametrize(("method", "dt"), [("bdf1", 0.025), ("bdf2", 0.025),
                                            ("bdf2", 0.0125)])
def test_a_string_locking_beside_a_shear_thinning_link_runs(method, dt):
    sol = simulate(_string_between_two_herschel_bulkley_links(), method=method, dt=dt,
                   t_end=0.5)
    assert sol.ok


def _loaded_string_chain() -> Scene:
    # a draw of the random-network suite's tight-tolerance check at LUMPED_LARGE=300
    # (issue 29): a chain of strings (ground - m0 - m1) and a string from ground to m3,
    # m1 tied to m2 by a spring and a Herschel-Bulkley n = 0.8 link, a sine burst on m1.
    # Unloaded, or at rtol 1e-10 with atol 1e-12, or at rtol 1e-9 it runs through; bdf1
    # and bdf2 pass the suite's checks on it
    string = get_law("string_spring")
    return Scene(
        [Mass("m0", m=0.4201702417518112, x0=-3.141099492883003e-250,
              v0=0.026714769789581094),
         Mass("m1", m=0.18571427732261467, x0=4.859632342139496e-263,
              v0=0.07226945714490585),
         Mass("m2", m=1.706516750708603, x0=0.001, v0=1.8244802830876417),
         Mass("m3", m=9.671948270867205, x0=-0.27078910260744926, v0=0.001)],
        [Element("e0", string.bind(k=15.862217459807617, L=0.18922035336843843), "ground",
                 "m0"),
         Element("e1", string.bind(k=5.166956371383977, L=0.01), "m0", "m1"),
         Element("e2", get_law("linear_spring").bind(k=0.4400038037639899), "m1", "m2"),
         Element("e3", string.bind(k=1.0, L=0.05506977693959426), "ground", "m3"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=0.14617915919865815, tau=0.1,
                                                        n=0.8), "m2", "m1")],
        {"m1": SineBurst(amplitude=1.936983360451386, omega=1.6104068096704158,
                         t_off=0.313764147268767)})


@pytest.mark.xfail(strict=True, raises=SolverError, reason=(
    "radau5 at rtol 1e-10, atol 1e-13: both strings of the chain go taut at t = 0.19476 "
    "(impacts of e0 and e1), the step falls below its floor there, and the backward-Euler "
    "bridge's Newton cannot bring e1's lock row below 8.7e-18 in 300 iterations, under "
    "one ulp (2.8e-17) of the positions it is computed from: the lock row's round-off "
    "scale, as for the taut string on a stuck junction above (issue 29)"))
def test_radau5_at_a_tight_tolerance_on_a_loaded_string_chain_runs():
    sol = simulate(_loaded_string_chain(), method="radau5", t_end=0.2, rtol=1e-10,
                   atol=1e-13, compiled=False)
    assert sol.ok


def _loaded_at_the_summed_yield_force() -> Scene:
    # a draw of the random-network suite at LUMPED_LARGE=1000 (radau5, Python loop; issue
    # 29), reduced: one mass on two Bingham dashpots to ground, loaded by exactly the sum
    # of their yield forces (0.1 + 0.125 = 0.225, exact in binary). The mass stays at rest
    # (bdf1 and bdf2 keep it there); a load below the sum (0.2) runs at once
    bingham = get_law("bingham")
    return Scene([Mass("m", m=1.0)],
                 [Element("a", bingham.bind(gamma=1.0, tau=0.1), "ground", "m"),
                  Element("b", bingham.bind(gamma=1.0, tau=0.125), "ground", "m")],
                 {"m": 0.225})


@pytest.mark.xfail(strict=True, raises=SolverError, reason=(
    "radau5 lands again and again on the break-out guards of two yielding dashpots in "
    "parallel whose summed yield force the load meets exactly (about 38 passes of the "
    "loop an accepted step, t = 4.8e-4 after 10 000): its work budget stops it "
    "(Status.MAX_ITERS, after 5 s by default; when max_steps counted accepted steps only, "
    "1e6 of them took some 4e7 passes, hours). Not diagnosed. The draw had three yielding "
    "links and a dashpot on one mass, its load their summed yield force (issue 29)"))
@pytest.mark.parametrize("compiled", [False, True])
def test_a_load_at_the_summed_yield_force_of_parallel_dashpots_runs(compiled):
    # (max_steps = 2000: the same stop in 1 s)
    sol = simulate(_loaded_at_the_summed_yield_force(), method="radau5", t_end=0.5,
                   compiled=compiled, max_steps=2000)
    assert sol.ok
