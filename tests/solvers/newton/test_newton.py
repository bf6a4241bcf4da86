"""Semismooth Newton: LU against numpy, result codes, counters, never a silent NaN."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from lumped.solvers.newton.linalg import DENSE_PYTHON_MAX, lu_factor, lu_solve
from lumped.solvers.newton.options import NewtonCode, NewtonOptions
from lumped.solvers.newton.semismooth import newton_solve

entries = st.floats(-10.0, 10.0, allow_nan=False)


@given(st.integers(1, DENSE_PYTHON_MAX).flatmap(
    lambda n: st.tuples(st.lists(st.lists(entries, min_size=n, max_size=n), min_size=n,
                                 max_size=n), st.lists(entries, min_size=n, max_size=n))))
def test_python_lu_solves_like_numpy(Ab):
    A, b = Ab
    M = np.array(A)
    if abs(np.linalg.det(M)) < 1e-3 or np.linalg.cond(M) > 1e6:
        return
    f = lu_factor(A)
    assert f is not None
    y = lu_solve(f, b)
    np.testing.assert_allclose(M @ np.array(y), b, atol=1e-8 * (1 + np.abs(b).max()))


def test_lu_reports_singular():
    assert lu_factor([[1.0, 2.0], [2.0, 4.0]]) is None
    assert lu_factor([[0.0]]) is None


def _linear(A, b):
    def evaluate(u):
        G = [sum(a * x for a, x in zip(row, u, strict=True)) - bi
             for row, bi in zip(A, b, strict=True)]
        S = [sum(abs(a * x) for a, x in zip(row, u, strict=True)) + abs(bi)
             for row, bi in zip(A, b, strict=True)]
        return G, [list(r) for r in A], S
    return evaluate


def test_linear_system_converges_in_one_iteration():
    res = newton_solve(_linear([[2.0, 1.0], [1.0, 3.0]], [3.0, 5.0]), [0.0, 0.0])
    assert res.code is NewtonCode.SUCCESS
    assert res.iterations == 1
    assert res.factorizations == 1 and res.jacobian_evals == 1
    assert res.residual_evals == 2
    np.testing.assert_allclose(res.u, np.linalg.solve([[2, 1], [1, 3]], [3, 5]), rtol=1e-14)


def test_already_solved_takes_no_iteration():
    res = newton_solve(_linear([[2.0]], [4.0]), [2.0])
    assert res.code is NewtonCode.SUCCESS and res.iterations == 0


def test_large_system_goes_through_numpy():
    n = DENSE_PYTHON_MAX + 3
    rng = np.random.default_rng(1)
    A = (np.eye(n) * 5 + rng.uniform(-1, 1, (n, n))).tolist()
    b = rng.uniform(-1, 1, n).tolist()
    res = newton_solve(_linear(A, b), [0.0] * n)
    assert res.code is NewtonCode.SUCCESS
    np.testing.assert_allclose(res.u, np.linalg.solve(A, b), rtol=1e-12)


def test_large_singular_system_is_reported_without_a_warning():
    """A singular Jacobian above :data:`DENSE_PYTHON_MAX` (a stuck dashpot's row with a
    zero pivot) is Newton's business, reported as ``SINGULAR``: scipy's ``lu_factor``
    used to emit a ``LinAlgWarning`` for it on every such step."""
    import warnings

    n = DENSE_PYTHON_MAX + 3
    A = np.eye(n)
    A[4, :] = 0.0  # a row the law leaves empty
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        res = newton_solve(_linear(A.tolist(), [1.0] * n), [0.0] * n)
    assert res.code is NewtonCode.SINGULAR


def test_min_norm_solver_leaves_a_non_finite_step_to_newton_without_a_warning():
    """A right-hand side with an infinity (a residual that overflowed) gives a
    non-finite step, which Newton reports as ``NON_FINITE``; numpy's 'invalid value
    encountered in matmul' reached the user (the LUMPED_LARGE radau5 run)."""
    import warnings

    from lumped.solvers.newton.min_norm import min_norm_solver

    solve = min_norm_solver([[1.0, 1.0], [1.0, 1.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        du = solve([math.inf, -math.inf])
    assert not all(math.isfinite(d) for d in du)


def test_nonlinear_quadratic_convergence():
    def evaluate(u):
        return [u[0] ** 3 - 8.0], [[3 * u[0] ** 2]], [abs(u[0]) ** 3 + 8.0]
    res = newton_solve(evaluate, [3.0])
    assert res.code is NewtonCode.SUCCESS
    assert res.u[0] == pytest.approx(2.0, rel=1e-13)
    assert res.iterations <= 8


def test_singular_jacobian_is_reported():
    res = newton_solve(_linear([[1.0, 1.0], [1.0, 1.0]], [1.0, 2.0]), [0.0, 0.0])
    assert res.code is NewtonCode.SINGULAR


def test_nan_residual_is_reported_not_returned():
    def evaluate(u):
        return [math.nan if u[0] != 0.0 else 1.0], [[1.0]], [1.0]
    res = newton_solve(evaluate, [0.0])
    assert res.code is not NewtonCode.SUCCESS


def test_iteration_budget_is_enforced():
    # arctan: full Newton steps from far away diverge; with a tiny budget we stop
    def evaluate(u):
        return [math.atan(u[0])], [[1.0 / (1.0 + u[0] ** 2)]], [abs(math.atan(u[0])) + 1e-300]
    res = newton_solve(evaluate, [10.0], NewtonOptions(max_iters=2, free_steps=0,
                                                        max_backtracks=0))
    assert res.code in (NewtonCode.MAX_ITERS, NewtonCode.DIVERGED)
    assert res.iterations <= 2


def test_line_search_rescues_arctan():
    def evaluate(u):
        return [math.atan(u[0])], [[1.0 / (1.0 + u[0] ** 2)]], [abs(u[0]) + 1.0]
    res = newton_solve(evaluate, [10.0], NewtonOptions(free_steps=0))
    assert res.code is NewtonCode.SUCCESS
    assert abs(res.u[0]) < 1e-10


@pytest.mark.parametrize("kw", [{"rtol": 0.0}, {"atol": -1.0}, {"max_iters": 0}])
def test_bad_options(kw):
    with pytest.raises(ValueError, match=next(iter(kw))):
        NewtonOptions(**kw)


@given(st.integers(1, DENSE_PYTHON_MAX).flatmap(
    lambda n: st.tuples(st.lists(st.lists(entries, min_size=n, max_size=n), min_size=n,
                                 max_size=n), st.lists(entries, min_size=n, max_size=n))))
def test_unrolled_solve_is_lu_solve_bit_for_bit(Ab):
    import struct

    from lumped.solvers.newton.linalg import unrolled_lu_solve

    def bits(xs):  # bit patterns: NaN == NaN when its bits agree (list == compares NaN by id)
        return [struct.pack("<d", x) for x in xs]

    A, b = Ab
    f = lu_factor(A)
    if f is not None:
        assert bits(unrolled_lu_solve(f)(b)) == bits(lu_solve(f, b))


def test_factor_cache_reuses_factors_across_solves():
    from lumped.solvers.newton.linalg import FactorCache

    cache = FactorCache()
    ev = _linear([[2.0, 1.0], [1.0, 3.0]], [3.0, 5.0])
    first = newton_solve(ev, [0.0, 0.0], cache=cache)
    assert first.factorizations == 1
    for _ in range(3):
        again = newton_solve(ev, [0.0, 0.0], cache=cache)
        assert again.factorizations == 0 and again.u == first.u


def _lock_on_a_lattice(h: float = 1e-4, m: float = 1.0, load: float = 2.6517535238691945):
    # a mass at x = x_hat + h v on a lock q - L = 0, q = x - x_a, loaded by ``load``
    # against the lock's force F: (m / h) v + F - load = 0. Far from the origin, q lies on
    # a lattice of spacing ulp(x) = 1.4e-14 that misses L by 40 ulps of q (6.9e-17)
    x_hat, x_a = 100.01, 100.0
    q0 = x_hat - x_a  # exact (Sterbenz)
    L = q0 + 40 * math.ulp(q0)

    def evaluate(u):
        v, F = u
        p = (m / h) * v
        x = x_hat + h * v
        q = x - x_a
        G = [p + F - load, q - L]
        S = [abs(p) + abs(F) + abs(load), abs(x) + abs(x_a) + abs(L)]
        return G, [[m / h, 1.0], [h, 0.0]], S

    return evaluate, L


def test_a_lock_that_no_float_meets_converges_at_round_off():
    """The lock row cannot go below a fraction of ulp(x), and each correction asks the
    force for m (q - L) / h^2 (6.9e-9), beyond rtol |F|: Newton keeps the iterate where
    every row is at the rounding of its terms (``at_roundoff``), the lock row's terms being
    the positions, instead of running out of budget."""
    from lumped.solvers.newton.criteria import at_roundoff

    evaluate, L = _lock_on_a_lattice()
    res = newton_solve(evaluate, [0.0, 2.0])
    assert res.code is NewtonCode.SUCCESS and res.iterations <= 3
    G, _, S = evaluate(res.u)
    assert G[1] != 0.0  # no floating-point root
    assert abs(G[1]) <= 0.5 * math.ulp(100.01)
    assert at_roundoff(G, S)
    assert abs(res.u[1] - 2.6517535238691945) <= 1.0 * math.ulp(100.01) / 1e-4**2
    # read from |q| + |L| alone the lock row would not be at round-off
    assert not at_roundoff([G[1]], [abs(G[1] + L) + abs(L)])


@given(st.lists(st.tuples(st.floats(-1e3, 1e3), st.floats(0.0, 1e3)), min_size=1,
                max_size=6))
def test_at_roundoff_compiled_is_the_reference(rows):
    from lumped.solvers.newton.criteria import at_roundoff
    from lumped.solvers.newton.criteria_jit import at_roundoff as at_roundoff_jit

    G = [g * 1e-15 for g, _ in rows]
    S = [s for _, s in rows]
    assert at_roundoff_jit(np.array(G), np.array(S)) == at_roundoff(G, S)
