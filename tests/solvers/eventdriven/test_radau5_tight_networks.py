"""``radau5`` at ``rtol = 1e-10`` on loaded random networks that it used to bridge or stop
on (issue 29), each scene written out from the random-network strategy
(``benchmarks/tight_hunt.py`` draws seed ``s``); each runs through with no backward-Euler
bridge, as at ``rtol = 1e-6``."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _convergence import assert_within_bdf2s_own_error
from _lock_scenes import junction_on_springs_slipping_on_coulomb, spring_held_junction_beside_a_stop
from scipy.integrate import solve_ivp

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene, SineBurst


def _string_beside_a_flat_herschel_bulkley_link() -> Scene:
    # seed 274: a loaded mass m0 tied to m1 by a string (e3) beside a shear-thickening
    # Herschel-Bulkley link (e1, n = 2)
    hb = get_law("herschel_bulkley")
    return Scene(
        [Mass("m0", m=1.0, x0=-0.37624293996242686, v0=-1.77269902465682),
         Mass("m1", m=0.9999999999999686, x0=0.3280626156988069, v0=1.1860400812457152e-233)],
        [Element("e0", get_law("implicit_spring").bind(k=1.0, L0=0.46991011312735004,
                                                       F0=2.4975923322238236), "ground", "m0"),
         Element("e1", hb.bind(gamma=0.26969640567091646, tau=0.10816107742637955, n=2.0),
                 "m0", "m1"),
         Element("e2", hb.bind(gamma=0.6471675365679924, tau=0.9906610524904494, n=1.5),
                 "m1", "ground"),
         Element("e3", get_law("string_spring").bind(k=3.6150856881332056,
                                                     L=0.8043055556612337), "m0", "m1")],
        {"m0": 1.638745886928079})


def test_the_string_beside_a_flat_yielding_link_starts_from_the_yield_force():
    """The run of seed 274 started from e2's force 0.99066325, the mode probe's 2.2e-6
    beyond its yield force (m1's v0 = 1.2e-233 pinned the yield force of the other sign,
    which the chosen mode's law missed; :mod:`lumped.solvers.implicit.initial_slip`): e2
    (m1 to ground) starts at its yield force with the slip's sign, and the run needs no
    bridge."""
    sol = simulate(_string_beside_a_flat_herschel_bulkley_link(), method="radau5",
                   dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.F["e2"][0] == pytest.approx(0.9906610524904494, rel=1e-15)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_string_that_impacts_beside_a_flat_yielding_link_goes_slack_at_once(compiled):
    """At ``t = 0.0729808183`` the string e3 reaches its length while its ends separate: a
    plastic impact. After it the load and the springs pull the ends together (the balance
    of accelerations wants ``0.14`` of the string, below its ``k L = 2.9``), so the string
    goes slack at once and e1, at rest relative to its ends, slips from its yield force
    (``F = -tau - sqrt(-q / gamma)``). The mode choice's probe read the string taut from
    round-off and a stage solve found e1's mirror root beyond its yield force: the modes
    alternated with steps of ``1e-12`` s until the run stopped at its step floor and
    backward Euler bridged it (a strict expected failure before)."""
    scene = _string_beside_a_flat_herschel_bulkley_link()
    sol = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    impacts = [ev for ev in sol.events if ev.kind == "impact"]
    assert [ev.element for ev in impacts] == ["e3"]
    assert impacts[0].t == pytest.approx(0.0729808183, abs=1e-9)
    assert impacts[0].impulse > 0.0  # a string pulls
    # ... and goes slack at the same t: the record says so
    at = [(ev.element, ev.kind, ev.from_branch, ev.to_branch) for ev in sol.events
          if ev.t == impacts[0].t and ev.element == "e3"]
    assert at == [("e3", "impact", 0, 1), ("e3", "switch", 1, 0)], at
    # after the impact: the string slack (q < L, its spring's force) and e1 slipping
    # backwards beyond its yield force, at every output point
    k, L = 3.6150856881332056, 0.8043055556612337
    tau = 0.10816107742637955
    after = np.asarray(sol.t) > impacts[0].t
    q = np.asarray(sol.x["m1"])[after] - np.asarray(sol.x["m0"])[after]
    assert after.sum() >= 60 and np.all(q < L)
    np.testing.assert_allclose(np.asarray(sol.F["e3"])[after], k * q, rtol=1e-9)
    assert np.all(np.asarray(sol.F["e1"])[after] < -tau)


def test_the_tight_run_agrees_with_a_loose_one():
    # the same trajectory at rtol 1e-6 (no event there is in doubt): within its error
    scene = _string_beside_a_flat_herschel_bulkley_link()
    tight = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10,
                     atol=1e-13, compiled=False)
    loose = simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-6, atol=1e-9)
    for m in ("m0", "m1"):
        np.testing.assert_allclose(tight.x[m], loose.x[m], rtol=0.0, atol=1e-7)


def _hb(gamma: float, tau: float, n: float):
    return get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=n)


def _reversal_on_a_flat_dashpot() -> Scene:
    # seed 194: one mass under a constant load on a Herschel-Bulkley n = 2 dashpot, an
    # implicit spring and a Coulomb element; its velocity reverses at t = 0.1596569
    return Scene(
        [Mass("m0", m=2.6565687933920197, x0=-0.21046971942104764, v0=-1.7097946948874458)],
        [Element("e0", _hb(0.27963355412729224, 0.4412091524066749, 2.0), "ground", "m0"),
         Element("e1", get_law("implicit_spring").bind(k=9.40868042238207,
                                                       L0=0.0015935589511856228,
                                                       F0=5.879285344921708), "m0", "ground"),
         Element("e2", get_law("coulomb").bind(tau=0.3068528816816773, r=4.994123538547976),
                 "m0", "ground")],
        {"m0": 23.231273403190748})


def _flat_dashpot_beside_a_string() -> Scene:
    # seed 213: one mass on a string, a spring and a Herschel-Bulkley n = 2 dashpot under
    # a sine burst switched off at t = 0.4546
    from lumped.scene import SineBurst

    return Scene(
        [Mass("m0", m=3.9899789046560774, x0=-1.0, v0=-1.2129175679201702)],
        [Element("e0", get_law("string_spring").bind(k=38.61750789085946,
                                                     L=0.0515048670355757), "ground", "m0"),
         Element("e1", get_law("linear_spring").bind(k=68.00507898670062), "ground", "m0"),
         Element("e2", _hb(1.817817533995073, 1.0, 2.0), "m0", "ground")],
        {"m0": SineBurst(amplitude=431.4099384281861, omega=3.204603325404082,
                         t_off=0.4546168700249126)})


def _flat_link_between_two_masses() -> Scene:
    # seed 49: two masses joined by a Herschel-Bulkley n = 1.5 link beside a Newtonian one,
    # each held to ground by Coulomb friction, a constant load on m1
    return Scene(
        [Mass("m0", m=0.8666274162739471, x0=-5e-324, v0=-1.9728383359966308),
         Mass("m1", m=0.6521039562145671, x0=0.6380837067484215, v0=0.31529104260138086)],
        [Element("e0", get_law("coulomb").bind(tau=0.16015961405658938, r=18.114335354054283),
                 "ground", "m0"),
         Element("e1", _hb(1.6067472549655282, 1.0, 1.5), "m0", "m1"),
         Element("e2", get_law("newtonian").bind(c=0.06670007435404195), "m0", "m1"),
         Element("e3", get_law("coulomb").bind(tau=0.01518558690481843, r=11.99154758201777),
                 "m0", "ground")],
        {"m1": -2.952333662634861})


@pytest.mark.parametrize("scene", [_reversal_on_a_flat_dashpot, _flat_dashpot_beside_a_string,
                                   _flat_link_between_two_masses])
def test_a_dashpot_flat_at_its_yield_force_slips_on_without_a_bridge(scene):
    """A Herschel-Bulkley ``n > 1`` dashpot leaving its yield force (a velocity reversal
    under a load: ``F = tau + (q / gamma)^(1/n)``, flat in ``F`` at ``q = 0``). The step
    just after it is short (``3.5e-12`` s) and Newton's tolerance on forces is then wide
    (``1e-5`` of a yield force ``0.44``: a force error below it does not show in ``x``,
    ``v``), so the stage force read the slip's end in its guard ``F - tau > 0`` at a rate
    of ``2.6e-11``: a false event at once, then a stop at the step floor and a bridge.
    The guard of a branch flat at its end reads its rate now
    (:func:`lumped.codegen.stage_forms.flat_root`)."""
    sc = scene()
    tight = simulate(sc, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13,
                     compiled=False)
    assert tight.ok, tight.message
    assert tight.stats.get("bridges", 0) == 0, tight.message
    loose = simulate(sc, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-7, atol=1e-10)
    for m in (nd.name for nd in sc.nodes):
        np.testing.assert_allclose(tight.x[m], loose.x[m], rtol=0.0, atol=1e-6)


def _break_out_beside_a_slipping_junction() -> Scene:
    # seed 299: m1 held by a Herschel-Bulkley n = 0.3 dashpot under a sine burst from 0;
    # apart from it, m2 pulls the junction j0 through a Bingham link against a Coulomb
    # element and a Herschel-Bulkley n = 2 dashpot, both slipping
    from lumped.scene import Junction, SineBurst

    return Scene(
        [Junction("j0", x0=-0.4493388199063352),
         Mass("m1", m=1.0, x0=-0.8093858571406134, v0=-1.9901902673742497e-265),
         Mass("m2", m=0.9101753972241203, x0=-4.393472556134144e-284, v0=1.3462318218299716)],
        [Element("e0", get_law("coulomb").bind(tau=1.0, r=4.188702165799558), "ground", "j0"),
         Element("e1", _hb(1.0023052380778996, 0.2766720230509037, 0.3), "ground", "m1"),
         Element("e2", get_law("bingham").bind(gamma=0.9999769744141629,
                                               tau=0.21148509565329432), "j0", "m2"),
         Element("e3", _hb(0.2541925035541346, 0.04027863975236504, 2.0), "ground", "j0")],
        {"m1": SineBurst(amplitude=-12.713856305975922, omega=13.666925321491332,
                         t_off=math.inf)})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_break_out_decided_by_a_long_probe_keeps_the_junction_at_t(compiled):
    """At ``t = 0.0015924`` the load on m1 reaches e1's yield force; probes of ``3e-10``
    and ``3e-7`` s read e1 still stuck (the load beyond the yield force is below their
    round-off), the one of ``3e-4`` s reads it slipping. That probe's junction velocity
    is j0's at ``t + 3e-4`` (``0.05388`` against ``0.05399`` at ``t``), which the state
    at ``t`` took: the forces at j0 jumped by ``4.5e-4`` at the step's start, every step
    was rejected down to the step floor and backward Euler bridged it. The mode a long
    probe decides now takes its junction velocities and forces from the first probe's
    size (:func:`lumped.solvers.modes.mode_guess.probe_state`)."""
    sc = _break_out_beside_a_slipping_junction()
    sol = simulate(sc, method="radau5", dt=0.01463386938139617 / 4, t_end=0.5121854283488659,
                   rtol=1e-10, atol=1e-13, compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.events[0].element == "e1" and sol.events[0].t == pytest.approx(0.0015924, abs=1e-7)
    # j0's balance at every output point: e0 (slipping at tau) + e3 = e2
    F = {e: np.asarray(sol.F[e]) for e in ("e0", "e2", "e3")}
    np.testing.assert_allclose(F["e0"] + F["e3"], F["e2"], rtol=0.0, atol=1e-9)


def _junction_stopping_on_two_steep_dashpots() -> Scene:
    # seed 374: the junction j1 held to ground by two Herschel-Bulkley n = 0.3 dashpots
    # (e1, e3) and pulled by m2 through an implicit spring (e2), under a sine burst on m2;
    # m0 is apart, on dashpots only
    hb = get_law("herschel_bulkley")
    return Scene(
        [Mass("m0", m=6.122963612261025, x0=0.6730236746110743, v0=-1.1065805147941068),
         Junction("j1", x0=-0.4997121867720419),
         Mass("m2", m=1.8171502897752574, x0=0.8468161039641338, v0=-1.2590352377112737)],
        [Element("e0", get_law("newtonian").bind(c=0.48247348595466244), "ground", "m0"),
         Element("e1", hb.bind(gamma=1.8727634113838452, tau=0.014397551368561884, n=0.3),
                 "ground", "j1"),
         Element("e2", get_law("implicit_spring").bind(k=1.0, L0=0.006542981771376858,
                                                       F0=1.0), "j1", "m2"),
         Element("e3", hb.bind(gamma=2.8170994613045766, tau=0.03153653723592915, n=0.3),
                 "j1", "ground"),
         Element("e4", get_law("bingham").bind(gamma=0.22544630146946573,
                                               tau=0.10174688416237884), "m0", "ground"),
         Element("e5", get_law("newtonian").bind(c=0.025579307286359657), "ground", "m0")],
        {"m2": SineBurst(amplitude=-0.6476809727668699, omega=1.0,
                         t_off=0.4958712796291407)})


def test_radau5_lands_on_a_junction_stopping_on_steep_dashpots_without_a_bridge():
    """The spring e2 pulling j1 falls to the sum of its two dashpots' yield forces at
    ``1.5 N/s``: j1 stops in finite time at ``t* = 0.46528152``, its velocity set by its
    balance through the dashpots' inverse forms, ``v ~ (F - tau)^0.3``. Near ``t*`` the
    forces' round-off (``7e-18``) moved that velocity by ``1e-14 .. 4e-14`` (``dv/dF =
    0.3 v / (F - tau) = 2000``), above the stage Newton's velocity test ``1e-3 (atol +
    rtol |v|) = 5e-15``: from ``5e-6`` s before ``t*`` every stage solve failed at its
    round-off (the corrections cycling there), the step fell to its floor and backward
    Euler bridged twice (a strict expected failure before). A junction's velocity now
    passes the test at the round-off its laws amplify
    (:mod:`lumped.solvers.radau.roundoff`); the run lands on the stop. Both loops, the
    same numbers bit for bit."""
    scene = _junction_stopping_on_two_steep_dashpots()
    runs = [simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10,
                     atol=1e-13, compiled=compiled) for compiled in (False, True)]
    for sol in runs:
        assert sol.ok, sol.message
        assert sol.stats.get("bridges", 0) == 0, sol.message
    sol, fast = runs
    for name in ("m0", "j1", "m2"):
        np.testing.assert_array_equal(np.asarray(fast.x[name]), np.asarray(sol.x[name]))
    # the stop: e3 sticks where the spring's force reaches the yield forces' sum (and
    # e1, whose rate is j1's too, at the same t, or held at its yield force until the
    # next event: which of the two the guards read first is round-off)
    stop = next(ev for ev in sol.events if ev.kind == "switch")
    assert stop.t == pytest.approx(0.46528152, abs=1e-8)
    assert "e3" in {ev.element for ev in sol.events if ev.t == stop.t}
    t = np.asarray(sol.t)
    F = {e: np.asarray(sol.F[e]) for e in ("e1", "e2", "e3")}
    np.testing.assert_allclose(F["e1"] - F["e3"], F["e2"], rtol=0.0, atol=1e-12)
    after = (t > stop.t) & (t < 0.4958712796291407)
    assert after.sum() >= 4 and np.all(np.asarray(sol.v["j1"])[after] == 0.0)
    # ... each stuck dashpot within its yield force
    assert np.all(np.abs(F["e1"][after]) <= 0.014397551368561884 * (1.0 + 1e-12))
    assert np.all(np.abs(F["e3"][after]) <= 0.03153653723592915 * (1.0 + 1e-12))


def test_the_stop_of_a_junction_on_steep_dashpots_agrees_with_bdf2():
    # bdf2 at dt / 32 and dt / 64 (its own error at dt / 64: their difference, 4e-6 at
    # j1, whose velocity ~ (t* - t)^0.3 bdf2 follows at first order, 4e-8 at the masses)
    scene = _junction_stopping_on_two_steep_dashpots()
    dt = 0.025 / 4
    sol = simulate(scene, method="radau5", dt=dt, t_end=0.5, rtol=1e-10, atol=1e-13)
    assert_within_bdf2s_own_error(scene, sol, ("m0", "j1", "m2"), dt, 0.5, 32)


def _junction_on_a_steep_dashpot_beside_a_bingham_junction() -> Scene:
    # seed 23: the junction j1 tied to m0 by a stiff implicit spring (e4) beside a
    # Herschel-Bulkley n = 0.3 dashpot (e1), m2 on a string under a sine burst, and the
    # junction j3 on a Bingham dashpot to ground
    return Scene(
        [Mass("m0", m=0.6601110606232546, x0=-0.0, v0=0.15806686887346055),
         Junction("j1", x0=0.49707607189094394),
         Mass("m2", m=6.163150560766638, x0=-0.43821309624802296, v0=-1.2711194010762457),
         Junction("j3", x0=1e-09)],
        [Element("e0", get_law("string_spring").bind(k=1.0, L=0.017161581244293563),
                 "ground", "m0"),
         Element("e1", get_law("herschel_bulkley").bind(gamma=1.1020425416966608, tau=0.1,
                                                        n=0.3), "m0", "j1"),
         Element("e2", get_law("string_spring").bind(k=22.428124246808057,
                                                     L=0.36395261778210747), "ground", "m2"),
         Element("e3", get_law("bingham").bind(gamma=0.9999999999999942,
                                               tau=0.5195164908099175), "ground", "j3"),
         Element("e4", get_law("implicit_spring").bind(k=5.240614430488878,
                                                       L0=0.8088635680026663,
                                                       F0=49.43323562011863), "m0", "j1"),
         Element("e5", get_law("linear_spring").bind(k=0.2944512267678015), "m2", "j3")],
        {"m2": SineBurst(amplitude=14.110867222515967, omega=7.410325461732834,
                         t_off=0.19027617256588175)})


def test_radau5_follows_a_junction_on_a_steep_dashpot_without_a_bridge():
    """Seed 23, the same kind as seed 374 above: 12 bridges, then a stop at the step floor
    after 64 s of CPU before the round-off test of a junction's velocity."""
    sol = simulate(_junction_on_a_steep_dashpot_beside_a_bingham_junction(), method="radau5",
                   dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message


def _two_strings_at_a_junction_on_a_dashpot() -> Scene:
    # a LUMPED_LARGE=1 draw of test_random_network_tight_tolerance (after 2166 passes):
    # the junction j0 held to ground by a light Newtonian dashpot (e0), met by two slack
    # strings (e3 to m3, e4 from m2) and a spring (e5 from m2), a sine burst on m2
    return Scene(
        [Junction("j0", x0=0.6296010537391945), Junction("j1", x0=1e-09),
         Mass("m2", m=1.0, x0=-2.225073858507203e-309, v0=3.901405947716668e-305),
         Mass("m3", m=0.37903204152837305, x0=1.0, v0=0.7286770384113068)],
        [Element("e0", get_law("newtonian").bind(c=0.04767909628035078), "ground", "j0"),
         Element("e1", get_law("newtonian").bind(c=1.0), "ground", "j1"),
         Element("e2", get_law("linear_spring").bind(k=1.0), "ground", "m2"),
         Element("e3", get_law("string_spring").bind(k=1.0, L=1.3703989462608055),
                 "j0", "m3"),
         Element("e4", get_law("string_spring").bind(k=0.2814572724404816,
                                                     L=1.6296010537391945), "m2", "j0"),
         Element("e5", get_law("linear_spring").bind(k=1.0), "m2", "j0")],
        {"m2": SineBurst(amplitude=1.6407286362202407, omega=1.0, t_off=math.inf)})


def test_radau5_passes_a_junction_velocity_reversal_between_two_strings_without_a_bridge():
    """j0's velocity, ``v = F_e0 / c``, reverses at ``t = 0.0713``: there the strings'
    and the spring's forces (``0.59``, ``0.13``, ``0.46``) cancel at the junction to the
    dashpot's ``F_e0 ~ 0``, so one ulp of the balance moves the velocity by ``ulp / c =
    2.3e-15``. The stage Newton's corrections of j0's velocity cycled at ``1.16e-15``,
    above the test ``1e-3 (atol + rtol |v|) = 6.6e-16``, and the round-off floor read
    from the dashpot's row alone (``|F_e0| + c |v|``, near 0 there) did not lift it:
    every stage solve failed, backward Euler bridged 12 times from ``t = 0.071388`` and
    the run stopped at its step floor at ``t = 0.0720``. The dashpot's force is now taken
    at the rounding of the junction's balance (:mod:`lumped.solvers.radau.roundoff`)."""
    scene = _two_strings_at_a_junction_on_a_dashpot()
    dt = 0.025 / 4
    sol = simulate(scene, method="radau5", dt=dt, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.stats["rejected"] == 0
    v = np.asarray(sol.v["j0"])
    assert v[0] < 0.0 < v[-1]  # (the reversal is passed)
    # j0's balance: e0 = e3 - e4 - e5 (a force +F on a, -F on b; j0 is b of e0 and e4)
    F = {e: np.asarray(sol.F[e]) for e in ("e0", "e3", "e4", "e5")}
    np.testing.assert_allclose(F["e0"], F["e3"] - F["e4"] - F["e5"], rtol=0.0, atol=1e-12)
    # ... and agrees with bdf2 at dt / 32 within its own error
    assert_within_bdf2s_own_error(scene, sol, ("j0", "m2", "m3"), dt, 0.5, 16)


def _junction_on_a_stiff_spring_and_two_dashpots() -> Scene:
    # seed 346: the junction j0 held to ground by a stiff spring (e5, k = 97) and a
    # Herschel-Bulkley n = 1 dashpot (e0), pulled by m1 through a Newtonian dashpot (e1);
    # m1 and m2 joined by a Bingham link and a string, a constant load on m1
    return Scene(
        [Junction("j0", x0=-0.20217138345871333),
         Mass("m1", m=0.6311041379314297, x0=0.11140782311815767, v0=1.8234346782271862),
         Mass("m2", m=1.0, x0=0.17630429650635038, v0=-1.373175342743421)],
        [Element("e0", _hb(2.154434690031884, 0.1, 1.0), "ground", "j0"),
         Element("e1", get_law("newtonian").bind(c=5.7985248430108065), "j0", "m1"),
         Element("e2", get_law("bingham").bind(gamma=0.7414048798085399,
                                               tau=0.33562481622494755), "m1", "m2"),
         Element("e3", get_law("string_spring").bind(k=1.0, L=0.023594244663493184),
                 "m2", "m1"),
         Element("e4", get_law("coulomb").bind(tau=0.3635471438348037, r=1.0),
                 "m2", "ground"),
         Element("e5", get_law("linear_spring").bind(k=97.20928943554951), "j0", "ground")],
        {"m1": -207.51238123919384})


def test_radau5_stops_a_junction_between_large_cancelling_forces_without_a_bridge():
    """Seed 346, the same cause as the reversal above: from ``t = 0.3617`` j0 slows to a
    stop on e0 while e1 and e5 carry ``-180.5`` and ``180.4`` N, which cancel at j0 to
    e0's ``-0.10``: the corrections of j0's velocity cycled at ``1e-15 .. 5e-15`` (the
    balance's ulp, ``2.8e-14``, over e0's slope) above the test's ``1.2e-15``; 12 bridges,
    then a stop at the step floor at ``t = 0.3671``."""
    scene = _junction_on_a_stiff_spring_and_two_dashpots()
    dt, t_end = 0.016032609881584677, 0.5130435162107096
    sol = simulate(scene, method="radau5", dt=dt / 4, t_end=t_end, rtol=1e-10, atol=1e-13,
                   compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    # e0 sticks (its branch 2, rate 0) and slips again (branch 0) in 0.362 .. 0.367
    stops = [(ev.element, ev.to_branch) for ev in sol.events if 0.36 < ev.t < 0.37]
    assert stops == [("e0", 2), ("e0", 0)], stops
    F = {e: np.asarray(sol.F[e]) for e in ("e0", "e1", "e5")}
    np.testing.assert_allclose(F["e1"] + F["e5"], F["e0"], rtol=0.0, atol=1e-9)
    assert_within_bdf2s_own_error(scene, sol, ("j0", "m1", "m2"), dt / 4, t_end, 4)


def _mass_breaking_out_a_hair_from_the_origin() -> Scene:
    # m1 of seed 68 alone: a constant load beyond the yield forces of a Coulomb element
    # and a Herschel-Bulkley n = 1.5 dashpot, from rest a hair (2e-15) from the origin
    return Scene(
        [Mass("m1", m=0.24814255310164568, x0=2e-15, v0=0.0)],
        [Element("e1", _hb(0.9999769744141629, 0.017172936580817665, 1.5), "ground", "m1"),
         Element("e6", get_law("coulomb").bind(tau=0.9999999999999994, r=7.397929212653803),
                 "m1", "ground")],
        {"m1": 3.592123679239016})


def test_radau5_starts_with_a_step_the_loop_takes():
    """The first step's estimate (scipy's ``0.01 d0 / d1``) read the position ``2e-15``,
    below its tolerance ``atol = 1e-13``, against the acceleration ``10.4 / atol``: a
    step of ``3.0e-19``, below the step floor ``1.8e-18`` of a run to ``0.5``. The run
    stopped before its first step, 12 times over (backward Euler bridging ``1e-22 ..
    6e-20`` s each), then for good. The first step is now at least the floor."""
    sol = simulate(_mass_breaking_out_a_hair_from_the_origin(), method="radau5",
                   dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    # the mass slips from the start: m a = f - tau_c - F_e1, F_e1 -> its yield force
    v = np.asarray(sol.v["m1"])
    assert np.all(np.diff(v) > 0.0)
    loose = simulate(_mass_breaking_out_a_hair_from_the_origin(), method="radau5",
                     dt=0.025 / 4, t_end=0.5, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(sol.x["m1"], loose.x["m1"], rtol=0.0, atol=1e-6)


@pytest.mark.parametrize("compiled", [False, True])
def test_a_junction_held_by_springs_alone_while_its_coulomb_link_slips(compiled):
    """While e0 slips its law's row is ``F + tau`` (``dR/dq = 0``): only the springs'
    rows ``F_k = F_n + h sum_l a_kl k (V_m - V_j)_l`` hold the junction's velocity, to
    one ulp of their forces over ``h a k`` (``1e-13`` at ``h = 6e-3``), above the stage
    Newton's test ``1e-3 (atol + rtol |v|) = 7e-14`` at ``rtol = 1e-10``. Every stage solve
    from ``t = 0.35387`` failed, more so as the step shrank: the run crept, backward Euler
    bridged it twice and it stopped on its work budget after 15 000 rejected steps (the
    junction velocity's test now floored at the springs' round-off,
    :mod:`lumped.solvers.radau.roundoff`)."""
    scene = junction_on_springs_slipping_on_coulomb()
    dt = 0.025
    sol = simulate(scene, method="radau5", dt=dt, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled, max_steps=5_000)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.stats["rejected"] <= 10, sol.stats
    # e0 slips from t = 0.148 on at its yield force, the junction's springs carry it
    assert [ev.element for ev in sol.events] == ["e0"]
    after = np.asarray(sol.t) > sol.events[0].t
    np.testing.assert_allclose(np.asarray(sol.F["e0"])[after], -1.0, rtol=1e-9)
    assert_within_bdf2s_own_error(scene, sol, ("j0", "m1"), dt, 0.5, 4)


def _equal_coulombs_in_series() -> Scene:
    # a draw of the LUMPED_LARGE tight run (session 25, seed 22040 of ``long``, after 200
    # passing), shrunk: two Coulomb elements of one tau in series through the junction
    # j0, a spring across each, a Bingham dashpot on the mass
    coulomb = get_law("coulomb").bind(tau=0.7233941627366748, r=1.0)
    return Scene(
        [Junction("j0", x0=-0.109375), Mass("m1", m=4.067944321083047, x0=-0.15625,
                                               v0=0.109375)],
        [Element("e0", coulomb, "ground", "j0"),
         Element("e1", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "m1"),
         Element("e2", get_law("linear_spring").bind(k=0.31622776601683794), "ground", "j0"),
         Element("e3", coulomb, "j0", "m1"),
         Element("e4", get_law("linear_spring").bind(k=0.6493816315762113), "j0", "m1")])


@pytest.mark.parametrize("compiled", [False, True])
def test_two_equal_coulomb_elements_slipping_in_series_leave_the_junction_to_its_springs(
        compiled):
    """From ``t = 0.198`` both Coulomb elements slip at ``tau``: the junction's balance
    ``tau + k_2 x_j = tau + k_4 (x_m - x_j)`` holds its position (an index-2 velocity,
    ``v_j = k_4 v_m / (k_2 + k_4)``), which only the springs' rows of the stage system
    carry. At ``rtol = 1e-10`` their rounding (one ulp over ``h a_kl k``) exceeded the
    velocity's tolerance on every step shorter than ``0.03``: every stage solve failed
    from ``t = 0.2325`` down to ``h = 4e-15`` and the run stopped after 12 bridges by
    backward Euler (the springs' floor now holds beyond that tolerance except on the
    first step after an impact, :mod:`lumped.solvers.radau.roundoff`)."""
    scene = _equal_coulombs_in_series()
    dt = 0.0125
    sol = simulate(scene, method="radau5", dt=dt, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.stats["rejected"] <= 20, sol.stats
    start = [ev.t for ev in sol.events if ev.element == "e3"][0]
    end = min(ev.t for ev in sol.events if ev.element == "e0")
    assert 0.19 < start < 0.21 and 0.24 < end < 0.27, sol.events
    ts = np.linspace(start, end, 101)[1:-1]
    y = sol.sol(ts)
    col = sol.columns.index
    tau = 0.7233941627366748
    np.testing.assert_allclose(y[:, col("F_e0")], tau, rtol=1e-12)
    np.testing.assert_allclose(y[:, col("F_e3")], tau, rtol=1e-12)
    k2, k4 = 0.31622776601683794, 0.6493816315762113
    # (the dense output of an index-2 velocity on the first step, h = 0.018: it starts
    # from the event probe's velocity of j0, off by the positions' rounding over the
    # probe, a few ulp(x) / h_p; 2.6e-9 (1.6e-7 relative) from the start as it was, 5.6e-8
    # (3.5e-6) from the start's junctions at t = 0, which moves the event's state by
    # round-off)
    np.testing.assert_allclose(y[:, col("v_j0")], k4 / (k2 + k4) * y[:, col("v_m1")],
                               rtol=5e-6, atol=1e-12)
    assert_within_bdf2s_own_error(scene, sol, ("j0", "m1"), dt, 0.5, 4)


def test_a_spring_held_junction_runs_through_a_stop_and_a_break_out_beside_it():
    """j0's velocity is held by its spring's row alone (its Coulomb link slips), to less
    than the spring's rounding (its ends far from its force); j3's Herschel-Bulkley
    dashpot stops in finite time and breaks out again. The run crawled through bridges by
    backward Euler for 30 minutes; with the index-2 tolerance of j0's velocity (also on
    the first step after j3's break-out, an event that is no impact) it runs through with
    no bridge, both loops bit for bit (:mod:`lumped.solvers.radau.roundoff`)."""
    scene = spring_held_junction_beside_a_stop()
    sols = [simulate(scene, method="radau5", dt=0.025, t_end=0.5, rtol=1e-10, atol=1e-13,
                     compiled=compiled) for compiled in (False, True)]
    for sol in sols:
        assert sol.ok, sol.message
        assert sol.stats.get("bridges", 0) == 0, sol.message
    assert np.array_equal(sols[0].data, sols[1].data)
    assert [ev.element for ev in sols[0].events if ev.element == "e4"] == ["e4", "e4"]


def _junction_hung_on_a_loaded_mass_by_stuck_dashpots() -> Scene:
    # seed 22042 of the long profile, draw 3631, shrunk (two slack strings dropped): the
    # junction j1 slips on e1 (Herschel-Bulkley n = 1.5, flat at its yield force) while
    # e3 and e4 in parallel hold it to the loaded mass m2
    hb = get_law("herschel_bulkley")
    return Scene(
        [Junction("j1", x0=1e-08), Mass("m2", m=7.83640712338274)],
        [Element("e1", hb.bind(gamma=0.5364445264145451, tau=0.02433199029053824, n=1.5),
                 "ground", "j1"),
         Element("e3", hb.bind(gamma=0.1, tau=0.11065334455818125, n=1.0), "j1", "m2"),
         Element("e4", get_law("bingham").bind(gamma=5.2343753905899035,
                                               tau=0.07224799472467348), "m2", "j1")],
        {"m2": 1.207233329573393})


@pytest.mark.parametrize("compiled", [False, True])
def test_a_mode_kept_by_every_probe_takes_the_shortest_probes_state(compiled):
    """At the guard event at ``t = 1e-14`` the full laws' probes of ``2.2e-13`` (diverged),
    ``2.2e-10`` and ``2.2e-7`` s all keep the mode; the run took the longest one's state,
    ``v_j1 = 3.4e-8`` against the mass's ``1.5e-15`` (e3 and e4 stuck tie them): the
    collocation polynomial from that start dipped through e1's guard just after ``c_1 h``
    on every step, however short, and the run stopped after 12 bridges (41 s). The
    shortest probe's state: 215 steps. Until e3 and e4 break out (e1's force reaching
    their joint yield force ``tau_3 + tau_4``), ``m v' = P - tau_1 - (v / gamma_1)^(1/n)``
    with ``v_j1 = v``."""
    scene = _junction_hung_on_a_loaded_mass_by_stuck_dashpots()
    sol = simulate(scene, method="radau5", t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    m, P = 7.83640712338274, 1.207233329573393
    gamma, tau, n = 0.5364445264145451, 0.02433199029053824, 1.5
    held = 0.11065334455818125 + 0.07224799472467348

    def rhs(t, y):
        return [y[1], (P - tau - (max(y[1], 0.0) / gamma) ** (1.0 / n)) / m]

    def breaks(t, y):
        return tau + (max(y[1], 0.0) / gamma) ** (1.0 / n) - held

    breaks.terminal = True
    ref = solve_ivp(rhs, (0.0, 0.5), [0.0, 0.0], method="DOP853", rtol=1e-13, atol=1e-16,
                    events=breaks, dense_output=True)
    t_break = ref.t_events[0][0]
    out = [ev for ev in sol.events if ev.element in ("e3", "e4")]
    assert out and out[0].t == pytest.approx(t_break, rel=1e-9), sol.events
    ts = np.linspace(0.0, t_break, 50)[1:-1]
    y, col = sol.sol(ts), sol.columns.index
    v = ref.sol(ts)[1]
    np.testing.assert_allclose(y[:, col("v_m2")], v, rtol=1e-9)
    np.testing.assert_allclose(y[:, col("v_j1")], y[:, col("v_m2")], rtol=1e-12, atol=1e-14)
    np.testing.assert_allclose(y[:, col("F_e1")], tau + (v / gamma) ** (1.0 / n), rtol=1e-8)
