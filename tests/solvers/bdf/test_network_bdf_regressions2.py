"""Regressions of ``bdf1`` / ``bdf2`` found by the random-network property suite (issue 11,
session 7), each scene written out as drawn. As in ``test_network_bdf_regressions``,
every run is checked against the laws: it completes, every value is finite and no stuck
dashpot carries more than its yield force."""

from __future__ import annotations

import numpy as np
import pytest
from _bdf_scenes import creeping_pair_on_a_string
from _yield_check import run_checked as _run_ok

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.bdf.impact_step import be_substep, impact_step
from lumped.solvers.newton.options import NewtonCode, NewtonOptions


def _junction_stuck_to_a_mass_on_a_string() -> Scene:
    """Drawn by the suite (session 6, as drawn): ``m0`` runs down and pulls ``m1`` by the
    string ``e1`` (``L = 0.0377``); junction ``j2`` hangs on ``m1`` by a Bingham dashpot
    ``e2`` (yield force 1, stuck) and on ``m0`` by a Herschel-Bulkley dashpot ``e4``
    (``n = 0.3``) with a soft string ``e3`` beside it."""
    return Scene(
        [Mass("m0", m=0.9227538421826473, x0=-2.086289839414613e-220, v0=-1.264090566528024),
         Mass("m1", m=0.2644046075244924, x0=-1.7041178526680463e-189,
              v0=3.2146334072091546e-15),
         Junction("j2", x0=1.4746358831165997e-110)],
        [Element("e0", get_law("implicit_spring").bind(k=1.0, L0=0.9227538421826473,
                                                       F0=9.176852061319995), "ground", "m0"),
         Element("e1", get_law("string_spring").bind(k=2.235793320878419,
                                                     L=0.0376977285700998), "m0", "m1"),
         Element("e2", get_law("bingham").bind(gamma=0.974936211160075, tau=1.0), "m1", "j2"),
         Element("e3", get_law("string_spring").bind(k=0.2644046075244924, L=1.0), "m0", "j2"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=1.9909712398533543,
                                                        tau=0.5288589781931184, n=0.3),
                 "m0", "j2")])


#: The state of :func:`_junction_stuck_to_a_mass_on_a_string` at ``t = 0.03125`` (bdf2,
#: ``dt = 0.00625``), the start of the step in which ``e1`` goes taut.
_X5 = [-0.039068076425362655, -0.0014901253546072296, -0.0014901253546072296]
_V5 = [-1.2375066273136315, -0.09054628515523376, -0.09054628515523376]
_F5 = [-0.03549860057997392, 0.084016532016291, -0.6978732238129373, 0.009935783404437667,
       0.6879374404084996]


@pytest.mark.parametrize("dt", [0.025, 0.0125, 0.00625])
def test_impact_beside_a_junction_stuck_to_a_mass(dt):
    """At ``dt = 0.00625`` the run stopped with 'Newton failed (diverged)' at
    ``t = 0.0375`` in the step where ``e1`` goes taut (it passed before session 6's
    impact step: its first substep took ``h = t0 + dt - t0``, two ulps below ``dt``, and the
    substep's solve fails with that ``h``, see the next test)."""
    scene = _junction_stuck_to_a_mass_on_a_string()
    sol = _run_ok(scene, "bdf2", dt, 0.5)
    assert [ev.element for ev in sol.events][:1] == ["e1"]
    assert 0.03 < sol.events[0].t < 0.035
    q1 = sol.x["m1"] - sol.x["m0"]
    assert q1.max() <= 0.0376977285700998 * (1 + 1e-12)


def test_substep_reads_a_rate_below_rounding_as_rest():
    """The backward-Euler substep across ``e1``'s lock with ``h`` two ulps below
    ``0.00625``: plain Newton diverges (the loop ``e1``, ``e2``, ``e4``), and in the
    globalised solve an iterate left ``j2`` one ulp off ``m1``; the projection onto the
    laws read the stuck Bingham dashpot ``e2`` as slipping at ``1e-16`` and gave it its
    yield force ``1.0`` instead of ``-0.54``, ``j2``'s balance failed by ``1.5`` and
    every restart stalled ('Newton failed (diverged)'; with ``h = 0.00625`` exactly the
    iterate fell on ``m1``'s velocity and it converged). A dashpot's rate below the
    rounding of its ends' velocities now reads as rest where its law admits the force
    there."""
    scene = _junction_stuck_to_a_mass_on_a_string()
    t0, dt = 0.031250000000000007, 0.00625
    h = (t0 + dt) - t0
    assert dt - h == 2 * np.spacing(h)  # two ulps below dt
    for step in (dt, h):
        _, v, F, res = be_substep(scene, t0 + dt, step, _X5, _V5, _F5, NewtonOptions())
        assert res.code is NewtonCode.SUCCESS, step
        assert v[2] == v[1]  # j2 moves with m1: e2 stuck
        assert F[2] == pytest.approx(-0.5388266210348774, rel=1e-9)
        assert F[1] == pytest.approx(36.53688495319027, rel=1e-9)  # e1 taut


