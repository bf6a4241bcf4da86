"""A position lock whose value the positions cannot hit (issue 29): ``q = x_b - x_a`` lies
on a lattice of spacing ``ulp(x)`` that misses ``L``, so Newton's lock row stays a
fraction of an ulp of the positions off, and the correction it asks of the forces
(``m ulp(x) / h^2``) is noise. Newton keeps such an iterate when every row is at the
rounding of its terms (:func:`lumped.solvers.newton.criteria.at_roundoff`), a law row's
terms counting the positions ``q`` is computed from
(:func:`lumped.solvers.implicit.step_system.law_scale`)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from _lock_scenes import loaded_string_chain

from lumped import simulate
from lumped.codegen.jit import numba_enabled
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

_LOAD = 2.6517535238691945
_TAU = 3.9413367058075166
_L = 0.22357337016105375


def _string_to_a_held_junction() -> Scene:
    # a loaded mass on a string to a junction held by Coulomb friction and a dashpot: the
    # load is below the friction's yield, so the mass comes to rest with the string taut
    # and the junction stuck (t = 1.3236)
    return Scene([Mass("m", m=1.0, v0=1.4061113287668847), Junction("j")],
                 [Element("s", get_law("string_spring").bind(k=0.19164306754609922, L=_L),
                          "j", "m"),
                  Element("d", get_law("coulomb").bind(tau=_TAU, r=1.0), "ground", "j"),
                  Element("c", get_law("newtonian").bind(c=0.25034763590404496),
                          "ground", "j")],
                 {"m": _LOAD})


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_a_taut_string_on_a_stuck_junction_comes_to_rest_at_the_load(method):
    dt = 1e-4
    sol = simulate(_string_to_a_held_junction(), method=method, dt=dt, t_end=1.5)
    assert sol.ok
    rest = sol.t >= 1.4
    xm, xj = sol.x["m"][rest], sol.x["j"][rest]
    ulp = math.ulp(float(np.abs(xm).max()))
    h = dt if method == "bdf1" else 2.0 * dt / 3.0
    # at rest: the velocities are the rounding of x = x_hat + h v, ulp(x) / h
    assert np.abs(sol.v["m"][rest]).max() <= 4.0 * ulp / h
    assert np.abs(sol.v["j"][rest]).max() <= 4.0 * ulp / h
    # the string taut on its lock, to the lattice of the positions
    assert np.abs((xm - xj) - _L).max() <= 4.0 * ulp
    # it carries the load, to the rounding of the momentum balance, m ulp(x) / h^2
    Fs = sol.F["s"][rest]
    assert np.abs(Fs - _LOAD).max() <= 4.0 * 1.0 * ulp / h**2
    # the junction's balance: the friction and the dashpot carry the string's force,
    # the friction stuck within its yield force
    assert np.abs(sol.F["d"][rest] + sol.F["c"][rest] - Fs).max() <= 8 * math.ulp(_LOAD)
    assert np.abs(sol.F["d"][rest]).max() <= _TAU


def test_radau5_holds_the_taut_string_at_rest_exactly():
    sol = simulate(_string_to_a_held_junction(), method="radau5", t_end=1.5)
    assert sol.ok
    assert sol.v["m"][-1] == pytest.approx(0.0, abs=1e-12)
    assert sol.F["s"][-1] == pytest.approx(_LOAD, rel=1e-12)
    assert sol.x["m"][-1] - sol.x["j"][-1] == pytest.approx(_L, rel=1e-12)


def _end(sol) -> np.ndarray:
    names = ("m0", "m1", "m2", "m3")
    return np.array([sol.x[n][-1] for n in names] + [sol.v[n][-1] for n in names])


_TIGHT = dict(method="radau5", t_end=0.2, rtol=1e-10, atol=1e-13)


@pytest.fixture(scope="module")
def python_loop_run():
    """radau5's Python loop on the loaded chain of strings at a tight tolerance (both
    strings taut from t = 0.19476; no bridge since the mode after an impact is decided
    by the balance of accelerations, two before)."""
    return simulate(loaded_string_chain(), compiled=False, **_TIGHT)


def test_radau5_at_a_tight_tolerance_on_a_loaded_string_chain_agrees_with_bdf2(
        python_loop_run):
    ref = python_loop_run
    assert ref.ok and ref.stats.get("bridges", 0) == 0
    # both strings taut at the end
    assert ref.x["m0"][-1] == pytest.approx(0.18922035336843843, abs=1e-12)
    assert ref.x["m1"][-1] - ref.x["m0"][-1] == pytest.approx(0.01, abs=1e-12)
    # bdf2 converges to it at second order (errors 8.4e-7 and 2.1e-7 in x)
    errs = [np.abs(_end(simulate(loaded_string_chain(), method="bdf2", dt=dt,
                                 t_end=0.2)) - _end(ref)).max() for dt in (4e-4, 2e-4)]
    assert errs[1] <= errs[0] / 3.0
    assert errs[1] <= 1e-5


def test_radau5_compiled_at_a_tight_tolerance_on_a_loaded_string_chain_is_the_python_run(
        python_loop_run):
    # the compiled loop gives the Python loop's numbers bit for bit (before, its bridges
    # there took steps of 1.2e-8 s, not 1.6e-8, and it stopped after 12 of them)
    ref = python_loop_run
    sol = simulate(loaded_string_chain(), compiled=True, **_TIGHT)
    assert sol.ok
    assert sol.stats.pop("loop") == "compiled" or not numba_enabled()
    assert sol.stats == {k: val for k, val in ref.stats.items() if k != "loop"}
    assert sol.message == ref.message
    assert np.array_equal(sol.data, ref.data)
