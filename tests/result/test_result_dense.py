"""Solution.sol(t): exact at the samples, cubic Hermite between them, domain checked."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.post.dense import hermite_dense
from lumped.scene import bingham_oscillator, paper_F2

K, M = 100.0, 1.0
OMEGA = math.sqrt(K / M)


def _spring_scene() -> Scene:
    return Scene([Mass("mass", m=M, x0=1.0)],
                 [Element("spring", get_law("linear_spring").bind(k=K), "ground", "mass")])


def _exact_rows(t: np.ndarray) -> np.ndarray:
    """The undamped oscillator x = cos(w t) laid out like the scene's columns."""
    x = np.cos(OMEGA * t)
    return np.column_stack([t, x, -OMEGA * np.sin(OMEGA * t), K * x])


def test_sol_is_exact_at_the_samples_and_shapes_follow_t():
    sol = simulate(bingham_oscillator(x0=0.5, forcing=paper_F2), method="bdf2", dt=1e-2,
                   t_end=2.0)
    assert np.array_equal(sol.sol(sol.t), sol.data)
    assert sol.sol(0.5).shape == (len(sol.columns),)
    assert sol.sol([0.25, 0.5]).shape == (2, len(sol.columns))
    assert sol.sol(2.0)[0] == 2.0


@pytest.mark.parametrize("bad", [-1e-9, 2.0 + 1e-9, math.nan, math.inf])
def test_sol_refuses_times_outside_the_solved_interval(bad):
    sol = simulate(bingham_oscillator(x0=0.5), method="closed-bdf1", dt=1e-2, t_end=2.0)
    with pytest.raises(ValueError, match="`t`"):
        sol.sol(bad)
    with pytest.raises(ValueError, match="`t`"):
        sol.sol([0.0, bad])


def test_hermite_is_fourth_order_on_exact_samples():
    """Hermite on exact samples of x = cos(wt): x and v (whose derivative is the
    acceleration from the momentum balance) converge like h^4, the force like h^2."""
    scene = _spring_scene()
    errors = []
    for h in (0.02, 0.01):
        t = np.arange(0.0, 1.0 + h / 2, h)
        mid = t[:-1] + 0.37 * h
        dense = hermite_dense(scene, _exact_rows(t))
        errors.append(np.abs(dense(mid) - _exact_rows(mid)).max(axis=0))
    ratio = errors[0][1:] / errors[1][1:]
    assert ratio[0] > 14 and ratio[1] > 14, ratio   # x, v: 2^4 = 16
    assert 3.5 < ratio[2] < 4.5, ratio               # F: linear, 2^2 = 4


@given(st.lists(st.floats(-10, 10), min_size=4, max_size=4),
       st.floats(0.0, 1.0))
def test_hermite_reproduces_a_cubic_displacement(coeffs, s):
    """x(t) a cubic with v = x' sampled: the interpolant of x is that cubic."""
    p = np.polynomial.Polynomial(coeffs)
    t = np.array([0.0, 0.3, 0.7, 1.0])
    rows = np.column_stack([t, p(t), p.deriv()(t), np.zeros_like(t)])
    got = hermite_dense(_spring_scene(), rows)(np.array([s]))[0, 1]
    assert got == pytest.approx(p(s), abs=1e-12 * (1 + np.abs(coeffs).sum()))


def test_method_dense_output_is_used_when_given():
    from lumped.result import Solution

    sol = simulate(bingham_oscillator(x0=0.5), method="closed-bdf1", dt=0.1, t_end=1.0)
    calls = []

    def dense(t):
        calls.append(t)
        return np.repeat(sol.data[:1], len(t), axis=0)

    other = Solution(columns=sol.columns, data=sol.data, node_names=sol.node_names,
                     element_names=sol.element_names, method="custom", scene=sol.scene,
                     dense=dense, located_events=())
    assert np.array_equal(other.sol(0.55), sol.data[0]) and len(calls) == 1


def test_a_failed_run_is_interpolated_up_to_its_last_good_step():
    """An S-shaped spring unloaded past its fold: the run stops early (throw=False); sol()
    covers what was solved and names `t` beyond it, and the result still reports."""
    from lumped import ElementLaw

    cubic = ElementLaw("cubic", "spring", "q = F**3 - F", []).bind()   # folds at F = 3**-0.5
    scene = Scene([Mass("mass", 0.01, x0=1.5**3 - 1.5)],
                  [Element("s", cubic, "ground", "mass"),
                   Element("damper", get_law("newtonian").bind(c=0.02), "ground", "mass")],
                  {"mass": (lambda t: 1.5 - 0.5 * t)})
    sol = simulate(scene, method="bdf1", dt=1e-3, t_end=4.0, throw=False)
    assert not sol.success and sol.t[-1] < 4.0
    assert np.array_equal(sol.sol(sol.t[-1]), sol.data[-1])
    with pytest.raises(ValueError, match=r"`t` must lie in \[0\.0, "):
        sol.sol(4.0)
    assert sol.status.value in repr(sol) and sol.energy().t[-1] == sol.t[-1]
