"""Regressions of ``bdf1`` / ``bdf2`` found by the random-network property suite (issue 11,
session 8), each scene written out as drawn. As in ``test_network_bdf_regressions2``,
every run is checked against the laws: it completes, every value is finite and no stuck
dashpot carries more than its yield force."""

from __future__ import annotations

import numpy as np
import pytest
from _bdf_scenes import creeping_pair_on_a_string, second_string_taut_within_the_step
from _yield_check import run_checked as _run_ok

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.bdf.impact_step import impact_step, impulse_is_negligible
from lumped.solvers.implicit.initial_state import consistent_initial_state
from lumped.solvers.newton.options import NewtonOptions


def _string_taut_beside_a_stuck_parallel_pair() -> Scene:
    """Drawn by the suite (session 8, as drawn): ``m1`` runs away from ``m0`` (held by a
    Coulomb element ``e0``) and the string ``e1``, ``0.0066`` short of its length, goes
    taut in the first step; junction ``j2`` hangs on ``m1`` by a Bingham-like
    Herschel-Bulkley dashpot ``e2`` (``n = 1``) and a Coulomb element ``e3`` in parallel,
    both stuck (their split of the spring ``e5``'s force is free), while ``m1`` slips on
    a Herschel-Bulkley dashpot ``e4`` (``n = 0.3``) to ground."""
    return Scene(
        [Mass("m0", m=3.267642917017149, x0=-0.5934019634047084, v0=5.795687848153468e-157),
         Mass("m1", m=5.623413251903491, x0=7.183868578550699e-278, v0=0.38677848560916894),
         Junction("j2", x0=0.5070979777114681)],
        [Element("e0", get_law("coulomb").bind(tau=0.46971913285260636, r=57.38038306498419),
                 "ground", "m0"),
         Element("e1", get_law("string_spring").bind(k=1.0000000000000004,
                                                     L=0.5999609420416394), "m0", "m1"),
         Element("e2", get_law("herschel_bulkley").bind(gamma=2.124618119325982, tau=1.0,
                                                        n=1.0), "m1", "j2"),
         Element("e3", get_law("coulomb").bind(tau=0.12733782932613766, r=8.212538101258005),
                 "m1", "j2"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=1.0000000000000009, tau=1.0,
                                                        n=0.3), "ground", "m1"),
         Element("e5", get_law("linear_spring").bind(k=1.0), "m1", "j2")])


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("dt", [0.025, 0.0125, 0.00625])
def test_string_taut_beside_a_stuck_parallel_pair(method, dt):
    """Every level stopped with 'Newton failed (diverged)' in the step where ``e1`` goes
    taut: the rows of the stuck pair ``e2``, ``e3`` are proportional (ratio ``-8.2``), LU
    eliminated one to a pivot of an ulp instead of zero, and while ``e4``'s law was still
    converging the correction moved their free split by ``1e13``; Newton crawled back by
    halving and ran out. A correction that long along a null space hidden by rounding
    is now replaced by the minimum-norm one, which leaves the split alone."""
    scene = _string_taut_beside_a_stuck_parallel_pair()
    sol = _run_ok(scene, method, dt, 0.5)
    assert [ev.element for ev in sol.events][:1] == ["e1"]
    assert 0.0 < sol.events[0].t < 0.025
    assert np.array_equal(sol.v["j2"], sol.v["m1"])  # the pair stays stuck
    # the pair carries the spring's force between them, each within its yield force
    total = sol.F["e2"] + sol.F["e3"] + sol.F["e5"]
    assert np.abs(total).max() <= 1e-9


def _coulomb_chain_from_a_moving_mass() -> Scene:
    """Drawn by the suite (session 8, as drawn): junctions ``j0`` and ``j1`` hang in a
    chain of Coulomb elements from ground (``e0``, ``tau = 0.29``) through ``e1`` to the
    moving mass ``m2`` (``e3``), and a spring ``e2`` (force ``0.32``) pulls ``j0`` towards
    ``m2``."""
    return Scene(
        [Junction("j0", x0=-0.403854085521261),
         Junction("j1", x0=0.9565950581006502),
         Mass("m2", m=0.5897700987435932, x0=0.7975242779713154, v0=1.7842051501075806)],
        [Element("e0", get_law("coulomb").bind(tau=0.29226228629904866, r=1.0), "ground", "j0"),
         Element("e1", get_law("coulomb").bind(tau=1.0, r=1.0), "j0", "j1"),
         Element("e2", get_law("linear_spring").bind(k=0.2658057176104353), "j0", "m2"),
         Element("e3", get_law("coulomb").bind(tau=1.0, r=2.250457835392165), "j1", "m2")])


