"""The stage guess of a ``radau5`` step that starts where a held branch is flat at its end
(:mod:`lumped.solvers.radau.flat_start`, issue 29)."""

from __future__ import annotations

import math

import numpy as np
import pytest
import sympy as sp
from _convergence import assert_within_bdf2s_own_error

from lumped import simulate
from lumped.codegen.branches import law_branches
from lumped.codegen.stage_forms import flat_inverse
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene, SineBurst
from lumped.solvers.eventdriven.step import StepPass
from lumped.solvers.radau.flat_start import at_flat_end, flat_base

q, F = sp.symbols("q F")


def test_flat_inverse_solves_a_flat_ended_power_for_its_force():
    base, G = flat_inverse(q - 2 * (F - sp.Rational(1, 2)) ** sp.Rational(3, 2))
    assert sp.simplify(base - (F - sp.Rational(1, 2))) == 0
    assert float(G.subs(q, 2 * 8)) == pytest.approx(0.5 + 4.0, rel=1e-15)
    # not flat at its end (p <= 1), or not a power of F: none
    assert flat_inverse(q - 2 * (F - 1) ** sp.Rational(1, 2)) is None
    assert flat_inverse(q - 2 * (F - 1)) is None


def test_a_herschel_bulkley_slip_branch_with_n_above_one_has_a_flat_start():
    gamma, tau = 0.5, 0.25
    lb = law_branches(get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=1.5))
    starts = [lb.flat_start_for(i) for i in range(lb.count)]
    slips = [s for s in starts if s is not None]
    assert len(slips) == 2  # forward and backward slip; not the stuck branch
    for start in slips:
        base, force = start(1e-3, 0.0)
        if math.isfinite(force) and force > 0.0:  # the forward branch at rate 1e-3
            assert force == pytest.approx(tau + (1e-3 / gamma) ** (2 / 3), rel=1e-14)
    # Bingham (p = 1) and n < 1 (an inverse form already) have none
    for n in (1.0, 0.5):
        lb = law_branches(get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=n))
        assert all(lb.flat_start_for(i) is None for i in range(lb.count))


def test_at_flat_end_reads_the_force_at_the_end_only():
    gamma, tau = 0.5, 0.25
    lb = law_branches(get_law("herschel_bulkley").bind(gamma=gamma, tau=tau, n=1.5))
    fwd = next(i for i in range(lb.count) if lb.flat_start_for(i) is not None
               and lb.flat_start_for(i)(1e-3, tau)[0] == 0.0)
    base = flat_base(lb.flat_start_for(fwd))
    assert base == (1.0, -tau)  # F - tau, read exactly
    assert at_flat_end([base, None], [tau, 1.0]) == [0]
    assert at_flat_end([base], [tau + 1e-6]) == []
    assert at_flat_end([base], [tau * (1 + 1e-13)]) == [0]  # within AT_END
    assert flat_base(None) is None


def test_the_flat_ends_are_read_once_per_state():
    # a pass asks up to three times at one state (the run loop, the step, the stage
    # guess): the ends are a function of the modes and F, read once (before: 3); the
    # branches' bases once per modes
    tau = 0.25
    law = get_law("herschel_bulkley").bind(gamma=0.5, tau=tau, n=1.5)
    lb = law_branches(law)
    fwd = next(i for i in range(lb.count) if lb.flat_start_for(i) is not None
               and lb.flat_start_for(i)(1e-3, tau)[0] == 0.0)
    reads = []

    class Branches:
        def flat_start_for(self, i):
            start = lb.flat_start_for(i)
            return lambda q, F: reads.append((q, F)) or start(q, F)

    scene = Scene([Mass("m", 1.0)], [Element("d", law, "ground", "m")])
    run = StepPass()
    run.frame, run.lbs, run.scene, run.modes = None, [Branches()], scene, [fwd]
    run.x, run.v, run.F = [0.0], [0.0], [tau]
    assert [run.flat_ends() for _ in range(3)] == [[0]] * 3
    assert len(reads) == 2  # (the base at F = 2^200 and at 0: one reading)
    run.F = [tau + 1e-3]  # a new state: the ends read again, the base kept
    assert run.flat_ends() == [] and len(reads) == 2
    run.modes = [fwd]  # (the same modes, made anew)
    assert run.flat_ends() == [] and len(reads) == 2
    assert run.flat_reader().table(run.modes).tolist() == [[1.0, -tau]] and len(reads) == 2


