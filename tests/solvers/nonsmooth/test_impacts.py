"""Impacts, locks and hard points in the generic fixed-step solver (issue 11).

The impact scene has an exact solution (:func:`lumped.bench.impact_scenes.exact_impact`):
a mass on a spring with an inextensible string (``k = m = 1``, ``L = 0.5``) released at
``x = 0, v = 1`` moves as ``x = sin t`` until ``t = pi/6``, the string stops it
(perfectly inelastic), and then ``x = 0.5 cos(t - pi/6)``.
"""

from __future__ import annotations

import math
import pickle

import numpy as np
import pytest

from lumped import simulate
from lumped.bench.impact_scenes import exact_impact, impact_scene, lock_scene
from lumped.laws import ElementLaw, get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.nonsmooth.impacts import impact_velocities, locking_elements

T_IMPACT = math.pi / 6


def _energy(sol, k: float = 1.0, m: float = 1.0) -> np.ndarray:
    x, v = sol.x["mass"], sol.v["mass"]
    return 0.5 * m * v**2 + 0.5 * k * x**2


@pytest.mark.parametrize("dt", [1e-3, 1e-4])
@pytest.mark.parametrize("method", ["bdf1", "bdf2", "auto"])
def test_impact_scene_within_3_dt_of_exact(method, dt):
    sol = simulate(impact_scene(), method=method, dt=dt, t_end=1.5)
    assert sol.ok
    err = np.abs(sol.x["mass"] - exact_impact(sol.t)).max()
    assert err <= 3 * dt
    # energy: 1/2 before, the inelastic 1/8 after, never more (beyond the method's error)
    E = _energy(sol)
    after = sol.t > T_IMPACT + dt
    assert E[after].max() <= 0.125 + 3 * dt
    assert np.all(np.diff(E) <= 1e-12) if method == "bdf1" else True
    # the impact is an event: time, element, impulse m v = sqrt(3)/2, energy lost 3/8
    (ev,) = sol.events
    assert ev.kind == "impact" and ev.element == "string"
    assert abs(ev.t - T_IMPACT) <= 2 * dt
    assert ev.impulse == pytest.approx(math.sqrt(3) / 2, abs=3 * dt)
    assert ev.energy_lost == pytest.approx(0.375, abs=3 * dt)


@pytest.mark.parametrize(("method", "bound"), [("bdf1", 1e-3), ("bdf2", 2e-6),
                                             ("jit-bdf2", 2e-6)])
def test_dense_output_jumps_at_the_impact(method, bound):
    # the dense output has the impact as a knot (the states just before and after), so
    # the velocity jumps there; it used to be interpolated across the impact's step: v off
    # by 0.55 and x by 1e-4 (120 times the samples' error) inside that step at dt 1e-3
    dt = 1e-3
    sol = simulate(impact_scene(), method=method, dt=dt, t_end=1.5)
    (ev,) = sol.events
    t = np.linspace(0.0, 1.5, 150_001)
    t = t[np.abs(t - T_IMPACT) > abs(ev.t - T_IMPACT)]  # off the impact's own error
    rows = sol.sol(t)
    v_exact = np.where(t < T_IMPACT, np.cos(t), -0.5 * np.sin(t - T_IMPACT))
    assert np.abs(rows[:, 1] - exact_impact(t)).max() <= bound
    assert np.abs(rows[:, 2] - v_exact).max() <= bound
    # at the event time: just before, the free motion's speed; from it on, the stop
    before, at = sol.sol(np.nextafter(ev.t, 0.0)), sol.sol(ev.t)
    assert before[2] == pytest.approx(math.sqrt(3) / 2, abs=3 * dt)
    assert abs(at[2]) <= 1e-12
    # and it travels with the solution (sweeps send solutions between processes)
    assert np.array_equal(pickle.loads(pickle.dumps(sol)).sol(t[::1000]), rows[::1000])


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_dense_output_of_the_lock_scene_holds_from_the_impact(method):
    sol = simulate(lock_scene(), method=method, dt=1e-3, t_end=2.0)
    (ev,) = sol.events
    rows = sol.sol(np.linspace(ev.t, 2.0, 20_001))
    assert np.all(rows[:, 1] == 0.5)
    assert np.abs(rows[:, 2]).max() <= 1e-12
    assert np.abs(rows[:, 3] + rows[:, 4] - 1.0).max() <= 1e-8


