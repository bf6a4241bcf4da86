"""Regressions found by the random-network property suite (issue 11), each scene written
out: consistent initial states at massless junctions, and their refusal by name.

Every consistent initial state is checked against the laws themselves: each element's
``R(q, F) = 0`` at the initial elongation (rate) and each junction's balance.
"""

from __future__ import annotations

import numpy as np
import pytest
from _yield_check import check_yield

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.implicit.initial_state import consistent_initial_state
from lumped.solvers.nonsmooth.junction_balance import force_range


def _assert_consistent(scene: Scene, v: list[float], F: list[float]) -> None:
    x = [nd.x0 for nd in scene.nodes]
    q = scene.elongations(x, v)
    for e, el in enumerate(scene.elements):
        R, Rq, RF = el.law.kernel(q[e], F[e])
        # Newton's residual test: rtol 1e-10 of the row's terms
        assert abs(R) <= 1e-9 * (abs(Rq * q[e]) + abs(RF * F[e])) + 1e-12, (el.name, R)
    net = scene.net_forces(0.0, F)
    for i, nd in enumerate(scene.nodes):
        if isinstance(nd, Junction):
            assert abs(net[i]) <= 1e-9 * (1.0 + max(abs(f) for f in F)), (nd.name, net[i])


def test_dashpot_between_a_moving_mass_and_a_junction():
    """The dashpot's initial rate is ``v_m1(0) - v_j0``: the mass's own ``v0`` used to be
    left out (rate ``-v_j0``), so the Bingham force broke its law at ``t = 0`` and the
    property test saw it 'stuck above its yield force'."""
    scene = Scene(
        [Junction("j0", x0=-0.6697413259070863),
         Mass("m1", m=3.1924379244757684, x0=0.48551487434681895, v0=0.2347263776679429)],
        [Element("e0", get_law("newtonian").bind(c=1.0), "ground", "j0"),
         Element("e1", get_law("linear_spring").bind(k=1.0), "j0", "m1"),
         Element("e2", get_law("bingham").bind(gamma=1.000002302587744,
                                               tau=0.5464543382491791), "j0", "m1")])
    v, F, _ = consistent_initial_state(scene, time_scale=0.025)
    assert v[1] == 0.2347263776679429
    _assert_consistent(scene, v, F)
    # the first step continues the initial force (no jump of 0.12 as before)
    sol = simulate(scene, method="bdf1", dt=1e-4, t_end=1e-4)
    assert abs(sol.F["e2"][1] - sol.F["e2"][0]) < 1e-3


def test_herschel_bulkley_below_one_at_a_junction_initial_state():
    """Two junctions, each held by a Herschel-Bulkley ``n = 0.3`` dashpot to ground: the
    junction's velocity solves ``tau + |v|^(1/n) = load`` where ``dR/dF`` is unbounded
    near the yield force; Newton on the full system diverged, with every force on its own
    law (nonlinear elimination) it converges."""
    scene = Scene(
        [Junction("j0", x0=-0.8214456802661636),
         Mass("m1", m=3.9117442790871966, x0=-0.4407554400132171, v0=-0.9169750711037865),
         Mass("m2", m=0.2556443700171146, x0=0.0, v0=0.40235831165150016),
         Junction("j3", x0=0.0)],
        [Element("e0", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.07622720731997515,
                                                        n=0.3), "ground", "j0"),
         Element("e1", get_law("implicit_spring").bind(k=17.455596862395318,
                                                       L0=0.007783971084312072, F0=1.0),
                 "j0", "m1"),
         Element("e2", get_law("coulomb").bind(tau=0.12836919455914939,
                                               r=5.963315799144944), "j0", "m2"),
         Element("e3", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=0.3),
                 "ground", "j3"),
         Element("e4", get_law("bingham").bind(gamma=1.4656780887024323, tau=1.0), "j3", "m1"),
         Element("e5", get_law("string_spring").bind(k=1.0, L=1.0), "ground", "m2"),
         Element("e6", get_law("string_spring").bind(k=1.0, L=1.0), "j3", "m1")])
    v, F, _ = consistent_initial_state(scene, time_scale=0.025)
    _assert_consistent(scene, v, F)
    assert F[2] == -0.12836919455914939  # the Coulomb element slips backwards: -tau
    for method in ("bdf1", "bdf2"):
        sol = simulate(scene, method=method, dt=0.0125, t_end=0.5)
        assert sol.ok


