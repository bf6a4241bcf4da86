"""The Coulomb limit of the Bingham law under ``radau5`` (issue 29, Remark 2.1).

A Bingham dashpot with a huge ``gamma`` slips on ``q - gamma (F - sgn(F) tau) = 0``,
whose forward form fixes the rate only to ``gamma ulp(tau)``; ``radau5`` solves such a
steep branch in its inverse form ``F = sgn(q) tau + q / gamma``
(:func:`lumped.codegen.stage_forms.affine_inverse_form`). Checked against the exact
reference (:mod:`lumped.reference`): the paper's two scenes with only ``gamma`` raised
run through without a bridge, are as accurate as the ``coulomb`` law's runs and take
about as many steps; the compiled loop gives the Python loop's numbers; a property over
``gamma``, ``k`` and ``m``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from lumped import Element, ElementLaw, Mass, Scene, get_law, simulate
from lumped.codegen.jit import numba_enabled
from lumped.reference import reference_for_grid
from lumped.scene import SineBurst, paper_F2
from lumped.solvers.closed.closed_form import BinghamOscillator

GRID_DT = 1e-3
SCENES = {"release-0.5": (0.5, None), "forcing-F2": (0.0, paper_F2)}


def _scene(law, m: float, k: float, x0: float, forcing) -> Scene:
    return Scene([Mass("mass", m=m, x0=x0)],
                 [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("dashpot", law, "ground", "mass")],
                 {} if forcing is None else {"mass": forcing})


def _error(sol, osc: BinghamOscillator, x0: float, forcing, t_end: float, dt: float,
           coulomb: bool = False, relative: bool = False) -> float:
    """``max |x - x_exact|`` on the grid ``n dt`` through the dense output (divided by
    ``max |x_exact|`` when ``relative``)."""
    x_ref = reference_for_grid(osc, x0=x0, forcing=forcing, dt=dt, t_end=t_end,
                               coulomb=coulomb).x
    grid = np.arange(len(x_ref)) * dt
    err = float(np.max(np.abs(sol.sol(grid)[:, sol.columns.index("x_mass")] - x_ref)))
    return err / float(np.max(np.abs(x_ref))) if relative else err


def _paper_run(name: str, gamma: float | None, rtol: float, **kw):
    """The paper's oscillator (m = 1, k = 100, tau = 1) with a Bingham dashpot of
    ``gamma`` (``None``: the ``coulomb`` law), and its error against the reference."""
    x0, forcing = SCENES[name]
    law = (get_law("coulomb").bind(tau=1.0, r=1.0) if gamma is None
           else get_law("bingham").bind(gamma=gamma, tau=1.0))
    sol = simulate(_scene(law, 1.0, 100.0, x0, forcing), method="radau5", rtol=rtol,
                   atol=1e-3 * rtol, t_end=5.0, **kw)
    assert sol.ok, sol.message
    osc = BinghamOscillator(1.0, 100.0, 1.0 if gamma is None else gamma, 1.0)
    return sol, _error(sol, osc, x0, forcing, 5.0, GRID_DT, coulomb=gamma is None)


@pytest.mark.parametrize("name", sorted(SCENES))
@pytest.mark.parametrize("gamma", [1e6, 1e9, 1e12])
def test_the_paper_scenes_run_through_in_the_coulomb_limit(name, gamma):
    # before the inverse form: bridges from gamma = 1e6 on, errors of 1e-6..1e-3, stops
    errors = []
    for rtol in (1e-5, 1e-9):
        sol, err = _paper_run(name, gamma, rtol)
        ref, ref_err = _paper_run(name, None, rtol)
        assert sol.stats.get("bridges", 0) == 0
        assert err <= 2.0 * ref_err + 1e-12 and err <= 10.0 * rtol
        # the coulomb law's cost: the same steps up to a few landings
        assert ref.stats["steps"] / 1.2 <= sol.stats["steps"] <= 1.2 * ref.stats["steps"]
        errors.append(err)
    assert errors[1] <= 1e-3 * errors[0]  # the error falls with rtol


@pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")
@pytest.mark.parametrize(("name", "gamma"), [("forcing-F2", 1e12), ("release-0.5", 1e9)])
def test_the_compiled_loop_gives_the_python_loop_run_in_the_coulomb_limit(name, gamma):
    ref, _ = _paper_run(name, gamma, 1e-8, compiled=False)
    fast, _ = _paper_run(name, gamma, 1e-8, compiled=True)
    assert ref.stats["loop"] == "python: compiled=False" and fast.stats["loop"] == "compiled"
    counters = ("steps", "rejected", "newton_iterations", "nfev", "events")
    assert {c: fast.stats[c] for c in counters} == {c: ref.stats[c] for c in counters}
    assert [(ev.kind, ev.from_branch, ev.to_branch) for ev in fast.events] == [
        (ev.kind, ev.from_branch, ev.to_branch) for ev in ref.events]
    scale = np.maximum(np.abs(ref.data).max(axis=0), 1e-300)
    assert np.all(np.abs(fast.data - ref.data) <= 1e-11 * scale)


@settings(max_examples=10, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(log_gamma=st.floats(3.0, 12.0), log_k=st.floats(-1.0, 4.0), log_m=st.floats(-1.0, 1.0),
       forced=st.booleans())
def test_radau5_agrees_with_the_exact_reference_across_the_coulomb_limit(log_gamma, log_k,
                                                                         log_m, forced):
    gamma, k, m, tau = 10.0 ** log_gamma, 10.0 ** log_k, 10.0 ** log_m, 1.0
    period = 2.0 * math.pi * math.sqrt(m / k)
    t_end, dt = 3.0 * period, period / 1000.0
    if forced:  # a burst above the yield force at 0.7 of the natural frequency
        x0, forcing = 0.0, SineBurst(4.0 * tau, 0.7 * 2.0 * math.pi / period, 1.5 * period)
    else:
        x0, forcing = 6.0 * tau / k, None
    law = get_law("bingham").bind(gamma=gamma, tau=tau)
    osc = BinghamOscillator(m, k, gamma, tau)
    t_end = dt * round(t_end / dt)
    scale = tau / k  # the displacement scale
    for rtol, bound in ((1e-6, 1e-4), (1e-11, 1e-8)):
        sol = simulate(_scene(law, m, k, x0, forcing), method="radau5", rtol=rtol,
                       atol=1e-3 * rtol * scale, t_end=t_end)
        assert sol.ok and sol.stats.get("bridges", 0) == 0, sol.message
        assert _error(sol, osc, x0, forcing, t_end, dt, relative=True) <= bound


@pytest.mark.parametrize("law", [
    get_law("herschel_bulkley").bind(gamma=1e12, tau=1.0, n=1.0),
    ElementLaw("my_fluid", "dashpot", "q/gamma - F + clip(F, -tau, tau)",
               ["gamma", "tau"]).bind(gamma=1e12, tau=1.0)], ids=["herschel-bulkley", "user"])
def test_a_law_of_the_same_shape_is_solved_alike(law):
    # the shape is read from the law's expression: Herschel-Bulkley n = 1, and a user's
    # Bingham scaled by 1/gamma, take the coulomb law's steps and error on forcing-F2
    rtol = 1e-9
    sol = simulate(_scene(law, 1.0, 100.0, 0.0, paper_F2), method="radau5", rtol=rtol,
                   atol=1e-3 * rtol, t_end=5.0)
    assert sol.ok and sol.stats.get("bridges", 0) == 0, sol.message
    ref, ref_err = _paper_run("forcing-F2", None, rtol)
    err = _error(sol, BinghamOscillator(1.0, 100.0, 1e12, 1.0), 0.0, paper_F2, 5.0, GRID_DT)
    assert err <= 2.0 * ref_err + 1e-12
    assert abs(sol.stats["steps"] - ref.stats["steps"]) <= 0.05 * ref.stats["steps"]