def test_bdf2_across_an_impact_converges_at_second_order():
    errs = []
    for dt in (4e-3, 2e-3, 1e-3):
        sol = simulate(impact_scene(), method="bdf2", dt=dt, t_end=1.5)
        errs.append(np.abs(sol.x["mass"] - exact_impact(sol.t)).max())
    slopes = np.diff(np.log(errs)) / np.log(0.5)
    assert np.all(slopes > 1.7), errs


@pytest.mark.parametrize("method", ["bdf1", "bdf2", "auto"])
@pytest.mark.parametrize("dt", [1e-3, 1e-4])
def test_lock_scene_holds_at_L_and_splits_the_load(method, dt):
    sol = simulate(lock_scene(), method=method, dt=dt, t_end=2.0)
    assert sol.ok
    (ev,) = sol.events
    after = sol.t > ev.t  # every sample from the end of the impact's step on
    assert np.abs(sol.x["mass"][after] - 0.5).max() <= 1e-9
    assert np.abs(sol.v["mass"][after]).max() <= 1e-9
    total = sol.F["string"][after] + sol.F["friction"][after]
    assert np.abs(total - 1.0).max() <= 1e-8
    # the split is not unique: reported, and the friction element stays within its yield
    assert np.abs(sol.F["friction"]).max() <= 0.2 * (1 + 1e-9)
    assert sol.F["string"][after].min() >= 0.5 - 1e-9  # a taut string pulls at least k L
    for name in ("string", "friction"):
        spans = sol.indeterminate[name]
        assert spans[0][0] <= ev.t + 3 * dt and spans[-1][1] == pytest.approx(2.0)
        assert spans[-1][0] <= ev.t + 6 * dt
    assert set(sol.indeterminate) == {"string", "friction"}


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("rest", [1e-2, 1e-3, 1e-4])
def test_lock_reached_late_in_a_step_keeps_the_load_balanced(method, rest):
    # the string locks a fraction ``rest`` of a step before the grid point: the forces
    # there come from the momentum balance over that remainder, m (v1 - v0) / h, with v1
    # known only to ulp(x) / h on the lock; they were off by m ulp(x) / h^2 (4.5e-5 of the
    # load at rest = 1e-2, the whole friction share 0.3 at 1e-4) and the mass kept a
    # spurious rate of 3e-9
    n = 11864  # dt ~ 1e-4
    probe = simulate(lock_scene(), method=method, dt=1e-4, t_end=1.3)
    t_lock = probe.events[0].t
    dt = (t_lock + rest * 1e-4) / n
    sol = simulate(lock_scene(), method=method, dt=dt, t_end=(n + 20) * dt)
    (ev,) = sol.events
    i = int(np.searchsorted(sol.t, ev.t))  # the end of the impact's step
    assert 0.0 < sol.t[i] - ev.t <= 2 * rest * dt  # the lock really came late in the step
    after = sol.t >= sol.t[i]
    assert np.all(sol.x["mass"][after] == 0.5)
    assert np.abs(sol.v["mass"][after]).max() <= 1e-12
    total = sol.F["string"][after] + sol.F["friction"][after]
    assert np.abs(total - 1.0).max() <= 1e-8, total[:3] - 1.0
    assert np.abs(sol.F["friction"]).max() <= 0.2 * (1 + 1e-9)


def _taut_pair() -> Scene:
    # two unit masses, a string between them pulled taut by a load of 3 on m2 against a
    # ground spring on m1: after the impact the pair moves on with the string taut
    return Scene([Mass("m1", m=1.0), Mass("m2", m=1.0, v0=1.0)],
                 [Element("g", get_law("linear_spring").bind(k=10.0), "ground", "m1"),
                  Element("s", get_law("string_spring").bind(k=1.0, L=0.5), "m1", "m2")],
                 {"m2": 3.0})


