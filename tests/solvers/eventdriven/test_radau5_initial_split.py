"""``radau5``'s first step where locks in parallel share a load (issue 29, session 23).

The consistent initial state and the stage solve each pick a split of the load among
locks in parallel (the motion fixes only their sum), and the two picks differ. Junction
j0 is stuck on e0 (Herschel-Bulkley ``n = 0.5``, ``tau = 0.1``) to ground and on e6
(``n = 0.8``, ``tau = 1 - 2.3e-12``) in series with e5 (Bingham, ``tau = 1``) to ground,
and carries the Bingham dashpot e2 of the sliding mass m2, ``F_2 = 1.076``. The initial
state splits it ``F_0 = -0.0767, F_6 = 0.9993``; the stage solve's free split is
``F_0 = -0.179, F_6 = 0.897``, beyond e0's interval, held at ``F_0 = -0.1``, ``F_6 =
0.976``. The split jumps at ``t = 0`` (a force that acts on no mass). The first step's
force cubic, started from the initial split, overshot ``-0.1`` between its nodes, and the
kink test (:mod:`lumped.solvers.modes.split_kink`) cut the step to where the free cubic
crosses ``-0.1``: ``s = 0.0266`` of the step at every step size, as the jump sits at
``s = 0``. Eight cuts took the first step from ``1.7e-7`` (m1 starting from rest on a
``n = 0.5`` dashpot sets it) to ``6e-20``, below the step floor; the backward-Euler bridge
then locked m1's dashpot e1, whose load 3.89 is beyond its yield force 1, and failed.
The first step now starts the split of locks in parallel from the stage solve's, as after
an event.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _convergence import assert_within_bdf2s_own_error

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.eventdriven.bridge import run_bridge
from lumped.solvers.newton.options import NewtonOptions


def _junction_on_locks_in_parallel(with_m1: bool = True) -> Scene:
    # the failing draw 4592 of the LUMPED_LARGE tight-tolerance run, less e3 (j0 to j3);
    # m1 (on e1 alone) and the rest share no node
    hb, bingham = get_law("herschel_bulkley"), get_law("bingham")
    nodes = [Junction("j0", x0=-0.20376697147345424),
             Mass("m2", m=1.0369505197756097, x0=0.3789563121966302, v0=-1.254696966621026),
             Junction("j3", x0=-0.5)]
    elements = [
        Element("e0", hb.bind(gamma=1.0, tau=0.1, n=0.5), "ground", "j0"),
        Element("e2", bingham.bind(gamma=1.5370439640269398, tau=0.2596922396087791),
                "j0", "m2"),
        Element("e4", get_law("implicit_spring").bind(
            k=0.9999930473271447, L0=0.08544917964130305, F0=45.061606870877355),
            "m2", "ground"),
        Element("e5", bingham.bind(gamma=5.59881894026202, tau=1.0), "ground", "j3"),
        Element("e6", hb.bind(gamma=0.8099522487037356, tau=0.9999999999976974, n=0.8),
                "j0", "j3")]
    if not with_m1:
        return Scene(nodes, elements)
    nodes.append(Mass("m1", m=0.1367559683814865, x0=-0.535200862916131,
                      v0=4.999931686804877e-84))
    elements.append(Element("e1", hb.bind(gamma=0.3694690741303337, tau=1.0, n=0.5),
                            "ground", "m1"))
    return Scene(nodes, elements, {"m1": -3.886707193086813})


def test_the_first_step_beside_a_mass_starting_from_rest_is_not_cut_to_the_floor():
    """The draw itself (raised SolverError before: step size 6.0e-20 below its floor at
    ``t = 0``, then backward Euler failed with e1 locked)."""
    sol = simulate(_junction_on_locks_in_parallel(), method="radau5", dt=0.025 / 4,
                   t_end=0.5, rtol=1e-10, atol=1e-13, compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message


@pytest.mark.parametrize("compiled", [False, True])
def test_a_split_that_jumps_at_the_start_is_not_a_kink_inside_the_first_step(compiled):
    """Without m1, a first step of ``1e-7`` (the size m1 set): cut eight times by ``s =
    0.025`` to ``6.2e-19`` before, below the floor, and bridged by backward Euler."""
    sol = simulate(_junction_on_locks_in_parallel(with_m1=False), method="radau5",
                   dt=0.025 / 4, t_end=0.5, rtol=1e-10, atol=1e-13, first_step=1e-7,
                   compiled=compiled)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert sol.stats.get("split_rejected", 0) == 0
    # the motion fixes the split's sum: j0's balance, e0 and e6 within their intervals
    for k in range(len(sol.t)):
        F0, F2, F6 = (sol.F[e][k] for e in ("e0", "e2", "e6"))
        assert F0 - F2 - F6 == pytest.approx(0.0, abs=1e-9)
        assert abs(F0) <= 0.1 * (1.0 + 1e-9)
        assert abs(F6) <= 1.0


def test_the_draw_agrees_with_bdf2():
    # j0 and j3 stay stuck, m2 slides on e2 and m1 breaks away from rest on e1
    scene = _junction_on_locks_in_parallel()
    dt = 0.025 / 4
    sol = simulate(scene, method="radau5", dt=dt, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=False)
    assert_within_bdf2s_own_error(scene, sol, ("m1", "m2", "j0"), dt, 0.5, 32)


# m1 alone on e1 (Herschel-Bulkley n = 0.5) under a load beyond its yield force
_M1, _GAMMA1, _TAU1, _LOAD1 = 0.1367559683814865, 0.3694690741303337, 1.0, -3.886707193086813
#: the bridge's step on the draw (``sqrt(rtol) h``)
_DT_BRIDGE = 6.7e-12


def _breaking_away() -> Scene:
    return Scene([Mass("m1", m=_M1, x0=0.0)],
                 [Element("e1", get_law("herschel_bulkley").bind(
                     gamma=_GAMMA1, tau=_TAU1, n=0.5), "ground", "m1")],
                 {"m1": _LOAD1})


def _exact_break_away(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(v, F)`` of m1 breaking away: on the slip branch ``F = -tau - (v/gamma)^2``, so
    ``m v' = f + tau + (v/gamma)^2``, a Riccati equation with ``v(0) = 0``: ``v = -c
    tanh(c t / (m gamma^2))``, ``c = gamma sqrt(-f - tau)``."""
    c = _GAMMA1 * math.sqrt(-_LOAD1 - _TAU1)
    v = -c * np.tanh(c * t / (_M1 * _GAMMA1**2))
    return v, -_TAU1 - (v / _GAMMA1) ** 2


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_backward_euler_follows_a_break_away_on_a_thinning_dashpot_at_tiny_steps(method):
    """The bridge's own failure on the draw. m1 (``m = 0.137``) breaks away from rest on
    e1 alone (``n = 0.5``, ``gamma = 0.369``, ``tau = 1``) under ``-3.887``, ``v' =
    -21.1``. Backward Euler at ``dt = 6.7e-12`` (the bridge's ``sqrt(rtol) h``) failed at
    step 22 (bdf2: step 15), ``v = -3.1e-9``, its largest residual ``-3.1e-9``, all of
    ``q``: a rate below ``gamma sqrt(ulp(tau)) = 5.5e-9`` has no force in floating point
    (``F - tau = (q / gamma)^2 = 7e-17 < ulp(1)``), Newton sat at ``F = -tau``, the stuck
    branch (``q - 0``), and never converged. The step is now solved with the slip branch
    in its inverse form ``F = -tau - (q/gamma)^2``, read at ``F = -tau`` where it holds
    (:mod:`lumped.solvers.implicit.conditioned`).

    Checked against the exact motion: the method's own error is far below its Newton
    tolerance here (``v''`` is ``1e-5``), so ``v`` to that tolerance summed over the steps
    (``64 x 4 rtol`` relative) and ``F`` to ``10 rtol`` of ``tau``."""
    sol = simulate(_breaking_away(), method=method, dt=_DT_BRIDGE, t_end=64 * _DT_BRIDGE)
    assert sol.ok, sol.message
    t = np.asarray(sol.t)
    v_exact, F_exact = _exact_break_away(t)
    np.testing.assert_allclose(sol.v["m1"], v_exact, rtol=64 * 4e-10,
                               atol=1e-3 * abs(v_exact[1]))
    np.testing.assert_allclose(sol.F["e1"], F_exact, rtol=0.0, atol=1e-9 * _TAU1)
    # past the band of rates that have no force in floating point (|v| > 5.5e-9)
    assert sol.v["m1"][-1] < -1.6 * _GAMMA1 * math.sqrt(math.ulp(_TAU1))


def test_the_bridge_follows_the_break_away_from_rest():
    """``radau5``'s bridge itself (:func:`~lumped.solvers.eventdriven.bridge.run_bridge`)
    from m1 at rest on e1's yield force: 64 backward-Euler steps of ``6.7e-12`` (before:
    ``backward Euler failed too``, at step 22)."""
    run = run_bridge(_breaking_away(), 0.0, [0.0], [0.0], [-_TAU1], _DT_BRIDGE, 64,
                     NewtonOptions(), 0.0)
    assert not isinstance(run, str), run
    t = np.arange(65) * _DT_BRIDGE
    v_exact, F_exact = _exact_break_away(t)
    np.testing.assert_allclose(run.vs, v_exact, rtol=64 * 4e-10,
                               atol=1e-3 * abs(v_exact[1]))
    np.testing.assert_allclose(run.Fs, F_exact, rtol=0.0, atol=1e-9 * _TAU1)