def _spring_beyond_two_frictions(tau2: float) -> Scene:
    return Scene(
        [Junction("j0", x0=0.0), Mass("m1", m=0.658293436725718, x0=0.6555146683870468, v0=2.0)],
        [Element("e0", get_law("coulomb").bind(tau=0.17065955049643716, r=10.0), "ground", "j0"),
         Element("e1", get_law("implicit_spring").bind(k=83.19394860923276, L0=0.1, F0=1.0),
                 "j0", "m1"),
         Element("e2", get_law("coulomb").bind(tau=tau2, r=10.0), "m1", "j0")])


def test_spring_beyond_the_frictions_at_its_junction_is_refused_by_name():
    """The spring pulls the junction with 2.5 N, the two Coulomb elements there hold at most
    ``0.17 + 1``: no forces balance the junction (it would have to jump). This used to end
    in 'Newton failed (diverged)'; it is refused, naming the junction and the elements."""
    with pytest.raises(ValueError, match="inconsistent initial state") as info:
        simulate(_spring_beyond_two_frictions(1.0), method="bdf1", dt=1e-3, t_end=0.01)
    msg = str(info.value)
    assert "junction 'j0'" in msg and "'e0' ('coulomb'" in msg and "'e2' ('coulomb'" in msg
    # with strong enough friction the same state is consistent
    v, F, _ = consistent_initial_state(_spring_beyond_two_frictions(3.0), time_scale=1e-3)
    _assert_consistent(_spring_beyond_two_frictions(3.0), v, F)


def test_two_frictions_in_series_between_junctions_refused():
    """A cut through two junctions: the string spring's 1.9 N at ``j2`` against Coulomb
    elements of 0.019 and 0.013 N (found by the property suite)."""
    scene = Scene(
        [Mass("m0", m=0.6743417896569033, x0=-0.3170668239044251, v0=-1.296804247131086),
         Mass("m1", m=0.1590420118694413, x0=0.10835873644634009, v0=0.0),
         Junction("j2", x0=0.3565226499225125), Junction("j3", x0=-1.0)],
        [Element("e0", get_law("newtonian").bind(c=0.3489027375490963), "ground", "m0"),
         Element("e1", get_law("implicit_spring").bind(k=49.09553054265474,
                                                       L0=0.004710785643406155,
                                                       F0=8.86413652305611), "ground", "m1"),
         Element("e2", get_law("coulomb").bind(tau=0.018729660830781453,
                                               r=2.3558941599970122), "ground", "j2"),
         Element("e3", get_law("coulomb").bind(tau=0.013126657588633897,
                                               r=9.219319737177742), "j2", "j3"),
         Element("e4", get_law("bingham").bind(gamma=1.0, tau=0.06802381262814058), "m0", "j3"),
         Element("e5", get_law("string_spring").bind(k=37.75966069304012,
                                                     L=0.5048583838231933), "m0", "m1"),
         Element("e6", get_law("string_spring").bind(k=7.748297600531928,
                                                     L=0.24998540297724103), "m1", "j2")])
    with pytest.raises(ValueError, match="inconsistent initial state.*junction 'j2'"):
        simulate(scene, method="bdf2", dt=1e-3, t_end=0.01)


@pytest.mark.parametrize(("law", "params", "expected"), [
    ("coulomb", {"tau": 0.25, "r": 10.0}, (-0.25, 0.25)),
    ("bingham", {"gamma": 2.0, "tau": 0.25}, (-float("inf"), float("inf"))),
    ("herschel_bulkley", {"gamma": 2.0, "tau": 0.25, "n": 0.3}, (-float("inf"), float("inf"))),
    ("newtonian", {"c": 3.0}, (-float("inf"), float("inf"))),
])
def test_force_range_of_a_dashpot_at_some_rate(law, params, expected):
    lo, hi = force_range(get_law(law).bind(**params).kernel)
    assert (lo, hi) == pytest.approx(expected, rel=1e-15)