def test_initial_state_of_a_coulomb_chain_from_a_moving_mass():
    """The start stopped with 'no consistent initial state: Newton failed (diverged)',
    though one exists: ``j1`` and ``j0`` stuck to ``m2`` (``e1``, ``e3`` carry
    ``0.29 - 0.32 = -0.027``, within their yield force 1) and ``e0`` slipping at ``tau``.
    Every start (the balances swept one junction at a time, each junction moving with
    one neighbour in turn) left ``j0`` at rest; the restarts now also follow those
    guesses along the chain, so ``j0`` moves with ``j1``, which moves with ``m2``."""
    scene = _coulomb_chain_from_a_moving_mass()
    v, F, _ = consistent_initial_state(scene, time_scale=0.025, options=NewtonOptions())
    assert v == [1.7842051501075806] * 3
    assert F[0] == 0.29226228629904866  # e0 slips at its yield force
    assert F[2] == pytest.approx(0.2658057176104353 * (0.7975242779713154 + 0.403854085521261),
                                 rel=1e-12)
    assert F[1] == F[3] == pytest.approx(F[0] - F[2], rel=1e-9)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_coulomb_chain_from_a_moving_mass_runs(method):
    """The runs of the suite's three levels complete and keep every law."""
    scene = _coulomb_chain_from_a_moving_mass()
    for dt in (0.025, 0.0125, 0.00625):
        _run_ok(scene, method, dt, 0.5)



def _stuck_chain_to_ground_from_a_moving_mass() -> Scene:
    """Drawn by the suite (session 8, as drawn): ``m0`` moves down on a soft implicit
    spring ``e0``; junction ``j2`` hangs on it by a Coulomb element ``e2`` (yield force
    0.076), ``j1`` on ``j2`` by a Herschel-Bulkley dashpot ``e3`` (``n = 0.8``, yield
    force 0.116) and on ground by a Coulomb element ``e1`` (yield force 0.023)."""
    return Scene(
        [Mass("m0", m=1.0, x0=0.02174238759000713, v0=-0.6216909096624927),
         Junction("j1", x0=-0.9534830883625265),
         Junction("j2", x0=0.01039541614992635)],
        [Element("e0", get_law("implicit_spring").bind(k=1.8413783425232708,
                                                       L0=0.5511035225882043, F0=100.0),
                 "ground", "m0"),
         Element("e1", get_law("coulomb").bind(tau=0.022710766146197766, r=11.89758273125704),
                 "ground", "j1"),
         Element("e2", get_law("coulomb").bind(tau=0.07560428289654172, r=1.0), "m0", "j2"),
         Element("e3", get_law("herschel_bulkley").bind(gamma=1.023292992280754,
                                                        tau=0.11577390066003547, n=0.8),
                 "j1", "j2")])


def test_initial_state_of_a_stuck_chain_to_ground_from_a_moving_mass():
    """The start stopped with 'no consistent initial state: Newton failed (diverged)'.
    The balances give ``F1 = F3 = -F2``, so ``|F2|, |F3| <= 0.023`` below their yield
    forces: ``e2`` and ``e3`` are stuck, ``j2`` and ``j1`` move with ``m0``, and ``e1``
    slips at its yield force. No start had both junctions at ``m0``'s velocity (moving
    each junction with one neighbour, ``j1`` takes ``j2``'s velocity as it was, rest);
    every cluster of junctions now also moves as one with a neighbour outside it."""
    scene = _stuck_chain_to_ground_from_a_moving_mass()
    v, F, _ = consistent_initial_state(scene, time_scale=0.025, options=NewtonOptions())
    assert v == [-0.6216909096624927] * 3
    assert F[1] == -0.022710766146197766  # e1 slips at its yield force
    assert F[3] == pytest.approx(F[1], rel=1e-12)
    assert F[2] == pytest.approx(-F[1], rel=1e-12)
    for dt in (0.025, 0.0125, 0.00625):
        _run_ok(scene, "bdf1", dt, 0.5)

