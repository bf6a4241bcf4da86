"""The method registry and the argument checks of ``simulate`` (issue 7, the layout)."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import lumped
from lumped import Element, Mass, Scene, Solution, Status, get_law, simulate
from lumped.solvers import registry
from lumped.solvers.registry import METHOD_REGISTRY, RunSettings, register_method
from lumped.solvers.status import Event, RawRun


def oscillator() -> Scene:
    return Scene(
        [Mass("mass", m=1.0, x0=0.5)],
        [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "mass")],
    )


@pytest.fixture
def restore_registry():
    saved = (dict(METHOD_REGISTRY), set(registry.FIXED_STEP_METHODS), registry.METHODS)
    yield
    METHOD_REGISTRY.clear()
    METHOD_REGISTRY.update(saved[0])
    registry.FIXED_STEP_METHODS.clear()
    registry.FIXED_STEP_METHODS.update(saved[1])
    registry.METHODS = saved[2]


@pytest.mark.parametrize("method", ["bdf1", "bdf2", "closed-bdf1", "closed-bdf2", "exact"])
def test_fixed_step_methods_need_dt(method):
    with pytest.raises(ValueError, match="`dt` is required"):
        simulate(oscillator(), method=method, t_end=0.1)


def test_auto_without_dt_runs_the_adaptive_method():
    """Neither ``dt`` nor tolerances: ``auto`` runs ``radau5`` at its defaults (it asked for
    ``dt`` on the paper's scene before; see ``resolve_method``)."""
    sol = simulate(oscillator(), t_end=0.1)
    assert sol.method == "radau5" and sol.ok


@pytest.mark.parametrize("name", ["rtol", "atol"])
@pytest.mark.parametrize("bad", [0.0, -1e-6, math.nan, math.inf])
def test_tolerances_must_be_positive_finite(name, bad):
    with pytest.raises(ValueError, match=f"`{name}`"):
        simulate(oscillator(), method="bdf2", dt=1e-3, t_end=0.1, **{name: bad})


@pytest.mark.parametrize("name", ["rtol", "atol"])
def test_fixed_step_methods_refuse_tolerances(name):
    with pytest.raises(ValueError, match=f"`{name}` applies to adaptive methods only"):
        simulate(oscillator(), method="bdf2", dt=1e-3, t_end=0.1, **{name: 1e-6})


def test_fixed_step_methods_refuse_unknown_keywords():
    with pytest.raises(TypeError, match="'bogus'"):
        simulate(oscillator(), method="closed-bdf2", dt=1e-3, t_end=0.1, bogus=1)


def test_registered_method_gets_settings_and_its_raw_run_is_wrapped(restore_registry):
    seen: list[RunSettings] = []

    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        seen.append(settings)
        t = np.array([0.0, settings.t_end])
        data = np.column_stack([t, [0.5, 0.25], [0.0, -1.0], [50.0, 25.0], [-50.0, -25.0]])
        ev = Event(t=0.05, element="dashpot", kind="switch", from_branch=0, to_branch=1)
        return RawRun(data, {"steps": 1}, events=[ev], indeterminate={"dashpot": [(0.0, 0.1)]})

    register_method("fake-adaptive", runner)
    assert "fake-adaptive" in registry.METHODS
    sol = simulate(oscillator(), method="fake-adaptive", t_end=0.1, rtol=1e-6, atol=1e-9,
                   order=5)
    assert isinstance(sol, Solution) and sol.method == "fake-adaptive"
    (s,) = seen
    assert (s.t_end, s.dt, s.rtol, s.atol, s.throw) == (0.1, None, 1e-6, 1e-9, True)
    assert dict(s.extra) == {"order": 5}
    assert sol.status is Status.SUCCESS and sol.stats == {"steps": 1}
    assert sol.events == (Event(0.05, "dashpot", "switch", 0, 1),)
    assert sol.indeterminate == {"dashpot": [(0.0, 0.1)]}
    np.testing.assert_array_equal(sol.x["mass"], [0.5, 0.25])


def test_register_method_checks_its_arguments(restore_registry):
    with pytest.raises(ValueError, match="`name`"):
        register_method("auto", lambda scene, settings: None)
    with pytest.raises(TypeError, match="`runner`"):
        register_method("x", 3)


def test_registered_fixed_step_method_needs_dt(restore_registry):
    register_method("fake-fixed", METHOD_REGISTRY["bdf1"], fixed_step=True)
    with pytest.raises(ValueError, match="`dt` is required"):
        simulate(oscillator(), method="fake-fixed", t_end=0.1)
    a = simulate(oscillator(), method="fake-fixed", dt=1e-3, t_end=0.1)
    b = simulate(oscillator(), method="bdf1", dt=1e-3, t_end=0.1)
    np.testing.assert_array_equal(a.data, b.data)


def test_fixed_step_solutions_derive_their_events_from_the_samples():
    """A fixed-step runner locates no events (``located_events`` is None): the solution
    reads the branch switches off the samples; here the release of the stuck dashpot."""
    sol = simulate(oscillator(), method="closed-bdf2", dt=1e-3, t_end=0.01)
    assert sol.located_events is None and sol.indeterminate == {}
    assert [(e.t, e.element, e.kind) for e in sol.events] == [(0.001, "dashpot", "switch")]


def test_status_has_the_shared_members():
    assert {s.name for s in Status} >= {
        "SUCCESS", "MAX_ITERS", "DIVERGED", "SINGULAR", "NON_FINITE", "BRANCH_LOST",
        "TOO_MANY_EVENTS", "STEP_TOO_SMALL", "INCONSISTENT"}


def test_top_level_is_small():
    assert set(lumped.__all__) == {
        "simulate", "Scene", "Mass", "Junction", "Element", "ElementLaw", "get_law",
        "load_scene", "Solution", "Status", "SolverError", "BranchError",
        "InconsistentInitialForce", "GROUND", "__version__"}
    for name in lumped.__all__:
        assert getattr(lumped, name) is not None


@pytest.mark.parametrize("name", ["integrate", "BinghamOscillator", "Trajectory", "SineBurst",
                                  "METHODS", "exact_solution"])
def test_retired_top_level_names_are_gone(name):
    """0.2 retired the names 0.1 served with a DeprecationWarning (see the CHANGELOG)."""
    assert name not in lumped.__all__
    with pytest.raises(AttributeError, match=name):
        getattr(lumped, name)


def test_unknown_top_level_name_is_an_attribute_error():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(AttributeError, match="no_such_name"):
            lumped.no_such_name  # noqa: B018