@pytest.mark.parametrize("rest", [1e-2, 1e-3, 1e-4])
def test_moving_pair_locked_late_in_a_step_has_the_string_force(rest):
    # the string goes taut a fraction ``rest`` of a step before a grid point while the
    # pair keeps moving: its force there comes from the balance of accelerations, not from
    # the short remainder (at rest = 1e-3 that sample had 0.5 instead of 1.539)
    ref = simulate(_taut_pair(), method="radau5", t_end=0.5, rtol=1e-12, atol=1e-14,
                   compiled=False)
    t_hit = ref.events[0].t
    n = int(t_hit / 1e-4)
    dt = (t_hit + rest * 1e-4) / (n + 1)
    sol = simulate(_taut_pair(), method="bdf2", dt=dt, t_end=(n + 30) * dt)
    (ev,) = sol.events
    i = int(np.searchsorted(sol.t, ev.t))
    assert 0.0 < sol.t[i] - ev.t <= max(2 * rest, 1e-3) * dt  # late in that step
    F_ref = ref.sol(sol.t[i:i + 3])[:, 5:7]
    assert np.abs(sol.data[i:i + 3, 5:7] - F_ref).max() <= 1e-6
    assert sol.v["m2"][i] == pytest.approx(sol.v["m1"][i], rel=1e-15)  # the string stopped


def _hard_stop_law() -> ElementLaw:
    # a user's one-sided stop written without Min: the same graph as string_spring
    return ElementLaw("stop", "spring", "q - Piecewise((F/k, F < k*L), (L, True))",
                      ["k", "L"])


def test_user_law_with_a_hard_stop_gets_the_same_impact():
    law = _hard_stop_law().bind(k=1.0, L=0.5)
    scene = Scene([Mass("mass", m=1.0, x0=0.0, v0=1.0)],
                  [Element("string", law, "ground", "mass")])
    sol = simulate(scene, method="bdf2", dt=1e-3, t_end=1.5)
    ref = simulate(impact_scene(), method="bdf2", dt=1e-3, t_end=1.5)
    assert len(sol.events) == 1 and sol.events[0].kind == "impact"
    assert np.abs(sol.x["mass"] - exact_impact(sol.t)).max() <= 3e-3
    assert np.allclose(sol.data, ref.data, rtol=0, atol=1e-9)


def test_locking_elements_reads_the_branch_not_the_name():
    law = _hard_stop_law().bind(k=2.0, L=0.5)
    scene = Scene([Mass("m", m=1.0)], [Element("s", law, "ground", "m"),
                                       Element("k", get_law("linear_spring").bind(k=1.0),
                                               "ground", "m")])
    assert locking_elements(scene, [0.5], [0.0], [3.0, 0.5]) == [0]  # taut: F > k L
    assert locking_elements(scene, [0.2], [0.0], [0.4, 0.2]) == []


def _two_masses(L: float = 1.0) -> Scene:
    s = get_law("string_spring").bind(k=1.0, L=L)
    return Scene([Mass("a", m=1.0), Mass("b", m=3.0)], [Element("s", s, "a", "b")])


def test_impact_conserves_momentum_and_stops_the_rate():
    scene = _two_masses()
    v_after, (P,), lost = impact_velocities(scene, [0.0, 1.0], [-1.0, 2.0], [0])
    assert v_after[0] == pytest.approx(v_after[1])  # rate stopped
    assert 1.0 * v_after[0] + 3.0 * v_after[1] == pytest.approx(-1.0 + 6.0)  # momentum
    assert P == pytest.approx(3.0 * (2.0 - v_after[1]))  # impulse on b: -P
    assert lost == pytest.approx(0.5 * (1 + 12) - 0.5 * 4 * v_after[0] ** 2)


