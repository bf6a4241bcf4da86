"""Scenes drawn by the random-network suite that more than one test file runs (issue 29):
the loaded chain of strings of radau5's tight-tolerance check, a junction on springs
whose Coulomb link slips, one beside another junction's dashpot stopping, yield dashpots
slipping from rest at a junction held by a stuck one, and two junctions locked together by
a stuck dashpot while the one's dashpot to ground sticks and breaks out."""

from __future__ import annotations

import math

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene, SineBurst


def loaded_string_chain() -> Scene:
    # a draw of the random-network suite's tight-tolerance check at LUMPED_LARGE=300
    # (issue 29): a chain of strings (ground - m0 - m1) and a string from ground to m3,
    # m1 tied to m2 by a spring and a Herschel-Bulkley n = 0.8 link, a sine burst on m1;
    # both strings of the chain go taut at once at t = 0.19476
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


def junction_on_springs_slipping_on_coulomb() -> Scene:
    # the 3399th draw of the LUMPED_LARGE tight run (issue 29): a junction between two
    # springs (one to a loaded mass) held by a Coulomb element that slips from t = 0.148
    return Scene(
        [Junction("j0", x0=0.3617685522811145),
         Mass("m1", m=0.9092648455812927, x0=0.0, v0=-1.9246237940315574)],
        [Element("e0", get_law("coulomb").bind(tau=1.0, r=1.0), "ground", "j0"),
         Element("e1", get_law("linear_spring").bind(k=1.0), "ground", "m1"),
         Element("e2", get_law("linear_spring").bind(k=0.9999999999976974), "j0", "m1"),
         Element("e3", get_law("linear_spring").bind(k=1.0), "j0", "ground")],
        {"m1": SineBurst(amplitude=2.499999999998849, omega=1.0, t_off=math.inf)})


def spring_held_junction_beside_a_stop() -> Scene:
    # A draw of the ``LUMPED_LARGE`` tight run (session 25, seed 22039 of ``long``, draw 456):
    # junction j0 on a slipping Coulomb element and a spring to m1 whose ends sit far from
    # its force (its velocity an index-2 variable the springs' rows hold to less than
    # their rounding), junction j3's Herschel-Bulkley ``n = 0.8`` dashpot stopping in finite
    # time, a load on m2: ``radau5`` crawled through bridges for more than 30 minutes, then
    # stopped on its bridges' work budget (3.5 s, no bridge, since the index-2 scale of
    # :mod:`lumped.solvers.radau.roundoff`).
    return Scene(
        [Junction("j0", x0=-9.165015417625238e-13),
         Mass("m1", m=1.0, x0=7.352716816730862e-299, v0=-0.3878114301715043),
         Mass("m2", m=0.16297975469725767, x0=0.37451683983764616, v0=1.2821745797731507),
         Junction("j3", x0=-1.1125369292536007e-308)],
        [Element("e0", get_law("coulomb").bind(tau=0.015457028057135072, r=2.154434690031884),
                 "ground", "j0"),
         Element("e1", get_law("string_spring").bind(k=5.721343474396009, L=0.3164303725222444),
                 "j0", "m1"),
         Element("e2", get_law("linear_spring").bind(k=1.0), "m1", "m2"),
         Element("e3", get_law("newtonian").bind(c=0.05433652129603409), "m2", "j3"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=0.13895007859132505,
                                                        tau=0.01917904279590328, n=0.8),
                 "ground", "j3"),
         Element("e5", get_law("string_spring").bind(k=0.3093114588771922, L=0.2172821837380576),
                 "m2", "j3"),
         Element("e6", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.010241425498493753,
                                                        n=0.8), "m1", "m2")],
        {"m2": -3.5602049629881325})


def yield_slip_from_rest_at_a_held_junction() -> Scene:
    # the 3501st draw of the LUMPED_LARGE tight run (seed 22043): m0 at rest on a spring
    # to ground, pulled down past the joint yield force of the Herschel-Bulkley dashpots
    # e1 (n = 1.5) and e4 (n = 2), in parallel with the spring e3 from m0 to j1; j1 held
    # to ground by the stuck e2 (tau = 1, n = 0.3). At t = 0 e1 and e4 start slipping
    # from rest at their yield forces and e2 holds j1's balance, 0.512 < 1.
    hb = get_law("herschel_bulkley")
    return Scene(
        [Mass("m0", m=6.547881831672482, x0=0.846867998508825, v0=-6.825760428477066e-80),
         Junction("j1", x0=0.0)],
        [Element("e0", get_law("linear_spring").bind(k=32.500043010079736), "ground", "m0"),
         Element("e1", hb.bind(gamma=1.0, tau=0.9999999999976974, n=1.5), "m0", "j1"),
         Element("e2", hb.bind(gamma=1.0, tau=1.0, n=0.3), "j1", "ground"),
         Element("e3", get_law("linear_spring").bind(k=1.0), "m0", "j1"),
         Element("e4", hb.bind(gamma=1.0000000000000002, tau=0.3590082822589278, n=2.0),
                 "m0", "j1")])