def test_an_impulse_below_the_momentum_round_off_is_no_impact():
    """The state of ``test_second_impact_within_the_step_is_located`` (``dt = 0.02255``)
    at ``t = 0.1128``: both masses rest on their strings with velocities of round-off (they come
    out so or as exact zeros depending on the last bits of LAPACK's minimum-norm solve), and
    the string ``e3`` between them is read locked anew. Stopping it costs all of their
    kinetic energy (``1.6e-37``), so the relative test called it an impact, and the run
    recorded four more impacts of ``1e-21``; an impulse below the round-off of the step's
    momentum change is none."""
    scene = second_string_taut_within_the_step()
    v = [-3.1785747367369654e-22, 6.249848031473503e-19]
    F = [-0.050059090135453004, 0.05005909013545299, -0.5204840094388528,
         0.23621411273834048, -0.7066390320417403]
    floor = 4.0 * np.finfo(float).eps * 0.022551812495189668 * max(map(abs, F))
    assert not impulse_is_negligible(scene, v, [3])  # all the kinetic energy
    assert impulse_is_negligible(scene, v, [3], floor)
    assert not impulse_is_negligible(scene, [0.0, 1e-9], [3], floor)  # a real impact


def test_impact_located_where_a_bisection_substep_needs_halving():
    """The state of ``test_substep_after_an_impact_beside_a_creeping_dashpot`` at
    ``t = 0.3395``: ``m0`` and ``m1`` move together (the string ``e2`` taut, the Herschel-Bulkley
    ``n = 0.5`` dashpot ``e1`` stuck beside it) and ``m1`` reaches the stiff string ``e3``
    within the step. The bisection's first trial substep (half the step) ran out of Newton
    iterations (the taut ``e2`` fixes the rate to ``ulp(x) / h``, where ``e1``'s law is
    steep), the bracket stayed the whole step, the impact was put at its end, and the
    substep a hair long after it failed too: 'no motion satisfies all the laws' at ``t =
    0.3443``. A failing trial substep is now taken as 2 to 16 substeps, as the rest of the
    step is, and the impact is located inside the step."""
    scene = creeping_pair_on_a_string()
    t0, dt = 0.33947064700989427, 0.019398322686279675 / 4
    x = [0.08773879725496071, 0.06096124230265961]
    v = [0.08234632193033797, 0.08234632193033797]
    F = [0.0021681757064550985, -0.0021837589362244903, 4.496949413093089,
         5.983911556978875]
    done = impact_step(scene, t0, dt, x, v, F, {2}, NewtonOptions())
    assert done.failure is None
    assert [ev.element for ev in done.events] == ["e3"]
    assert t0 + 0.4 * dt < done.events[0].t < t0 + 0.6 * dt
    assert done.x[1] <= 0.06113590223120681  # m1 within e3's length
    assert abs(done.F[1]) <= 0.011042871848402393  # e1 within its yield force


def _two_strings_in_parallel_on_a_string() -> Scene:
    """Drawn by the ``LUMPED_LARGE`` suite (session 11, ``jit-bdf1``, which runs such a
    scene on ``bdf1``): ``m1`` runs away from ``m0`` at 1 m/s; the short string ``e1``
    goes taut and drags ``m0`` until ``m0``'s own string ``e0`` to ground goes taut too."""
    return Scene([Mass("m0", m=1.0, x0=0.0, v0=0.0), Mass("m1", m=1.0, x0=0.0, v0=1.0)],
                 [Element("e0", get_law("string_spring").bind(k=1.0, L=0.1), "ground", "m0"),
                  Element("e1", get_law("string_spring").bind(k=0.1, L=0.1), "m0", "m1"),
                  Element("e2", get_law("string_spring").bind(k=0.1, L=1.0), "m0", "m1")])


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_forces_a_hair_after_an_impact_on_a_lock_that_rounds_off_its_length(method):
    """At ``t = 0.306`` (``dt = 0.00625``) the impact on ``e0`` ends the step; the
    forces there come from a substep a hair long (``1e-10 dt = 6e-13`` s) after it. The
    taut ``e1``'s elongation rounds 2 ulps off its length there, and Newton was asked for
    the force that removes them, ``m ulp(x) / h^2 = 1e7``: 'Newton failed (max_iters)'
    with a largest residual of ``3e-17``. Where that substep fails, a longer one (1e3,
    then 1e6 times) gives the forces."""
    scene = _two_strings_in_parallel_on_a_string()
    sol = _run_ok(scene, method, 0.00625, 0.5)
    assert [(ev.element, ev.kind) for ev in sol.events][:2] == [("e1", "impact"),
                                                                 ("e0", "impact")]
    x0, x1, v0, v1 = sol.x["m0"], sol.x["m1"], sol.v["m0"], sol.v["m1"]
    assert x0.max() <= 0.1 and (x1 - x0).max() <= 0.1 * (1 + 1e-15)  # on the strings
    # kinetic energy and the springs' (the taut strings store none): never rises
    energy = 0.5 * (v0**2 + v1**2) + 0.5 * x0**2 + 0.1 * (x1 - x0) ** 2
    assert np.diff(energy).max() <= 1e-15


