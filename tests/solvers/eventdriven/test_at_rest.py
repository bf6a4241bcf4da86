"""``radau5`` on a scene at rest throughout (:mod:`lumped.solvers.eventdriven.at_rest`):
the same solution as the general driver, and only for scenes proven at rest."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped import simulate
from lumped.bench.scenes import PAPER_SCENES, generic_scene
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.scene.forcing import SineBurst
from lumped.solvers.eventdriven import runner
from lumped.solvers.eventdriven.at_rest import REST_LOOP
from lumped.solvers.status import InconsistentInitialForce


def _general(scene, **kw):
    """The run of the general driver (the run at rest switched off)."""
    saved = runner.rest_run
    runner.rest_run = lambda scene, settings: None
    try:
        return simulate(scene, **kw)
    finally:
        runner.rest_run = saved


def _assert_same(fast, ref) -> None:
    assert fast.stats["loop"] == REST_LOOP and ref.stats["loop"] != REST_LOOP
    assert np.array_equal(fast.data, ref.data) and fast.columns == ref.columns
    assert {k: v for k, v in fast.stats.items() if k != "loop"} == {
        k: v for k, v in ref.stats.items() if k != "loop"}
    assert (fast.status, fast.message, fast.method) == (ref.status, ref.message, ref.method)
    assert fast.events == ref.events and fast.located_events == ref.located_events
    assert fast.stick_intervals() == ref.stick_intervals()
    assert fast.indeterminate == ref.indeterminate
    t_end = float(ref.t[-1])
    t = np.linspace(0.0, t_end, 257)
    assert np.array_equal(fast.sol(t), ref.sol(t))


def _oscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0, x0=0.005, v0=0.0, force=None,
                F0=None) -> Scene:
    forces = {} if force is None else {"mass": force}
    return Scene(
        [Mass("mass", m=m, x0=x0, v0=v0)],
        [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=gamma, tau=tau), "ground",
                 "mass", F0=F0)],
        forces,
    )


def _two_masses(x1: float, x2: float, tau1: float = 2.0, tau2: float = 1.0) -> Scene:
    lin, bing = get_law("linear_spring"), get_law("bingham")
    return Scene(
        [Mass("m1", m=1.0, x0=x1), Mass("m2", m=0.5, x0=x2)],
        [Element("s1", lin.bind(k=100.0), "ground", "m1"),
         Element("d1", bing.bind(gamma=1.0, tau=tau1), "ground", "m1"),
         Element("s2", lin.bind(k=50.0), "m1", "m2"),
         Element("d2", bing.bind(gamma=2.0, tau=tau2), "m1", "m2")],
    )


@pytest.mark.parametrize("kw", [
    {}, {"method": "radau5", "rtol": 1e-7}, {"method": "radau5", "rtol": 1e-7,
                                              "compiled": True},
    {"method": "radau5", "rtol": 1e-9, "compiled": False},
    {"method": "radau5", "dt": 0.01}, {"method": "radau5", "rtol": 1e-6, "dt": 0.003},
])
@pytest.mark.parametrize("name", ["release-0.005", "forcing-F1"])
def test_the_bench_scenes_at_rest_give_the_general_solution(kw, name):
    bench = next(s for s in PAPER_SCENES if s.name == name)
    scene = generic_scene(bench)
    _assert_same(simulate(scene, t_end=bench.t_end, **kw),
                 _general(scene, t_end=bench.t_end, **kw))


@pytest.mark.parametrize("scene", [
    _oscillator(x0=-0.004),
    _oscillator(x0=0.0),
    _oscillator(x0=0.002, force=0.5),  # a constant load inside the band: k x0 - f = -0.3
    _oscillator(x0=0.005, F0=-0.5),  # the user's force, the consistent one
    _oscillator(x0=0.005, F0=0.3),  # ... one the law admits, off the balance
    _two_masses(0.004, 0.01),
    _oscillator(x0=0.0, force=SineBurst(0.5, 5.0, 1.0)),  # a burst below yield
    _oscillator(x0=0.0, force=SineBurst(0.0, 5.0, 1.0)),  # a burst of zero amplitude
    _oscillator(x0=0.003, force=SineBurst(-0.4, 7.0, 5.0)),  # ... past t_end: no event
], ids=["negative", "zero", "constant load", "user F0", "user F0 off balance",
        "two masses", "burst", "zero burst", "burst past t_end"])
def test_other_scenes_at_rest_give_the_general_solution(scene):
    _assert_same(simulate(scene, t_end=3.0), _general(scene, t_end=3.0))


@settings(max_examples=40, deadline=None)
@given(m=st.floats(0.01, 100.0), k=st.floats(0.1, 1e5), gamma=st.floats(1e-3, 1e3),
       tau=st.floats(1e-3, 1e3), frac=st.floats(-0.99, 0.99), load=st.floats(-0.99, 0.99),
       t_end=st.floats(1e-3, 100.0))
def test_at_rest_in_the_stick_band_gives_the_general_solution(m, k, gamma, tau, frac, load,
                                                              t_end):
    # the dashpot carries f - k x0 = tau (load - frac): inside its band when |.| < tau
    f = load * tau
    x0 = (f - frac * tau) / k
    if not abs(f - k * x0) < 0.99 * tau:  # (x0 rounded)
        return
    scene = _oscillator(m=m, k=k, gamma=gamma, tau=tau, x0=x0, force=f or None)
    _assert_same(simulate(scene, t_end=t_end, rtol=1e-8), _general(scene, t_end=t_end,
                                                                    rtol=1e-8))


@settings(max_examples=25, deadline=None)
@given(d1=st.floats(-0.99, 0.99), d2=st.floats(-0.99, 0.99))
def test_two_masses_at_rest_give_the_general_solution(d1, d2):
    # d2: the force of d2 over its tau2 = 1 (-k2 (x2 - x1)); d1: that of d1 over tau1 = 2
    # (m1's balance: F_d1 = F_s2 + F_d2 - F_s1 = -k1 x1)
    x21 = -d2 * 1.0 / 50.0
    x1 = -d1 * 2.0 / 100.0
    scene = _two_masses(x1, x1 + x21)
    _assert_same(simulate(scene, t_end=2.0), _general(scene, t_end=2.0))


def _maxwell() -> Scene:
    """A mass on a spring to a junction, the junction on a Bingham dashpot to ground."""
    return Scene(
        [Mass("mass", m=1.0, x0=0.001), Junction("j")],
        [Element("spring", get_law("linear_spring").bind(k=100.0), "j", "mass"),
         Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "j")],
    )


def _parallel_locks() -> Scene:
    """Two Bingham dashpots in parallel hold one mass (their split is free)."""
    bing = get_law("bingham")
    return Scene(
        [Mass("mass", m=1.0, x0=0.005)],
        [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
         Element("d1", bing.bind(gamma=1.0, tau=1.0), "ground", "mass"),
         Element("d2", bing.bind(gamma=2.0, tau=0.5), "ground", "mass")],
    )


@pytest.mark.parametrize("scene", [
    _oscillator(x0=0.0100001),  # k x0 just past tau = 1: breaks out at once
    _oscillator(x0=-0.0100001),
    _oscillator(x0=0.01),  # k x0 = tau exactly: on the yield limit
    _oscillator(x0=0.005, v0=1e-9),  # an initial velocity
    _oscillator(x0=0.0, force=SineBurst(1.5, 5.0, 1.0)),  # a sine burst past yield
    _oscillator(x0=0.0, force=lambda t: 0.0),  # a callable of t
    _oscillator(x0=0.0, force=1.5),  # a constant load past the band
    _two_masses(0.0, 0.03),  # d2 loaded past tau2 = 1 (k2 x = 1.5)
    _maxwell(),  # a junction (its velocity is the limit system's)
    _parallel_locks(),  # locks in parallel (cones)
], ids=["past yield", "past yield, negative", "at yield", "velocity", "burst past yield",
        "callable", "constant past yield", "two masses, past yield",
        "junction", "locks in parallel"])
def test_a_scene_not_proven_at_rest_runs_the_general_driver(scene):
    sol = simulate(scene, t_end=2.0)
    assert sol.stats["loop"] != REST_LOOP
    ref = _general(scene, t_end=2.0)
    assert np.array_equal(sol.data, ref.data)


@settings(max_examples=30, deadline=None)
@given(k=st.floats(1.0, 1e4), tau=st.floats(1e-2, 1e2), frac=st.floats(1.0, 10.0),
       sign=st.sampled_from([-1.0, 1.0]))
def test_loaded_past_yield_never_takes_the_run_at_rest(k, tau, frac, sign):
    scene = _oscillator(k=k, tau=tau, x0=sign * frac * tau / k)
    sol = simulate(scene, t_end=0.5, rtol=1e-6)
    assert sol.stats["loop"] != REST_LOOP


def test_bad_keywords_and_states_raise_as_in_the_general_driver():
    scene = _oscillator()
    with pytest.raises(TypeError, match="no keyword argument 'nope'"):
        simulate(scene, t_end=1.0, nope=1)
    with pytest.raises(ValueError, match="max_steps"):
        simulate(scene, t_end=1.0, max_steps=0)
    with pytest.raises(InconsistentInitialForce, match="F0 = 3.0"):  # beyond tau = 1
        simulate(_oscillator(x0=0.005, F0=3.0), t_end=1.0)


def _burst_pair(a1: float, a2: float, t1: float, t2: float) -> Scene:
    """The two masses of :func:`_two_masses` at rest, each under its own sine burst."""
    lin, bing = get_law("linear_spring"), get_law("bingham")
    return Scene(
        [Mass("m1", m=1.0, x0=0.002), Mass("m2", m=0.5, x0=0.003)],
        [Element("s1", lin.bind(k=100.0), "ground", "m1"),
         Element("d1", bing.bind(gamma=1.0, tau=2.0), "ground", "m1"),
         Element("s2", lin.bind(k=50.0), "m1", "m2"),
         Element("d2", bing.bind(gamma=2.0, tau=1.0), "m1", "m2")],
        {"m1": SineBurst(a1, 3.0, t1), "m2": SineBurst(a2, 11.0, t2)},
    )


@pytest.mark.parametrize("compiled", [None, True, False])
@pytest.mark.parametrize("scene", [
    _burst_pair(0.5, 0.3, 0.7, 1.9),  # two time events
    _burst_pair(0.5, 0.3, 1.2, 1.2),  # both bursts end together: one time event
    _burst_pair(-0.8, 0.2, 0.4, 2.5),  # the second past t_end
], ids=["two events", "one event", "one inside"])
def test_bursts_below_yield_give_the_general_solution(scene, compiled):
    kw = {"t_end": 2.0, "rtol": 1e-7, "compiled": compiled}
    _assert_same(simulate(scene, **kw), _general(scene, **kw))


@settings(max_examples=40, deadline=None)
@given(amp=st.floats(-2.0, 2.0), omega=st.floats(0.1, 100.0), t_off=st.floats(0.01, 3.0),
       frac=st.floats(-0.99, 0.99), t_end=st.floats(0.05, 4.0),
       compiled=st.sampled_from([None, True, False]), dt=st.sampled_from([None, 0.01]))
def test_a_burst_gives_the_general_solution(amp, omega, t_off, frac, t_end, compiled, dt):
    # tau = 1, k = 100: the dashpot holds k x0 = frac at rest; a burst of |amp| up to 2
    # stays inside the band or breaks out (then the general driver runs both)
    scene = _oscillator(x0=frac / 100.0, force=SineBurst(amp, omega, t_off))
    kw = {"t_end": t_end, "rtol": 1e-7, "compiled": compiled, "dt": dt}
    sol, ref = simulate(scene, **kw), _general(scene, **kw)
    if sol.stats["loop"] == REST_LOOP:
        _assert_same(sol, ref)
    else:
        assert np.array_equal(sol.data, ref.data) and sol.events == ref.events
    if abs(frac) + abs(amp) < 0.9:  # inside the band by a margin: proven at rest
        assert sol.stats["loop"] == REST_LOOP


def test_a_negative_zero_velocity_reads_as_the_driver_sets_it():
    # the start's mode choice sets the stuck dashpot's rate exactly: v = +0.0
    for force in (None, SineBurst(0.5, 5.0, 1.0)):
        scene = _oscillator(x0=0.004, v0=-0.0, force=force)
        sol, ref = simulate(scene, t_end=2.0), _general(scene, t_end=2.0)
        assert sol.stats["loop"] == REST_LOOP
        assert np.array_equal(np.signbit(sol.data), np.signbit(ref.data))


def test_the_kept_start_serves_its_scene_only_and_in_any_order():
    # the start is kept per scene object: a scene with other numbers reads its own, and
    # the runs of one scene give the same solution whatever ran before
    a = _oscillator(x0=0.004, force=SineBurst(0.5, 5.0, 1.0))
    b = _oscillator(x0=-0.003, force=SineBurst(0.5, 5.0, 1.0))
    first = {name: simulate(sc, t_end=t, rtol=rtol) for name, sc, t, rtol in
             (("a3", a, 3.0, 1e-6), ("b3", b, 3.0, 1e-6), ("a2", a, 2.0, 1e-9))}
    fresh = {"a3": _oscillator(x0=0.004, force=SineBurst(0.5, 5.0, 1.0)),
             "b3": _oscillator(x0=-0.003, force=SineBurst(0.5, 5.0, 1.0)),
             "a2": _oscillator(x0=0.004, force=SineBurst(0.5, 5.0, 1.0))}
    for name, t, rtol in (("a2", 2.0, 1e-9), ("b3", 3.0, 1e-6), ("a3", 3.0, 1e-6)):
        again = simulate(fresh[name], t_end=t, rtol=rtol)
        assert np.array_equal(first[name].data, again.data)
        _assert_same(again, _general(fresh[name], t_end=t, rtol=rtol))
    assert first["a3"].data[0, 1] == 0.004 and first["b3"].data[0, 1] == -0.003


def test_one_scene_run_again_and_again_gives_the_general_solution_each_time():
    # the start and the interval up to the first time event are kept on the scene: runs
    # that end before the burst ends, past it, compiled or not, sampled or not, in any
    # order, each give the general driver's solution on a fresh scene
    def make():
        return _burst_pair(0.5, 0.3, 0.7, 1.9)

    scene = make()
    for kw in ({"t_end": 0.5}, {"t_end": 2.5, "compiled": False}, {"t_end": 1.0},
               {"t_end": 2.5, "rtol": 1e-9, "compiled": True}, {"t_end": 0.7},
               {"t_end": 2.5, "dt": 0.01}, {"t_end": 1.9 + 1e-15}, {"t_end": 2.5}):
        kw["method"] = "radau5"
        _assert_same(simulate(scene, **kw), _general(make(), **kw))


def test_a_scene_given_other_nodes_or_forcing_reads_no_kept_start():
    # what is kept lives on the scene's plan, made again when the nodes, elements or
    # forcing objects are other objects (each of them immutable)
    scene = _oscillator(x0=0.004, force=SineBurst(0.5, 5.0, 1.0))
    simulate(scene, t_end=2.0)
    scene.nodes = (Mass("mass", m=1.0, x0=-0.002),)
    _assert_same(simulate(scene, t_end=2.0),
                 _general(_oscillator(x0=-0.002, force=SineBurst(0.5, 5.0, 1.0)), t_end=2.0))
    scene.forcing = (SineBurst(0.3, 9.0, 0.5),)
    _assert_same(simulate(scene, t_end=2.0),
                 _general(_oscillator(x0=-0.002, force=SineBurst(0.3, 9.0, 0.5)), t_end=2.0))