def test_force_range_at_a_fixed_elongation():
    string = get_law("string_spring").bind(k=2.0, L=0.5).kernel
    assert force_range(string, 0.5, 1.0) == (1.0, float("inf"))  # taut: F >= k L
    stuck = get_law("bingham").bind(gamma=2.0, tau=0.25).kernel
    assert force_range(stuck, 0.0, 0.0) == (-0.25, 0.25)


def _junction_of_five_dashpots() -> Scene:
    return Scene(
        [Junction("j0", x0=0.0), Mass("m1", m=1.0, x0=-1.0, v0=1.5606468215899714),
         Mass("m2", m=1.7782794100389228, x0=-0.7061852684569847, v0=0.11123692095274818)],
        [Element("e0", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=2.0),
                 "ground", "j0"),
         Element("e1", get_law("coulomb").bind(tau=1.0, r=1.0000000230258512), "j0", "m1"),
         Element("e2", get_law("coulomb").bind(tau=0.056055334808911325,
                                               r=1.7709886474076493), "ground", "m2"),
         Element("e3", get_law("bingham").bind(gamma=6.86434689232559,
                                               tau=0.02305106168698692), "m2", "j0"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=0.8106317434938142,
                                                        tau=0.8797579156045555, n=2.0),
                 "j0", "ground"),
         Element("e5", get_law("herschel_bulkley").bind(gamma=0.8106317434938142,
                                                        tau=0.012710501396889897, n=2.0),
                 "j0", "ground")])


def test_junction_of_five_dashpots_initial_state():
    """Five dashpots meet at one junction: its balance is one monotone equation in its
    velocity, with a unique root. Newton from the usual starts ended in 'no motion
    satisfies all the laws'; the junction's velocity from its balance solved by bisection
    (``balance_sweeps``) gives Newton a start it converges from."""
    scene = _junction_of_five_dashpots()
    v, F, _ = consistent_initial_state(scene, time_scale=0.025)
    _assert_consistent(scene, v, F)
    assert simulate(scene, method="bdf2", dt=0.0125, t_end=0.5).ok


def test_refusal_through_an_unloaded_junction():
    """``j3`` hangs on ``j0`` by a Newtonian dashpot alone, unloaded: its balance row has
    no terms of its own. It used to be weighted by ``1e300`` in the linear program, which
    then missed that ``j0``'s spring (0.24 N) exceeds its Coulomb element (0.024 N)."""
    scene = Scene(
        [Junction("j0", x0=0.23687463009672194),
         Mass("m1", m=1.2391583605961882, x0=0.1, v0=1e-06),
         Mass("m2", m=1.2589254117941673, x0=0.0, v0=-1.946432170701744),
         Junction("j3", x0=0.0)],
        [Element("e0", get_law("coulomb").bind(tau=0.023792800240715624, r=3.6027235136604525),
                 "ground", "j0"),
         Element("e1", get_law("linear_spring").bind(k=1.2589254117941673), "ground", "m1"),
         Element("e2", get_law("linear_spring").bind(k=1.0), "j0", "m2"),
         Element("e3", get_law("newtonian").bind(c=1.0), "j0", "j3")])
    with pytest.raises(ValueError, match="inconsistent initial state.*junction 'j0'"):
        simulate(scene, method="bdf1", dt=1e-3, t_end=0.01)


def _two_springs_on_a_friction(tau: float) -> Scene:
    # j1's two springs pull it the same way with 0.5 N each
    return Scene(
        [Mass("m0", m=1.0, x0=0.0, v0=0.0), Junction("j1", x0=0.5), Junction("j2", x0=0.0),
         Mass("m3", m=1.0, x0=0.0, v0=0.0)],
        [Element("e0", get_law("linear_spring").bind(k=1.0), "ground", "m0"),
         Element("e1", get_law("coulomb").bind(tau=tau, r=1.0), "ground", "j1"),
         Element("e2", get_law("newtonian").bind(c=1.0), "ground", "j2"),
         Element("e3", get_law("linear_spring").bind(k=1.0), "j1", "m3"),
         Element("e4", get_law("linear_spring").bind(k=1.0), "ground", "j1")])