def test_impact_with_restitution_one_keeps_the_energy():
    scene = _two_masses()
    v_after, _, lost = impact_velocities(scene, [0.0, 1.0], [-1.0, 2.0], [0], restitution=1.0)
    assert v_after[1] - v_after[0] == pytest.approx(-(2.0 + 1.0))
    assert lost == pytest.approx(0.0, abs=1e-12)


def test_impact_through_a_junction_and_parallel_strings():
    s = get_law("string_spring").bind(k=1.0, L=0.5)
    # mass -- string -- junction -- dashpot -- ground: the junction (no mass) takes the
    # jump, the mass keeps its momentum (no impulse through a massless node)
    scene = Scene([Mass("m", m=2.0), Junction("j")],
                  [Element("s", s, "j", "m"),
                   Element("d", get_law("newtonian").bind(c=1.0), "ground", "j")])
    v_after, (P,), lost = impact_velocities(scene, [0.5, 0.0], [1.0, 0.0], [0])
    assert v_after == pytest.approx([1.0, 1.0]) and P == pytest.approx(0.0, abs=1e-12)
    assert lost == pytest.approx(0.0, abs=1e-12)
    # two strings in parallel: the impulse is split by the minimum-norm rule (equal)
    scene = Scene([Mass("m", m=2.0)], [Element("s1", s, "ground", "m"),
                                       Element("s2", s, "ground", "m")])
    v_after, P, lost = impact_velocities(scene, [0.5], [1.0], [0, 1])
    assert v_after == pytest.approx([0.0], abs=1e-12)
    assert P == pytest.approx([1.0, 1.0]) and lost == pytest.approx(1.0)


def test_impact_velocities_rejects_bad_input():
    scene = _two_masses()
    with pytest.raises(ValueError, match="restitution"):
        impact_velocities(scene, [0.0, 0.0], [0.0, 1.0], [0], restitution=1.5)
    with pytest.raises(ValueError, match="locked"):
        impact_velocities(scene, [0.0, 0.0], [0.0, 1.0], [3])
    with pytest.raises(ValueError, match="`v`"):
        impact_velocities(scene, [0.0, 0.0], [0.0, math.nan], [0])


def test_restitution_keyword_bounces():
    sol = simulate(impact_scene(), method="bdf2", dt=1e-4, t_end=0.6, restitution=1.0)
    (ev,) = sol.events
    assert ev.energy_lost == pytest.approx(0.0, abs=1e-6)
    assert sol.v["mass"][-1] < -0.8  # bounced back at (almost) the impact speed
    with pytest.raises(ValueError, match="restitution"):
        simulate(impact_scene(), method="bdf1", dt=1e-3, t_end=0.1, restitution=-0.5)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize(("n", "tau", "x0", "k", "dt"), [
    (0.5, 0.01, 0.3, 100.0, 0.02), (0.5, 0.01, 1.0, 1.0, 0.005),
    (0.2, 0.01, 0.3, 1.0, 0.02), (0.5, 0.1, 1.0, 100.0, 0.005),
])
def test_herschel_bulkley_below_one_near_its_yield_force(method, n, tau, x0, k, dt):
    # dq/dF is infinite at |F| = tau: these runs stopped with Newton diverged/max_iters
    law = get_law("herschel_bulkley").bind(gamma=10.0, tau=tau, n=n)
    scene = Scene([Mass("m", m=1.0, x0=x0, v0=0.5)],
                  [Element("s", get_law("linear_spring").bind(k=k), "ground", "m"),
                   Element("d", law, "ground", "m")])
    sol = simulate(scene, method=method, dt=dt, t_end=2.0)
    assert sol.ok and np.all(np.isfinite(sol.data))
    q, F = sol.v["m"], sol.F["d"]
    # on the law, in its inverse form: |F| = tau + (|q| / gamma)^(1/n), sgn F = sgn q
    # where the dashpot moves; |F| <= tau where it is stuck
    moving = q != 0.0
    expect = np.sign(q) * (tau + (np.abs(q) / 10.0) ** (1.0 / n))
    assert np.abs(F[moving] - expect[moving]).max() <= 1e-8 * (1 + np.abs(F).max())
    assert np.all(np.abs(F[~moving]) <= tau * (1 + 1e-12))