def _flat_dashpot_on_a_mass_among_locks() -> Scene:
    # seed 191 of benchmarks/tight_hunt.py: m1 held to ground by a Herschel-Bulkley n =
    # 1.5 dashpot (e1) and tied to m3 and the junction j2 by Coulomb, Bingham and a
    # Newtonian (n = 1) link, under a sine burst; e1 starts a slip at its yield force at
    # t = 0.0893
    hb, bingham, coulomb = (get_law(n) for n in ("herschel_bulkley", "bingham", "coulomb"))
    return Scene(
        [Junction("j0", x0=-0.24943835126434144),
         Mass("m1", m=0.2938799365769739, x0=0.5090919980990107, v0=1.7688004129121042),
         Junction("j2", x0=0.7555142155271128),
         Mass("m3", m=0.21672818404543068, x0=5.712420930624005e-25,
              v0=-1.2584203971744161)],
        [Element("e0", coulomb.bind(tau=0.47104715054898755, r=17.107971715512384),
                 "ground", "j0"),
         Element("e1", hb.bind(gamma=0.5151898545983224, tau=0.0892798541199516, n=1.5),
                 "ground", "m1"),
         Element("e2", coulomb.bind(tau=0.35221513172595215, r=5.5271379906218945),
                 "m1", "j2"),
         Element("e3", hb.bind(gamma=0.9787382808753182, tau=1.0, n=1.0), "m1", "m3"),
         Element("e4", bingham.bind(gamma=0.6654226506596151, tau=0.9998594712341624),
                 "m1", "j2"),
         Element("e5", coulomb.bind(tau=1.0, r=1.000000137244776), "m1", "m3"),
         Element("e6", bingham.bind(gamma=7.299255625019936, tau=0.023454046207409193),
                 "m1", "j2")],
        {"m1": SineBurst(amplitude=-5.858888424251339, omega=5.623413251903491,
                         t_off=math.inf)})


def test_radau5_starts_a_slip_at_a_flat_yield_force_without_a_bridge():
    """Seed 191: at ``t = 0.0893`` e1 starts a slip at its yield force, where its law is
    flat in the force. From the constant stage guess Newton loaded the whole excess force
    onto e1 at its first iteration and forces of ``2e7`` at its second, then missed its
    10 iterations at every step size: 29 failed solves, a stop at the step floor, and a
    backward-Euler bridge. From the guess on the branch the first solve converges; the
    run agrees with bdf2 within bdf2's own error."""
    scene = _flat_dashpot_on_a_mass_among_locks()
    dt = 0.025 / 4
    sol = simulate(scene, method="radau5", dt=dt, t_end=0.5, rtol=1e-10, atol=1e-13,
                   compiled=False)
    assert sol.ok, sol.message
    assert sol.stats.get("bridges", 0) == 0, sol.message
    assert_within_bdf2s_own_error(scene, sol, ("m1", "m3"), dt, 0.5, 8)


def test_both_loops_start_the_slip_at_the_flat_yield_force_alike():
    """The step from the flat end is the Python loop's in both loops (the compiled loop
    hands that pass over): the same numbers."""
    scene = _flat_dashpot_on_a_mass_among_locks()
    ours, fast = (simulate(scene, method="radau5", dt=0.025 / 4, t_end=0.5, rtol=1e-10,
                           atol=1e-13, compiled=c) for c in (False, True))
    assert fast.ok and fast.stats.get("bridges", 0) == 0, fast.message
    assert np.array_equal(ours.data, fast.data)
    assert [(ev.t, ev.element, ev.kind) for ev in ours.events] == [
        (ev.t, ev.element, ev.kind) for ev in fast.events]


def test_a_law_of_a_parametric_class_gets_its_flat_start_from_the_class():
    hb = get_law("herschel_bulkley")
    for gamma, tau in ((0.5, 0.25), (0.7, 0.3), (0.9, 0.11)):
        lb = law_branches(hb.bind(gamma=gamma, tau=tau, n=1.5))
        forces = [start(1e-3, tau)[1] for start in map(lb.flat_start_for, range(lb.count))
                  if start is not None]
        assert max(forces) == pytest.approx(tau + (1e-3 / gamma) ** (2 / 3), rel=1e-14)