@pytest.mark.parametrize("method", ["bdf1", "radau5"])
def test_a_hair_beyond_the_friction_is_refused_by_name(method):
    """The springs pull ``j1`` with 1.0 N, its Coulomb element holds ``1 - 2.7e-7`` (found
    by the ``LUMPED_LARGE`` radau5 run). The linear program's feasibility tolerance
    (1e-7) hid the 2.7e-7 imbalance from its old 1e-6 threshold: 'Newton failed
    (diverged)' at ``t = 0``. The gap is now measured on the forces put back in their
    ranges, against 1e-9; the same scene with ``tau = 1`` is consistent."""
    with pytest.raises(ValueError, match="inconsistent initial state.*junction 'j1'"):
        simulate(_two_springs_on_a_friction(0.9999997255105045), method=method, dt=1e-3,
                 t_end=0.01)
    scene = _two_springs_on_a_friction(1.0)
    v, F, _ = consistent_initial_state(scene, time_scale=1e-3)
    _assert_consistent(scene, v, F)


def _slow_mass_on_a_steep_yield() -> Scene:
    # found by the LUMPED_LARGE bdf1 run: m2 moves at 2^-23 through a Herschel-Bulkley
    # n = 0.3 link to j0, which another n = 0.3 dashpot ties to ground
    return Scene(
        [Junction("j0", x0=0.0), Junction("j1", x0=0.0),
         Mass("m2", m=1.0, x0=0.0, v0=1.192092896e-07), Mass("m3", m=1.0, x0=0.0, v0=0.0)],
        [Element("e0", get_law("newtonian").bind(c=1.0), "ground", "j0"),
         Element("e1", get_law("bingham").bind(gamma=1.0, tau=1.0), "j0", "j1"),
         Element("e2", get_law("linear_spring").bind(k=1.0), "ground", "m2"),
         Element("e3", get_law("linear_spring").bind(k=1.0), "ground", "m3"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=0.3),
                 "j0", "m2"),
         Element("e5", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.11302494859750127,
                                                        n=0.3), "ground", "j0"),
         Element("e6", get_law("linear_spring").bind(k=1.0), "ground", "j0")])


def test_a_yield_force_between_two_floats_at_a_moving_junction():
    """``j0`` must move with ``m2`` (``e4`` stuck, carrying what ``j0``'s dashpots to
    ground need): ``e5`` then slips at ``1.2e-7``, which an ``n = 0.3`` law allows at
    ``tau + (q / gamma)^(1/n) = tau + 1e-23``, between ``tau`` and the next float. No
    float has a smaller residual than ``q`` itself, so Newton read ``e5`` as stuck and
    settled ``j0`` at half ``m2``'s speed (both links' rates ``6e-8``): 'no consistent
    initial state'. The settled start of the cluster guess (``j0``, ``j1`` with ``m2``) is
    now kept when every law holds there to its round-off."""
    scene = _slow_mass_on_a_steep_yield()
    v, F, _ = consistent_initial_state(scene, time_scale=0.5)
    v_m2 = 1.192092896e-07
    assert v[:3] == [v_m2, v_m2, v_m2]
    tau5 = 0.11302494859750127
    # e5's root lies between its force and the next float up
    kernel = scene.elements[5].law.kernel
    assert F[5] == tau5 and kernel(v_m2, F[5])[0] * kernel(v_m2, np.nextafter(F[5], 1))[0] < 0
    assert F[0] == v_m2  # the Newtonian dashpot at j0's speed
    assert abs(F[4] - 0.113025) <= 1e-6  # e4 carries j0's load, within its yield force
    assert abs(F[1]) <= 1e-12 and F[2] == F[3] == F[6] == 0.0
    net = scene.net_forces(0.0, F)
    assert abs(net[0]) <= 1e-12 and abs(net[1]) <= 1e-12  # the junctions balance
    for method in ("bdf1", "bdf2"):
        sol = simulate(scene, method=method, dt=1e-3, t_end=0.05)
        assert sol.ok and np.all(np.isfinite(sol.x["m2"]))


# ---------------------------------------------------------------------------------------
# steps (the globalised solve: balance sweeps, free forces split, checked last correction)


