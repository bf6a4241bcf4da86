"""The dense output of ``radau5``: positions of order 5 per step, against exact solutions.

The position of a node between step points integrates the collocation cubic of its
velocity (:func:`lumped.solvers.radau.dense.position_weights`); the cubic through the
stage positions, used before, is one order lower and made the error on an output grid up
to 200 times the error at the step points at tight tolerances.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import get_law, simulate
from lumped.codegen.jit import numba_enabled
from lumped.reference import exact_solution
from lumped.scenarios import get_scenario, scenario_scene
from lumped.solvers.radau.dense import DenseOutput, position_weights
from lumped.solvers.radau.stage import StageSystem
from lumped.solvers.radau.tableau import A, C


def test_position_weights_meet_the_step_ends():
    """``L_k(0) = 0``, ``L_k(1) = a_3k`` (the step's end is the stage-3 position), and
    ``L_k' = l_k`` (the slope is the velocity's cubic)."""
    assert position_weights(0.0) == (0.0, 0.0, 0.0)
    np.testing.assert_allclose(position_weights(1.0), A[2], rtol=0.0, atol=2e-15)
    s, d = 0.37, 1e-6
    slope = (np.array(position_weights(s + d)) - np.array(position_weights(s - d))) / (2 * d)
    c1, c2, c3 = C
    lagrange = (s * (s - c2) * (s - c3) / (c1 * (c1 - c2) * (c1 - c3)),
                s * (s - c1) * (s - c3) / (c2 * (c2 - c1) * (c2 - c3)),
                s * (s - c1) * (s - c2) / (c3 * (c3 - c1) * (c3 - c2)))
    np.testing.assert_allclose(slope, lagrange, rtol=0.0, atol=1e-9)


def _one_step_dense_error(h: float) -> float:
    """Max error of the dense ``x`` inside one Radau IIA step from the exact state of a
    damped linear oscillator (spring + newtonian dashpot)."""
    m, k, c = 1.0, 100.0, 0.5
    system = StageSystem([m], [-1, -1], [0, 0], [True, False])
    kernels = (get_law("linear_spring").bind(k=k).kernel, get_law("newtonian").bind(c=c).kernel)
    x0 = 0.1
    zeta = c / (2 * m)
    wd = math.sqrt(k / m - zeta ** 2)

    def exact(t):
        return x0 * np.exp(-zeta * t) * (np.cos(wd * t) + zeta / wd * np.sin(wd * t))

    x, v, F = [x0], [0.0], [k * x0, 0.0]
    U, _, _ = system.solve((v + F) * 3, h, x, v, [[0.0]] * 3, kernels, [1e-9] * 9, tol=1e-6)
    Y = []
    for kk in range(3):
        Xk = x[0] + h * sum(A[kk][j] * U[3 * j] for j in range(3))
        Y.append([Xk, U[3 * kk], U[3 * kk + 1], U[3 * kk + 2]])
    dense = DenseOutput(1, 2)
    dense.add(0.0, h, x + v + F, Y)
    t = np.linspace(0.0, h, 41)
    return float(np.max(np.abs(dense(t)[:, 1] - exact(t))))


def test_dense_positions_are_of_local_order_five():
    """Inside one step the dense ``x`` errs by ``O(h^5)`` (slope of log error on log h);
    the cubic through the stage positions gives slope 4."""
    hs = [0.02, 0.01, 0.005, 0.0025]  # (slope 5.4 here, 5.7 from h = 0.08)
    errs = [_one_step_dense_error(h) for h in hs]
    slope = np.polyfit(np.log(hs), np.log(errs), 1)[0]
    assert 4.6 <= slope <= 5.6, (slope, errs)


@pytest.mark.parametrize("name", ["release-0.5", "forcing-F2"])
def test_the_grid_error_is_the_step_point_error(name):
    """Between the step points the dense ``x`` is as accurate as at them (within a factor
    of 3), at a tight tolerance where the interpolant used to dominate (70-200 times)."""
    sc = get_scenario(name)
    sol = simulate(scenario_scene(name), method="radau5", t_end=5.0, rtol=1e-9, atol=1e-12)
    ts = sol.t
    at_steps = exact_solution(sc.osc, x0=sc.x0, v0=sc.v0, forcing=sc.forcing, t_eval=ts)
    e_steps = float(np.max(np.abs(sol.data[:, 1] - at_steps.trajectory.x)))
    inner = np.sort(np.concatenate([ts[:-1] + f * np.diff(ts) for f in (0.2, 0.5, 0.8)]))
    ex = exact_solution(sc.osc, x0=sc.x0, v0=sc.v0, forcing=sc.forcing, t_eval=inner)
    e_dense = float(np.max(np.abs(sol.sol(inner)[:, 1] - ex.trajectory.x)))
    assert e_steps <= 1e-10
    assert e_dense <= 3.0 * e_steps + 1e-15, (e_dense, e_steps)


def test_dense_positions_are_continuous_with_slope_v():
    """At every step point the dense ``x`` of the step that ends there meets the step's
    value, and its slope there is the step's ``v``."""
    sol = simulate(scenario_scene("release-0.5"), method="radau5", t_end=5.0, rtol=1e-8,
                   atol=1e-11)
    ts = sol.t[1:-1]
    left = sol.sol(np.nextafter(ts, -np.inf))[:, 1]
    scale = np.max(np.abs(sol.data[:, 1]))
    assert np.max(np.abs(left - sol.data[1:-1, 1])) <= 1e-13 * scale
    d = 1e-7
    long = np.diff(sol.t)[:-1] > 1e3 * d  # steps long enough for the difference
    slope = (sol.sol(ts[long] - d)[:, 1] - sol.sol(ts[long] - 2 * d)[:, 1]) / d
    # the one-sided difference errs by about 1.5 d |a| (a up to k x0 / m = 50)
    assert long.sum() > 100
    assert np.max(np.abs(slope - sol.data[1:-1, 2][long])) <= 1e-4