def test_impact_step_starts_with_the_step_itself():
    """The impact step's first backward-Euler substep is the whole step, ``h = dt`` (it
    took ``t0 + dt - t0``, which may round off ``dt``: a step without a lock then differed
    from the backward-Euler step, and the solve of the step where ``e1`` goes taut with
    it)."""
    scene = _junction_stuck_to_a_mass_on_a_string()
    t0, dt = 0.031250000000000007, 0.00625 / 128  # e1 is taut from t = 0.03135 only
    assert (t0 + dt) - t0 != dt
    opts = NewtonOptions()
    # a step without a lock: the same numbers
    x1, v1, F1, res = be_substep(scene, t0 + dt, dt, _X5, _V5, _F5, opts)
    assert res.code is NewtonCode.SUCCESS
    done = impact_step(scene, t0, dt, _X5, _V5, _F5, set(), opts)
    assert done.failure is None and not done.events
    assert (done.x, done.v, done.F) == (x1, v1, F1)


def _stuck_pair_in_series_beside_a_taut_string() -> Scene:
    """Drawn by the suite (session 6, as drawn): junction ``j3`` joins a Bingham dashpot
    ``e3`` (from ``m2``) and a Herschel-Bulkley dashpot ``e4`` (``n = 2``, to ``m0``) in
    series, beside the string ``e2`` from ``m0`` to ``m2`` (``L = 0.0015``)."""
    return Scene(
        [Mass("m0", m=7.943282347242816, x0=0.5939868712819689, v0=1.6219267418760683),
         Mass("m1", m=3.1570220713598056, x0=0.6527328550035731, v0=-0.9379809988815795),
         Mass("m2", m=1.0441675846923544, x0=1.1948735567399157e-36, v0=1.338424618122632),
         Junction("j3", x0=0.9673212042920198)],
        [Element("e0", get_law("string_spring").bind(k=26.5493640501496,
                                                     L=0.6045701633159638), "ground", "m0"),
         Element("e1", get_law("bingham").bind(gamma=1.0, tau=0.1), "ground", "m1"),
         Element("e2", get_law("string_spring").bind(k=30.066410226307074,
                                                     L=0.0015109845551111612), "m0", "m2"),
         Element("e3", get_law("bingham").bind(gamma=0.3791541014319603,
                                               tau=0.25501528082602126), "m2", "j3"),
         Element("e4", get_law("herschel_bulkley").bind(gamma=0.21560031682544745,
                                                        tau=0.1573080193367457, n=2.0),
                 "j3", "m0"),
         Element("e5", get_law("implicit_spring").bind(k=0.21359788343041639,
                                                       L0=0.012948296700961339, F0=1.0),
                 "m2", "ground"),
         Element("e6", get_law("newtonian").bind(c=0.026260127817332262), "m1", "m0")])


@pytest.mark.parametrize("dt", [0.025, 0.0125])
def test_stuck_pair_in_series_beside_a_taut_string(dt):
    """``e2`` goes taut at ``t = 0.22``; after it ``j3`` moves with ``m0`` and ``m2``, both
    dashpots stuck: their common force and the string's split the load freely (any
    ``|F| <= 0.1573``). Newton ended at ``e4``'s yield force, where the ``n = 2`` law is
    flat (``dR/dF -> 0``): the step matrix is nearly, not exactly, singular, every
    correction walked ``1e-7`` along the free split and the substep after the impact
    ran out of iterations with every residual below ``4e-15`` ('Newton failed
    (max_iters)' at ``t = 0.225``). An iterate that passes the residual test and whose
    correction moves no velocity (the motion determined, the forces not) is now kept."""
    scene = _stuck_pair_in_series_beside_a_taut_string()
    sol = _run_ok(scene, "bdf1", dt, 0.5)
    assert "e2" in [ev.element for ev in sol.events]
    after = sol.t > 0.23
    assert np.all(np.abs(sol.v["j3"][after] - sol.v["m0"][after]) <= 1e-12)
    assert np.all(np.abs(sol.F["e4"][after]) <= 0.1573080193367457 * (1 + 1e-5))


@pytest.mark.parametrize("dt", [0.019398322686279675 / 4])
def test_substep_after_an_impact_beside_a_creeping_dashpot(dt):
    """``e2`` goes taut again at ``t = 0.2083``, and the two masses move on together with
    ``e1`` stuck beside the string (their split of the load is free). The backward-Euler
    substep over the rest of that step (``2.7e-4``) failed in every start ('Newton
    failed (max_iters)' at ``t = 0.2085``): the string on its lock fixes the rate only to
    ``ulp(x) / h = 5e-14``, where the ``n = 0.5`` law is steep (``dq/dF -> infinity``) and
    its sign flips with the rounding. The same rest as two substeps converges; the rest
    of an impact step is now split as the whole step is (``halved_steps``) when its
    Newton fails."""
    scene = creeping_pair_on_a_string()
    sol = _run_ok(scene, "bdf1", dt, 0.5043563898432716)
    assert [ev.element for ev in sol.events].count("e2") >= 2
    q2 = sol.x["m0"] - sol.x["m1"]
    assert q2.max() <= 0.026777554952301115 * (1 + 1e-12)
    after = sol.t > 0.21
    assert np.all(np.abs(sol.F["e1"][after]) <= 0.011042871848402393 * (1 + 1e-9))
