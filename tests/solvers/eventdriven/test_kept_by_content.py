"""What ``radau5`` keeps per scene *content* (issue 27): a new scene object with the same
numbers reads the plan (and the start at rest) of the first, a scene that differs in
anything a run reads does not, and the numbers of every run are those of a run from
scratch, whatever ran before and in whatever order."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import simulate
from lumped.bench.scenes import PAPER_SCENES, generic_scene
from lumped.codegen import templates
from lumped.codegen.scene_key import scene_key
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.scene.forcing import SineBurst
from lumped.solvers.eventdriven import rest_bursts, setup
from lumped.solvers.eventdriven.setup import clear_plans, scene_plan


def _oscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0, x0=0.004, v0=0.0, force=None,
                names=("mass", "spring", "dashpot"), F0=None) -> Scene:
    node, spring, dashpot = names
    forces = {} if force is None else {node: force}
    return Scene(
        [Mass(node, m=m, x0=x0, v0=v0)],
        [Element(spring, get_law("linear_spring").bind(k=k), "ground", node),
         Element(dashpot, get_law("bingham").bind(gamma=gamma, tau=tau), "ground", node,
                 F0=F0)],
        forces,
    )


def _same_run(a, b) -> None:
    """Two solutions with the same numbers, bit for bit."""
    assert np.array_equal(a.data, b.data) and a.columns == b.columns
    assert a.stats == b.stats and (a.status, a.message) == (b.status, b.message)
    assert a.events == b.events and a.located_events == b.located_events
    assert a.indeterminate == b.indeterminate
    t = np.linspace(0.0, float(a.t[-1]), 129)
    assert np.array_equal(a.sol(t), b.sol(t))


def test_a_new_scene_object_with_the_same_numbers_reads_the_first_ones_plan():
    bench = {s.name: s for s in PAPER_SCENES}["forcing-F1"]
    first, again = generic_scene(bench), generic_scene(bench)
    assert first is not again and scene_key(first)[0] == scene_key(again)[0]
    plan = scene_plan(first)
    simulate(first, t_end=5.0)
    assert scene_plan(again) is plan
    assert "rest_start" in plan.__dict__  # (what the first run kept, the second reads)


@pytest.mark.parametrize("other", [
    lambda: _oscillator(k=math.nextafter(100.0, 200.0)),  # one bit of one number
    lambda: _oscillator(x0=0.004, v0=-0.0),  # -0.0 is not 0.0
    lambda: _oscillator(m=2.0),
    lambda: _oscillator(tau=1.5),
    lambda: _oscillator(F0=0.4),
    lambda: _oscillator(names=("mass", "spring", "damper")),
    lambda: _oscillator(names=("body", "spring", "dashpot")),
    lambda: _oscillator(force=0.3),
    lambda: _oscillator(force=SineBurst(0.5, 5.0, 1.0)),
    lambda: _oscillator(force=SineBurst(0.5, 5.0, 1.5)),
    lambda: Scene([Mass("mass", m=1.0, x0=0.004)],
                  [Element("spring", get_law("linear_spring").bind(k=100.0), "mass",
                           "ground"),
                   Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0),
                           "ground", "mass")]),
    lambda: Scene([Mass("mass", m=1.0, x0=0.004), Junction("j", x0=0.0)],
                  [Element("spring", get_law("linear_spring").bind(k=100.0), "ground",
                           "mass"),
                   Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0),
                           "mass", "j"),
                   Element("tie", get_law("linear_spring").bind(k=100.0), "j", "ground")]),
])
def test_a_scene_that_differs_in_anything_a_run_reads_has_its_own_plan(other):
    base = _oscillator()
    plan = scene_plan(base)
    assert scene_plan(_oscillator()) is plan
    scene = other()
    assert scene_key(scene)[0] != scene_key(base)[0]
    assert scene_plan(scene) is not plan


def test_a_forcing_of_any_other_kind_is_told_apart_by_identity():
    def f(t):
        return 0.1

    def g(t):
        return 0.1

    a, b, c = _oscillator(force=f), _oscillator(force=f), _oscillator(force=g)
    assert scene_plan(a) is scene_plan(b) and scene_plan(c) is not scene_plan(a)
    assert scene_key(_oscillator(force=SineBurst(1, 5.0, 1.0)))[0] != scene_key(
        _oscillator(force=SineBurst(1.0, 5.0, 1.0)))[0]  # (an int is not a float)


def _runs():
    """Runs of scenes at rest and moving, new objects and repeats, as (scene maker,
    keywords): their order is what the test changes."""
    burst = SineBurst(0.5, 5.0, 1.0)
    return [
        (lambda: _oscillator(force=burst), {"t_end": 3.0}),
        (lambda: _oscillator(k=100.5, force=burst), {"t_end": 3.0}),
        (lambda: _oscillator(force=SineBurst(0.5, 5.0, 1.0)), {"t_end": 2.0, "rtol": 1e-9}),
        (lambda: _oscillator(x0=0.5), {"t_end": 1.0}),  # moves: the general driver
        (lambda: _oscillator(x0=0.5), {"t_end": 1.0, "compiled": False,
                                       "method": "radau5"}),
        (lambda: _oscillator(), {"t_end": 2.0, "dt": 0.1}),
        (lambda: _oscillator(k=100.0 * (1 + 1e-6)), {"t_end": 2.0}),
    ]


def test_runs_give_the_same_numbers_in_any_order_and_from_scratch():
    runs = _runs()
    forward = [simulate(make(), **kw) for make, kw in runs]
    again = [simulate(make(), **kw) for make, kw in runs]  # new objects, kept plans
    backward = [simulate(make(), **kw) for make, kw in reversed(runs)][::-1]
    scratch = []
    for make, kw in runs:  # each from scratch: no plan, no law template kept
        clear_plans()
        templates._BY_LAW.clear()
        scratch.append(simulate(make(), **kw))
    for i in range(len(runs)):
        _same_run(forward[i], scratch[i])
        _same_run(again[i], scratch[i])
        _same_run(backward[i], scratch[i])


def test_a_time_events_probe_is_kept_on_the_start(monkeypatch):
    calls = []
    probe = rest_bursts._kept_at_time_event
    monkeypatch.setattr(rest_bursts, "_kept_at_time_event",
                        lambda *a: calls.append(a[3]) or probe(*a))
    first = simulate(_oscillator(force=SineBurst(0.5, 5.0, 1.0)), t_end=3.0, rtol=1e-8)
    assert calls == [1.0]
    again = simulate(_oscillator(force=SineBurst(0.5, 5.0, 1.0)), t_end=3.0, rtol=1e-8)
    assert calls == [1.0]  # the first run's probe
    _same_run(first, again)
    simulate(_oscillator(force=SineBurst(0.5, 5.0, 1.0)), t_end=3.0, rtol=1e-6)
    assert calls == [1.0, 1.0]  # another first step size: its own probe


def test_the_shared_plans_are_bounded():
    for i in range(setup.SHARED_PLANS + 5):
        scene_plan(_oscillator(k=100.0 + i))
    assert len(setup._SHARED) == setup.SHARED_PLANS


def test_the_time_events_and_the_first_step_are_kept_per_end_and_tolerances(monkeypatch):
    events, steps = [], []
    time_events, first_step = rest_bursts.time_events, rest_bursts._first_step
    monkeypatch.setattr(rest_bursts, "time_events",
                        lambda scene, t: events.append(t) or time_events(scene, t))
    monkeypatch.setattr(rest_bursts, "_first_step",
                        lambda s, o, st, t: steps.append((s.rtol, t)) or first_step(s, o, st, t))
    force = SineBurst(0.25, 7.0, 0.5)
    runs = [simulate(_oscillator(force=force), t_end=2.0, rtol=1e-7) for _ in range(2)]
    assert events == [2.0] and steps == [(1e-7, 2.0)]
    _same_run(*runs)
    simulate(_oscillator(force=force), t_end=2.5, rtol=1e-7)
    simulate(_oscillator(force=force), t_end=2.5, rtol=1e-5)
    assert events == [2.0, 2.5] and steps == [(1e-7, 2.0), (1e-7, 2.5), (1e-5, 2.5)]