@pytest.mark.skipif(not numba_enabled(), reason="the compiled evaluation needs numba")
@pytest.mark.parametrize("shuffle", [False, True])
def test_the_compiled_dense_output_is_the_numpy_one_across_stuck_intervals(monkeypatch,
                                                                          shuffle):
    """A run that sticks and breaks out again and again (a held interval without steps
    each time, :mod:`lumped.solvers.modes.stuck`): the compiled evaluation, which leaves the rows
    of a held interval to the static balance and walks the steps for sorted times, gives
    the numpy evaluation's numbers at the step points, at the ends of every held interval
    and on a grid, in order and shuffled."""
    import lumped.solvers.radau.dense as out
    from lumped import Element, Mass, Scene
    from lumped.scene.forcing import SineBurst

    scene = Scene([Mass("mass", m=1.0)],
                  [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
                   Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground",
                           "mass")],
                  {"mass": SineBurst(1.5, 2.0 * math.pi, 4.0)})
    sol = simulate(scene, method="radau5", t_end=5.0, rtol=1e-6)
    held = sol.dense._static
    assert sol.stats["held_intervals"] >= 8 and len(held) == sol.stats["held_intervals"]
    ends = [s for s0, s1, _ in held for s in (s0, s1)]
    t = np.concatenate([np.linspace(0.0, 5.0, 2001), sol.t, ends, np.nextafter(ends, 0.0),
                        np.nextafter(ends, 9.0)])
    t = np.clip(t, 0.0, 5.0)
    t = np.random.default_rng(0).permutation(t) if shuffle else np.sort(t)
    fast = sol.sol(t)
    monkeypatch.setattr(out, "numba_enabled", lambda: False)
    assert np.array_equal(sol.sol(t), fast)