def _four_dashpots_at_rest(v0: float = 7.271295973331632e-300) -> Scene:
    return Scene(
        [Mass("m0", m=1.0, x0=-0.762036820144262, v0=v0)],
        [Element("e0", get_law("bingham").bind(gamma=4.353057592343456,
                                               tau=0.010649302472488959), "ground", "m0"),
         Element("e1", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.9999999999999994,
                                                        n=0.3), "ground", "m0"),
         Element("e2", get_law("herschel_bulkley").bind(gamma=0.5547284437121088, tau=1.0,
                                                        n=2.0), "ground", "m0"),
         Element("e3", get_law("herschel_bulkley").bind(gamma=0.24532279088742764,
                                                        tau=0.12733226458031024, n=2.0),
                 "ground", "m0")])


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("v0", [7.271295973331632e-300, -0.25591956509194247])
def test_four_dashpots_in_parallel_come_to_rest(method, v0):
    """A mass on four dashpots to ground (Herschel-Bulkley n = 2 is flat in F at its
    yield force, n = 0.3 steep) comes to rest: all four stick, their forces are not
    unique. Newton crept along the flat law and ended in 'no motion satisfies all the
    laws'; the balance sweep finds v = 0, the free forces are split within their yield
    forces, and the run completes."""
    scene = _four_dashpots_at_rest(v0)
    sol = simulate(scene, method=method, dt=0.025, t_end=0.5)
    assert sol.ok
    v = sol.v["m0"]
    assert abs(v[-1]) <= 1e-12
    stuck = np.abs(v) <= 1e-12
    stuck[0] = False  # the initial forces are those of the initial (tiny) rate
    check_yield(scene, sol)  # within the yield forces, to Newton's own tolerance
    # at rest for the last two steps (BDF2's history), the forces balance (no inertia)
    total = sum(sol.F[el.name] for el in scene.elements)
    rest = stuck[2:] & stuck[1:-1] & stuck[:-2]
    assert rest.sum() >= 10 and np.all(np.abs(total[2:][rest]) <= 1e-9)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_junction_on_two_herschel_bulkley_in_parallel(method):
    """A junction held by Herschel-Bulkley n = 0.3 and n = 2 in parallel to a mass: the
    step's Newton diverged mid-run; the globalised solve completes."""
    scene = Scene(
        [Junction("j0", x0=-0.7689572851329782),
         Mass("m1", m=1.0, x0=-0.5121022573648716, v0=0.0),
         Mass("m2", m=0.11788397954976441, x0=0.0, v0=-0.6028301026485268)],
        [Element("e0", get_law("newtonian").bind(c=1.0), "ground", "j0"),
         Element("e1", get_law("linear_spring").bind(k=1.0000000002302585), "ground", "m1"),
         Element("e2", get_law("herschel_bulkley").bind(gamma=7.453825987360529,
                                                        tau=0.05784056333156519, n=0.8),
                 "j0", "m2"),
         Element("e3", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.14857730910506814,
                                                        n=0.3), "j0", "m1"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.030006262003269245,
                                                        n=2.0), "j0", "m1")])
    sol = simulate(scene, method=method, dt=0.02357679590995288, t_end=0.5186895100189634)
    assert sol.ok and np.all(np.isfinite(sol.data))


def test_coulomb_beside_a_stuck_dashpot_stays_within_its_yield_force():
    """Coulomb (tau ~ 1) and Herschel-Bulkley n = 1.5 in parallel between two masses, both
    stuck: the globalised solve's last correction (unevaluated) pushed the Coulomb force
    2.4e-8 beyond tau; a solution is now kept only where the residual test holds."""
    scene = Scene(
        [Mass("m0", m=1.499075613851422, x0=-0.11477249115637034, v0=-1.5503830736962936),
         Mass("m1", m=2.704576722066982, x0=0.2034593995948264, v0=-1.7420569884944603)],
        [Element("e0", get_law("implicit_spring").bind(k=1.000002302587744,
                                                       L0=0.019837972714233904,
                                                       F0=31.74116322012391), "ground", "m0"),
         Element("e1", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.07607304103585343,
                                                        n=1.5), "m0", "m1"),
         Element("e2", get_law("coulomb").bind(tau=0.9999769744141629, r=10.0), "m0", "m1"),
         Element("e3", get_law("implicit_spring").bind(k=1.0, L0=0.04752103097351587,
                                                       F0=25.474200917508327), "m0", "ground")])
    sol = simulate(scene, method="bdf2", dt=0.0125, t_end=0.5)
    assert sol.ok
    tau = 0.9999769744141629
    assert np.abs(sol.F["e2"]).max() <= tau * (1 + 1e-10) + 1e-12