def junctions_locked_by_a_stuck_dashpot() -> Scene:
    # A draw of the ``LUMPED_LARGE`` tight run (seed 22044, draw 5611): junctions j0 and j1
    # locked together by e1 (Herschel-Bulkley ``n = 0.3``, its force 0.4 .. 0.85 of its
    # yield force, stuck throughout), j0 on the Bingham dashpot e0 to ground, which slips,
    # sticks at ``t = 0.20484`` and breaks out backwards at ``t = 0.22573``, springs to
    # two masses, a sine burst on m2 up to ``t = 0.05``. Just after the break-out the
    # junctions' velocity (``1e-6``) carried e0's rounding, ``ulp(B) gamma = 7e-16``, above
    # the stage Newton's test ``1e-3 (atol + rtol |v|) = 1e-16``, where e1's row (``V_j1 -
    # V_j0 = 0``) floored both at ``1e-21``: ``radau5`` bridged 5 times and the work budget
    # stopped it at ``t = 0.2257586`` (:func:`lumped.solvers.radau.roundoff.linked_roundoff`).
    hb = get_law("herschel_bulkley")
    spring = get_law("linear_spring")
    return Scene(
        [Junction("j0", x0=-0.99999),
         Junction("j1", x0=-0.43344976148403436),
         Mass("m2", m=0.10000230261160267, x0=0.41572929332528274, v0=0.2194850500413712),
         Mass("m3", m=1.0000230261160268, x0=-1.175494351e-38, v0=0.3333333333333333)],
        [Element("e0", hb.bind(gamma=4.361695477664007, tau=0.034343951155054224, n=1.0),
                 "ground", "j0"),
         Element("e1", hb.bind(gamma=0.13105055149238326, tau=1.0, n=0.3), "j0", "j1"),
         Element("e2", spring.bind(k=1.0), "j0", "m2"),
         Element("e3", spring.bind(k=1.0), "j1", "m3"),
         Element("e4", spring.bind(k=1.0), "j1", "m2"),
         Element("e5", spring.bind(k=0.7394668943921522), "j0", "j1")],
        {"m2": SineBurst(amplitude=-0.49222144396399664, omega=1.0, t_off=0.05)})


def two_strings_stopped_together() -> Scene:
    # the 2618th draw of the LUMPED_LARGE tight run (seed 22045): m0 taut on the string e0
    # to ground, m1 pulled up by a load of 221 until the string e1 from m0 goes taut; both
    # move up until m0 reaches e0's length again and an impact stops both, the load keeping
    # both strings taut (tests/solvers/eventdriven/test_radau5_chain_impact.py)
    string = get_law("string_spring")
    return Scene(
        [Mass("m0", m=1.0, x0=0.6710605383456154, v0=1.5015005446176177),
         Mass("m1", m=1.0, x0=0.08534027660141175, v0=-1.4205672971659248e-99),
         Mass("m2", m=1.0, x0=7.82877556810346e-306, v0=2.1141156561281768e-55)],
        [Element("e0", string.bind(k=17.969410869328886, L=0.6720605383456154), "ground", "m0"),
         Element("e1", string.bind(k=76.98447979814374, L=0.03205626107396782), "m0", "m1"),
         Element("e2", get_law("implicit_spring").bind(k=0.1084546414232932, L0=0.001,
                                                       F0=39.08534189049614), "m0", "m2"),
         Element("e3", get_law("newtonian").bind(c=0.3763991381017348), "m2", "m0")],
        {"m1": 221.02329860463186})


def mass_stopped_by_a_string_between_yield_dashpots() -> Scene:
    # a draw of the LUMPED_LARGE tight run (seed 22046, draw 2841), shrunk: m0, pushed by a
    # sine burst and dragging m3 through the Bingham dashpot e3, is stopped by the string
    # e0 at x = 0.01 between a Bingham (e4) and a Herschel-Bulkley n = 2 (e5) dashpot to
    # ground, and held there until the burst ends
    # (tests/solvers/eventdriven/test_radau5_string_stop.py)
    bingham = get_law("bingham")
    return Scene(
        [Mass("m0", m=1.0), Mass("m3", m=6.065507752210283, v0=0.3798747617885483)],
        [Element("e0", get_law("string_spring").bind(k=1.1148689913102063, L=0.01),
                 "ground", "m0"),
         Element("e3", bingham.bind(gamma=1.0, tau=0.07504090132904585), "m0", "m3"),
         Element("e4", bingham.bind(gamma=1.0, tau=0.03405872114191103), "m0", "ground"),
         Element("e5", get_law("herschel_bulkley").bind(gamma=3.7106713747905107,
                                                        tau=0.8867371614238684, n=2.0),
                 "ground", "m0")],
        {"m0": SineBurst(35.532712795499286, 2.154434690031884, 0.18186971159620458)})