def test_the_output_keeps_its_steps_in_order_as_it_grows():
    """Steps added one at a time (the Python loop), as blocks (``extend``) and written in
    place (``block``/``commit``, the compiled loop), well past the first capacity: the
    arrays hold them in their order, and the rows likewise."""
    from lumped.solvers.radau.rows import Rows

    rng = np.random.default_rng(3)
    N, E = 1, 2
    ny = 2 * N + E
    dense, rows = DenseOutput(N, E), Rows()
    want_t, want_y0, want_d, want_rows = [], [], [], []
    t = 0.0
    for part in range(12):
        k = int(rng.integers(1, 40))
        y0 = rng.normal(size=(k, ny))
        Y = rng.normal(size=(k, 3, ny))
        r = rng.normal(size=(k, 1 + ny))
        T0, H = t + np.arange(k, dtype=float), np.ones(k)
        t += k
        if part % 3 == 0:
            for i in range(k):
                dense.add(T0[i], H[i], y0[i].tolist(), Y[i].tolist())
                rows.append(r[i].tolist())
        elif part % 3 == 1:
            dense.extend(T0, H, y0, Y - y0[:, None, :])
            rows.extend(r)
        else:
            views = dense.block(k + 5)  # room for more than is kept
            for view, val in zip(views, (T0, H, y0, Y - y0[:, None, :]), strict=True):
                view[:k] = val
            dense.commit(k)
            rows.block(k + 5, 1 + ny)[:k] = r
            rows.commit(k)
        want_t.append(T0)
        want_y0.append(y0)
        want_d.append(Y - y0[:, None, :])
        want_rows.append(r)
    T0, H, Y0, D = dense._arrays()
    assert len(dense) == len(T0) == sum(map(len, want_t)) > 64
    assert np.array_equal(T0, np.concatenate(want_t)) and np.all(H == 1.0)
    assert np.array_equal(Y0, np.concatenate(want_y0))
    assert np.array_equal(D, np.concatenate(want_d))
    assert np.array_equal(rows.array(), np.concatenate(want_rows))
    rows.set_first([9.0] * (1 + ny))
    assert rows.first() == [9.0] * (1 + ny)


@pytest.mark.skipif(not numba_enabled(), reason="the compiled evaluation needs numba")
@pytest.mark.parametrize("forcing", [None, "F1", "const"])
def test_a_run_held_from_the_start_has_an_exact_dense_output(monkeypatch, forcing):
    """A scene stuck from t = 0 to the end takes no step: its dense output is its held
    segments only (the compiled evaluation skips the steps' table then). Positions are
    frozen at x0, velocities exactly 0, the dashpot carries the load less the spring, bit
    for bit, at every time and at the segments' ends (a time event at t_off = 1), and the
    numpy evaluation gives the same numbers, in order and shuffled."""
    import lumped.solvers.radau.dense as out
    from lumped import Element, Mass, Scene
    from lumped.scene.forcing import paper_F1

    spec = {None: None, "F1": paper_F1, "const": 0.25}[forcing]
    scene = Scene([Mass("mass", m=1.0, x0=0.004)],
                  [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
                   Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground",
                           "mass")],
                  {} if spec is None else {"mass": spec})
    sol = simulate(scene, method="radau5", t_end=5.0, rtol=1e-7, atol=1e-9, compiled=True)
    assert sol.stats["steps"] == 0 and sol.dense._count == 0
    assert len(sol.dense._static) == (2 if forcing == "F1" else 1)
    ends = [s for s0, s1, _ in sol.dense._static for s in (s0, s1)]
    t = np.clip(np.concatenate([np.linspace(0.0, 5.0, 5001), ends, np.nextafter(ends, 0.0),
                                np.nextafter(ends, 9.0)]), 0.0, 5.0)
    t = np.sort(t)
    rows = sol.sol(t)
    assert np.array_equal(rows[:, 0], t)
    assert np.all(rows[:, 1] == 0.004) and np.all(rows[:, 2] == 0.0)
    F_s = sol.data[0, 3]
    assert np.all(rows[:, 3] == F_s)
    f = np.array([scene.external_forces(ti)[0] for ti in t])
    assert np.array_equal(rows[:, 4], f - F_s)  # the balance, m v' = f - F_s - F_d = 0
    shuffled = np.random.default_rng(1).permutation(t)
    assert np.array_equal(sol.sol(shuffled), sol.sol(t)[np.argsort(np.argsort(shuffled))])
    monkeypatch.setattr(out, "numba_enabled", lambda: False)
    assert np.array_equal(sol.sol(t), rows)