def _string_between_two_herschel_bulkley_links() -> Scene:
    """Drawn by the suite at ``LUMPED_LARGE=2000`` (session 14, ``bdf2``, example 732, as
    drawn): a string ``e1`` between ``m0`` and ``m1`` in parallel with a shear-thinning
    Herschel-Bulkley link ``e5`` (``n = 0.3``), ``m0`` on a shear-thickening one ``e0``
    (``n = 2``) to ground; the string goes taut near ``t = 0.355``, and ``m2``, ``m3``
    (a Bingham link ``e3`` between them) stick together near ``t = 0.3627``."""
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


@pytest.fixture(scope="module")
def string_beside_herschel_bulkley_reference():
    """A tight ``radau5`` run of the scene (agrees with ``rtol = 1e-10`` to ``5e-11``):
    the impact of ``e1`` at ``t = 0.354912``."""
    sol = simulate(_string_between_two_herschel_bulkley_links(), method="radau5",
                   t_end=0.5, rtol=1e-9, atol=1e-11)
    assert sol.ok, sol.message
    return sol


@pytest.mark.parametrize(("method", "dt"), [("bdf1", 0.025), ("bdf2", 0.025),
                                            ("bdf2", 0.0125)])
def test_a_string_locking_beside_a_shear_thinning_link_runs(method, dt):
    """Every run stopped with 'Newton failed' at ``t = 0.36`` to ``0.4`` (issue 29, a strict
    expected failure until now). After the impact the taut string ``e1`` and the stuck
    ``e5`` beside it fix the same rate (their rows ``h (v_1 - v_0)`` and ``v_0 - v_1``
    are proportional, their forces' columns opposite), a singular step matrix in which
    LU left a pivot of ``1.5e-20``; with ``e0``'s law still converging, its correction
    moved their free split by ``50`` to ``600`` (the minimum-norm one: ``0.19``), which
    pushed ``e5`` onto its slipping branch and ``e1`` slack, and Newton crawled back by
    halving (``bdf1``: 213 iterations in the remainder after the impact). Such a
    correction is now checked from ten times the iterate (not ``1e6`` times) and
    replaced by the minimum-norm one."""
    sol = _run_ok(_string_between_two_herschel_bulkley_links(), method, dt, 0.5)
    impacts = [ev for ev in sol.events if ev.kind == "impact"]
    assert [ev.element for ev in impacts] == ["e1"]
    after = sol.t > impacts[0].t + dt
    # m0 and m1 move as one on the taut string, e5 stuck within its yield force
    assert np.abs(sol.v["m1"][after] - sol.v["m0"][after]).max() <= 1e-12
    assert (sol.x["m1"] - sol.x["m0"]).max() <= 0.027118745378267504 * (1 + 1e-12)
    assert np.abs(sol.F["e5"][after]).max() <= 0.0866247187423721 * (1 + 1e-9)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_a_string_locking_beside_a_shear_thinning_link_converges_to_radau5(
        method, string_beside_herschel_bulkley_reference):
    """The runs agree with a tight ``radau5`` run within their own error: the largest
    displacement error over the samples falls as the step halves (``bdf2``: ``3.3e-3``,
    ``2.2e-3``, ``6.6e-4`` at ``dt = 0.025`` to ``0.00625``; ``bdf1``: ``6.7e-3``,
    ``4.3e-3``, ``1.6e-3``; first order across the impact, which the step locates only
    to its own error), and the impact is found within one step of ``radau5``'s."""
    ref = string_beside_herschel_bulkley_reference
    t_ref = next(ev.t for ev in ref.events if ev.kind == "impact")
    errors = []
    for dt in (0.025, 0.0125, 0.00625):
        sol = _run_ok(_string_between_two_herschel_bulkley_links(), method, dt, 0.5)
        exact = ref.sol(sol.t)
        errors.append(float(np.abs(sol.data[:, 1:9:2] - exact[:, 1:9:2]).max()))
        t_hit = next(ev.t for ev in sol.events if ev.kind == "impact")
        assert abs(t_hit - t_ref) <= dt
    assert errors[1] <= 0.8 * errors[0] and errors[2] <= 0.5 * errors[1], errors
    assert errors[2] <= (1e-3 if method == "bdf2" else 2e-3), errors
