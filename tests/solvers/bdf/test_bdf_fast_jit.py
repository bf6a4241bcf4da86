"""The fast path of ``jit-bdf1``/``jit-bdf2`` (the default) against the reference.

The fast path (:mod:`lumped.solvers.bdf.fast_codegen`, :mod:`lumped.solvers.bdf.fast_jit`) solves
the same step system as ``bdf1``/``bdf2`` with the same convergence tests, but its own
Newton sequence and an explicit inverse for the linear solves: the two agree to the
Newton tolerance, not bit for bit. Bound tested: ``|a - b| <= 1e-10 (1 + max |b|)`` per
column over the whole run (the default ``rtol`` is 1e-10; what is measured is at most
about 1e-11, while a step-size error is of order ``dt``), and the exact properties of the
reference (eq. 19, a stuck velocity of exactly 0) are kept (``test_fixed_step_jit.py``).
Every step must be taken by the fast path itself (no hand-over) on these scenes, so the
comparison tests the fast path and not the faithful port it falls back on.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from lumped import Element, Mass, Scene, simulate
from lumped.io import load_scene
from lumped.laws import ElementLaw, get_law
from lumped.scenarios import scenario_scene
from lumped.solvers.newton.options import NewtonOptions

EXAMPLES = Path(__file__).resolve().parents[3] / "examples"
DRAG = ElementLaw("quadratic_drag_fast", "dashpot", "F = c*q*Abs(q)", ["c"])


def custom():
    """A user law, not piecewise linear (its Jacobian changes every iteration) and not a
    known monotone built-in (the fold check runs every step)."""
    return Scene(
        [Mass("mass", 2.0, x0=0.4)],
        [Element("spring", get_law("linear_spring").bind(k=30.0), "ground", "mass"),
         Element("drag", DRAG.bind(c=0.7), "ground", "mass")],
        {"mass": lambda t: 3.0 * math.cos(4.0 * t)},
    )


SCENES = {
    "release-0.5": lambda: scenario_scene("release-0.5"),
    "forcing-F2": lambda: scenario_scene("forcing-F2"),
    "maxwell": lambda: load_scene(EXAMPLES / "maxwell.toml")[0],
    "two-masses": lambda: load_scene(EXAMPLES / "two-masses.toml")[0],
    "custom": custom,
}


def assert_close(a, b, bound=1e-10):
    assert a.ok and b.ok and a.columns == b.columns and a.data.shape == b.data.shape
    scale = 1.0 + np.max(np.abs(b.data), axis=0)
    err = np.max(np.abs(a.data - b.data), axis=0) / scale
    assert np.all(err <= bound), dict(zip(a.columns, err, strict=True))


@pytest.mark.parametrize("formula", ["bdf1", "bdf2"])
@pytest.mark.parametrize("name", list(SCENES))
def test_fast_path_takes_every_step_and_agrees_with_the_reference(name, formula):
    scene = SCENES[name]()
    a = simulate(scene, method=f"jit-{formula}", dt=1e-3, t_end=4.0, fast=True)
    b = simulate(scene, method=formula, dt=1e-3, t_end=4.0)
    assert a.stats["fast_steps"] == a.stats["steps"] == 4000
    assert a.stats["handovers"] == 0 and "fallback" not in a.stats
    assert_close(a, b)
    # the faithful port is still there, bit for bit
    c = simulate(scene, method=f"jit-{formula}", dt=1e-3, t_end=4.0, fast=False)
    assert np.array_equal(c.data, b.data) and "fast_steps" not in c.stats


def test_a_step_the_fast_path_cannot_take_goes_to_the_faithful_port():
    """At rtol 5e-16 the fast Newton's linearised row scales cannot be met on two steps of
    the two-masses scene: those steps are handed over (and taken: the faithful port uses
    the round-off scales), the fast path resumes, and the run agrees with the reference."""
    scene = SCENES["two-masses"]()
    opts = NewtonOptions(rtol=5e-16, atol=5e-18)
    a = simulate(scene, method="jit-bdf2", dt=1e-2, t_end=4.0, options=opts, fast=True)
    b = simulate(scene, method="bdf2", dt=1e-2, t_end=4.0, options=opts)
    assert a.stats["handovers"] >= 1
    assert a.stats["fast_steps"] + a.stats["handovers"] == a.stats["steps"] == 400
    assert "fallback" not in a.stats
    assert_close(a, b, 1e-12)


def test_failures_are_reported_by_the_faithful_port():
    """A Newton failure and a non-finite force on a step the fast path hands over are
    reported as by the reference: the step, the time, the element or node."""
    from lumped.solvers.bdf.fixed_step_jit import run_bdf_jit

    def run(fast):
        # a load whose momentum balance overflows from t = 0.11 (a tolerance below eps,
        # once used here, is now met where every row is at round-off: at_roundoff)
        scene = SCENES["maxwell"]()
        scene.forcing = (lambda t: 1.7e308 if t > 0.105 else 1.0, None)
        return run_bdf_jit(scene, method="jit-bdf2", dt=1e-2, n_steps=400, throw=False,
                           fast=fast)

    fast, slow = run(True), run(False)
    assert fast.status.name == "NON_FINITE" and "Newton failed" in fast.message
    assert fast.status is slow.status and fast.message == slow.message
    assert fast.stats["handovers"] == 1 and fast.stats["steps"] == slow.stats["steps"]
    scene = scenario_scene("release-0.5")
    scene.forcing = (lambda t: math.nan if t > 0.0105 else 1.0,)
    with pytest.raises(ValueError, match=r"force on node 'mass' returned nan at t = 0.011"):
        simulate(scene, method="jit-bdf1", dt=1e-3, t_end=1.0)


def test_a_new_structure_runs_on_the_port_until_the_process_has_run_it_long(monkeypatch,
                                                                          tmp_path):
    """``fast=None`` (the default) runs a structure whose fast loop is not built on the
    faithful port until this process has run it for ``FAST_MIN_STEPS`` steps in all (the
    port's tally, this run's included); then it compiles the fast loop, and every later
    run of the structure, with any numbers, takes it. ``fast=True`` takes it at once."""
    from lumped.solvers.bdf import core_jit, fast_codegen, fixed_step_jit

    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))  # an empty disk cache
    monkeypatch.setattr(fast_codegen, "_BY_KEY", {})
    monkeypatch.setattr(fast_codegen, "LOADED_MODULES", {})
    monkeypatch.setattr(core_jit, "port_cached", lambda: True)  # (as on a used machine)
    monkeypatch.setattr(fixed_step_jit, "FAST_MIN_STEPS", 1000)
    scene = scenario_scene("release-0.5")
    first = simulate(scene, method="jit-bdf2", dt=1e-3, t_end=0.6)
    assert "fast_steps" not in first.stats  # (600 steps: the port)
    again = simulate(scene, method="jit-bdf2", dt=1e-3, t_end=0.6)
    assert again.stats["fast_steps"] == 600  # (1200 in all: the fast loop, compiled)
    assert_close(again, first)
    assert fast_codegen.fast_module_cached(scene)
    other = Scene([Mass("mass", 2.5, x0=0.25)],
                  [Element("spring", get_law("linear_spring").bind(k=37.0), "ground", "mass"),
                   Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=0.75), "ground",
                           "mass")])
    assert simulate(other, method="jit-bdf2", dt=1e-3, t_end=0.1).stats["fast_steps"] == 100
    # a new structure (a Newtonian dashpot): the port, unless asked
    viscous = Scene([Mass("mass", 2.5, x0=0.25)],
                    [Element("spring", get_law("linear_spring").bind(k=37.0), "ground",
                             "mass"),
                     Element("dashpot", get_law("newtonian").bind(c=0.5), "ground", "mass")])
    assert "fast_steps" not in simulate(viscous, method="jit-bdf2", dt=1e-3, t_end=0.1).stats
    forced = simulate(viscous, method="jit-bdf2", dt=1e-3, t_end=0.1, fast=True)
    assert forced.stats["fast_steps"] == 100


def test_fast_keyword_is_checked():
    with pytest.raises(TypeError, match="`fast` must be True, False or None, got 'yes'"):
        simulate(scenario_scene("release-0.5"), method="jit-bdf1", dt=1e-3, t_end=0.01,
                 fast="yes")
    with pytest.raises(TypeError, match="takes no keyword argument"):
        simulate(scenario_scene("release-0.5"), method="bdf1", dt=1e-3, t_end=0.01,
                 fast=True)


def test_fast_module_is_memoised_per_scene_structure(monkeypatch):
    """A second run of a scene does not generate the fast loop's source again (sympy
    printing, about 0.4 ms a run); a run of another structure does."""
    from lumped.solvers.bdf import fast_codegen as jit_fast

    scene = scenario_scene("release-0.5")
    first = simulate(scene, method="jit-bdf1", dt=1e-3, t_end=0.05, fast=True)

    def refuse(_scene):
        raise AssertionError("source generated again")

    monkeypatch.setattr(jit_fast, "fast_source", refuse)
    again = simulate(scenario_scene("release-0.5"), method="jit-bdf1", dt=1e-3, t_end=0.05,
                     fast=True)
    assert np.array_equal(first.data, again.data)
    other = Scene([Mass("mass", 1.0, x0=0.1)],  # a spring constant no other test uses
                  [Element("spring", get_law("linear_spring").bind(k=37.25), "ground", "mass")])
    with pytest.raises(AssertionError, match="source generated again"):
        simulate(other, method="jit-bdf1", dt=1e-3, t_end=0.05, fast=True)