def test_initial_state_no_law_admits_is_refused_by_name():
    scene = Scene([Mass("mass", m=1.0, x0=0.5), Junction("j")],
                  [Element("spring", get_law("linear_spring").bind(k=10.0), "j", "mass"),
                   Element("friction", get_law("coulomb").bind(tau=1.0, r=10.0), "ground", "j")])
    with pytest.raises(ValueError, match="inconsistent initial state") as info:
        simulate(scene, method="bdf2", dt=1e-3, t_end=0.1)
    msg = str(info.value)
    assert "'friction'" in msg and "'coulomb'" in msg and "junction 'j'" in msg
    stretched = Scene([Mass("mass", m=1.0, x0=0.7)],
                      [Element("string", get_law("string_spring").bind(k=1.0, L=0.5),
                               "ground", "mass")])
    with pytest.raises(ValueError, match="'string'.*'string_spring'"):
        simulate(stretched, method="bdf1", dt=1e-3, t_end=0.1)


@pytest.mark.parametrize("name", ["impact", "lock"])
def test_example_files_are_the_bench_scenes(name):
    from pathlib import Path

    from lumped.bench.impact_scenes import IMPACT_SCENES
    from lumped.io.scenefile import load_scene

    path = Path(__file__).resolve().parents[3] / "examples" / f"{name}.toml"
    scene, settings = load_scene(path)
    a = simulate(scene, method="bdf2", dt=settings["dt"], t_end=1.5)
    b = simulate(IMPACT_SCENES[name][0](), method="bdf2", dt=settings["dt"], t_end=1.5)
    assert np.array_equal(a.data, b.data) and len(a.events) == 1


def test_impact_bench_rows():
    from lumped.bench.impact_scenes import impact_errors, impact_markdown

    rows = impact_errors(methods=("bdf1", "bdf2"), dts=(1e-2,), t_end=1.0, timed=True)
    assert [r["status"] for r in rows] == ["success", "success"]
    assert all(r["max_error"] <= 3e-2 and r["impacts"] == 1 for r in rows)
    assert all(math.isfinite(r["ratio"]) and r["ratio"] > 0 for r in rows)
    assert impact_markdown(rows).count("\n") == 4


def test_two_rigid_bars_of_different_lengths_are_refused_at_the_start():
    # user laws that fix q and leave F free everywhere: no state satisfies both
    bar = ElementLaw("bar", "spring", "q - l", ["l"])
    scene = Scene([Mass("mass", m=1.0, x0=0.5)],
                  [Element("long", bar.bind(l=0.5), "ground", "mass"),
                   Element("short", bar.bind(l=0.3), "ground", "mass")])
    with pytest.raises(ValueError, match="'short'.*'bar'"):
        simulate(scene, method="bdf1", dt=1e-3, t_end=0.1)


def test_two_equal_rigid_bars_share_a_load_indeterminately():
    bar = ElementLaw("bar", "spring", "q - l", ["l"])
    scene = Scene([Mass("mass", m=1.0, x0=0.5)],
                  [Element("b1", bar.bind(l=0.5), "ground", "mass"),
                   Element("b2", bar.bind(l=0.5), "ground", "mass")],
                  forces={"mass": 2.0})
    sol = simulate(scene, method="bdf2", dt=1e-2, t_end=0.5)
    assert sol.ok and np.all(sol.x["mass"] == 0.5)
    assert np.abs(sol.v["mass"]).max() <= 1e-15  # min-norm pinv: round-off only
    # from the first step on (the initial state's limit system mixes the free split with
    # the masses' accelerations: its forces need not sum to the load)
    assert np.allclose((sol.F["b1"] + sol.F["b2"])[1:], 2.0, rtol=0, atol=1e-12)
    assert set(sol.indeterminate) == {"b1", "b2"}
