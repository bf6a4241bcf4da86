"""The compiled closed-form steps against the pure-Python reference: bit for bit.

The compiled loop performs the reference's floating-point operations in the same order
(no fused multiply-adds, the same C ``sin``), so every column must be *equal*, not close.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from _helpers import log_uniform
from hypothesis import given
from hypothesis import strategies as st

from lumped.scene import SineBurst, paper_F1, paper_F2, zero_forcing
from lumped.solvers.closed import closed_form_jit as J
from lumped.solvers.closed.closed_form import (
    BinghamOscillator,
    initial_dashpot_force,
    initial_velocity,
)
from lumped.solvers.closed.integrate import integrate


def compiled(osc, x0, v0, forcing, dt, n, method):
    F0 = forcing(0.0) if forcing is not None else 0.0
    v0 = initial_velocity(osc, x0, v0, F0, h=1e-20 * dt)  # (as integrate)
    Fd0 = initial_dashpot_force(osc, x0, v0, F0)
    return J.compiled_columns(osc.m, osc.k, osc.gamma, osc.tau, forcing, x0, v0, Fd0,
                              dt, n, method)


def assert_identical(osc, x0, v0, forcing, dt, n, method):
    ref = integrate(osc, x0=x0, v0=v0, forcing=forcing, dt=dt, n_steps=n, method=method,
                    engine="python")
    x, v, Fd, Ft = compiled(osc, x0, v0, forcing, dt, n, method)
    for name, got, want in (("x", x, ref.x), ("v", v, ref.v), ("F_d", Fd, ref.F_d),
                            ("F~", Ft, ref.predictor)):
        bad = np.flatnonzero(got != want)
        assert bad.size == 0, (f"{method} {name} differs first at step {bad[0]}: "
                               f"{got[bad[0]]!r} != {want[bad[0]]!r}")
    return x, v, Fd


PAPER = BinghamOscillator(m=1.0, k=100.0, gamma=1.0, tau=1.0)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("x0, forcing", [(0.0, paper_F1), (0.0, paper_F2), (0.005, None),
                                         (0.5, None)])
def test_paper_scenarios_bit_for_bit(method, x0, forcing):
    assert_identical(PAPER, x0, 0.0, forcing or zero_forcing, 1e-4, 50_000, method)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_eq19_exact_under_the_yield_force(method):
    """Eq. (19): F1 stays below tau, so x = v = 0 and F_d = F(t) exactly at every step."""
    n, dt = 20_000, 1e-4
    x, v, Fd = assert_identical(PAPER, 0.0, 0.0, paper_F1, dt, n, method)
    assert not x.any() and not v.any()
    assert np.array_equal(Fd[1:], [paper_F1(i * dt) for i in range(1, n + 1)])


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("osc", [BinghamOscillator(1.0, 100.0, 1e12, 1.0),
                                 BinghamOscillator(1.0, 1e8, 1.0, 1.0),
                                 BinghamOscillator(1.0, 1e8, 1e12, 0.0)],
                         ids=["gamma1e12", "k1e8", "k1e8-coulomb-free"])
def test_hard_cases_bit_for_bit(method, osc):
    assert_identical(osc, 0.5, 0.0, paper_F2, 1e-4, 20_000, method)
    assert_identical(osc, 0.0, 3.0, SineBurst(50.0, 40.0, 0.5), 1e-3, 2_000, method)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_sampled_forcing_bit_for_bit(method):
    """Any callable is sampled on the grid in Python first: the same numbers."""
    assert J.forcing_code(math.cos)[0] == J.FORCE_SAMPLED
    assert_identical(PAPER, 0.1, -0.2, lambda t: 3.0 * math.cos(7.0 * t) - 0.5, 1e-3, 5_000,
                     method)


def test_constant_forcing_is_native():
    from lumped.scene import as_forcing

    F = as_forcing(2.5)
    assert J.forcing_code(F) == (J.FORCE_CONSTANT, 2.5, 0.0, 0.0)
    assert_identical(PAPER, 0.0, 0.0, F, 1e-3, 3_000, "bdf2")


oscillators = st.builds(
    BinghamOscillator,
    m=log_uniform(1e-3, 1e3), k=log_uniform(1e-2, 1e6), gamma=log_uniform(1e-3, 1e12),
    tau=st.one_of(st.just(0.0), log_uniform(1e-3, 1e2)),
)
forcings = st.one_of(
    st.just(zero_forcing),
    st.builds(SineBurst, amplitude=st.floats(-20, 20), omega=log_uniform(0.1, 100.0),
              t_off=st.one_of(st.just(math.inf), st.floats(0.0, 1.0))),
)


@given(osc=oscillators, forcing=forcings, x0=st.floats(-1, 1), v0=st.floats(-5, 5),
       dt=log_uniform(1e-5, 1e-1), method=st.sampled_from(["bdf1", "bdf2"]))
def test_property_bit_for_bit(osc, forcing, x0, v0, dt, method):
    assert_identical(osc, x0, v0, forcing, dt, 40, method)


def summary_from_columns(x, v, Fd, dt):
    """The summary fields computed in numpy from stored columns."""
    rest = v == 0.0
    sign = np.sign(v)
    return dict(x_end=x[-1], v_end=v[-1], stick_steps=np.count_nonzero(rest[1:]),
                cycles=np.count_nonzero(rest[1:] & ~rest[:-1]),
                events=np.count_nonzero(sign[1:] != sign[:-1]),
                dissipated=float(np.sum(dt * Fd[1:] * v[1:])))


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("forcing", [paper_F2, SineBurst(1.5, 2.0 * math.pi, 4.0)])
def test_summary_matches_the_stored_trajectory(method, forcing):
    dt, n = 1e-4, 50_000
    x, v, Fd = assert_identical(PAPER, 0.2, 0.0, forcing, dt, n, method)
    want = summary_from_columns(x, v, Fd, dt)
    out = np.empty(len(J.SUMMARY_FIELDS))
    code = J.forcing_code(forcing)
    J.summary_one(1.0, 100.0, 1.0, 1.0, dt, n, method == "bdf2", 0.2, 0.0, *code, out)
    got = dict(zip(J.SUMMARY_FIELDS, out, strict=True))
    assert got["steps_done"] == n
    for key in ("x_end", "v_end", "stick_steps", "cycles", "events"):
        assert got[key] == want[key], key
    assert got["cycles"] >= 1 and got["events"] > got["cycles"]
    assert got["dissipated"] == pytest.approx(want["dissipated"], rel=1e-12)
    assert got["dissipated"] > 0.0


def test_batch_equals_one_by_one():
    rng = np.random.default_rng(1)
    rows = np.column_stack([
        rng.uniform(0.5, 2, 40), rng.uniform(10, 200, 40), 1.0 / rng.uniform(0.1, 10, 40),
        rng.uniform(0, 2, 40), rng.uniform(-0.5, 0.5, 40), np.zeros(40),
        np.full(40, J.FORCE_SINE), rng.uniform(0, 10, 40), rng.uniform(1, 30, 40),
        np.full(40, 1.0)])
    par = np.empty((40, len(J.SUMMARY_FIELDS)))
    ser = np.empty_like(par)
    J.summary_batch(rows, 1e-3, 3000, True, par)
    J.summary_batch_serial(rows, 1e-3, 3000, True, ser)
    assert np.array_equal(par, ser)
    one = np.empty(len(J.SUMMARY_FIELDS))
    p = rows[7]
    J.summary_one(*p[:4], 1e-3, 3000, True, p[4], p[5], int(p[6]), *p[7:], one)
    assert np.array_equal(one, par[7])


def test_overflow_stops_with_the_last_good_state():
    """A state that overflows stops the run; what is reported is finite."""
    osc = BinghamOscillator(1.0, 1e300, 1.0, 0.0)
    out = np.empty(len(J.SUMMARY_FIELDS))
    J.summary_one(osc.m, osc.k, 1.0, 0.0, 1.0, 100, False, 1e10, 0.0, J.FORCE_ZERO,
                  0.0, 0.0, 0.0, out)
    assert out[2] < 100 and np.all(np.isfinite(out))
    with pytest.raises(FloatingPointError, match="non-finite state"):
        compiled(osc, 1e10, 0.0, None, 1.0, 100, "bdf1")


def test_non_finite_sampled_forcing_is_refused():
    with pytest.raises(ValueError, match="returned nan at t = 0.002"):
        compiled(PAPER, 0.0, 0.0, lambda t: math.nan if t > 1.5e-3 else 0.0, 1e-3, 10,
                 "bdf1")


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_integrate_engines_agree(method):
    """integrate() runs compiled by default once the compiled loops are loaded (they are,
    in this module): the same trajectory."""
    kw = dict(x0=0.3, v0=-1.0, forcing=paper_F2, dt=1e-3, n_steps=3000, method=method)
    a = integrate(PAPER, engine="python", **kw)
    for engine in ("auto", "compiled"):
        b = integrate(PAPER, engine=engine, **kw)
        np.testing.assert_array_equal(a.as_array(), b.as_array())
        np.testing.assert_array_equal(a.predictor, b.predictor)
    with pytest.raises(ValueError, match="`engine` must be one of"):
        integrate(PAPER, engine="fortran", **kw)


def test_auto_engine_keeps_short_runs_in_python():
    """In a fresh process a short run stays in Python (no numba start-up); a run of
    COMPILED_MIN_STEPS steps loads the compiled loops."""
    import subprocess
    import sys

    code = (
        "import sys\n"
        "from lumped.solvers.closed.closed_form import BinghamOscillator\n"
        "from lumped.solvers.closed.integrate import COMPILED_MIN_STEPS, integrate\n"
        "osc = BinghamOscillator(1.0, 100.0, 1.0, 1.0)\n"
        "integrate(osc, x0=0.5, dt=1e-4, n_steps=1000)\n"
        "print('lumped.solvers.closed.closed_form_jit' in sys.modules)\n"
        "integrate(osc, x0=0.5, dt=1e-5, n_steps=COMPILED_MIN_STEPS)\n"
        "print('lumped.solvers.closed.closed_form_jit' in sys.modules)\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True).stdout.split()
    assert out == ["False", "True"]


def _stepped_summary(m, k, gamma, tau, x0, v0, code, dt, n, bdf2):
    """Every step stored (``run_steps``), then the summary in ``summary_one``'s own
    order of operations: the numbers the rest shortcut must reproduce bit for bit."""
    cols = [np.zeros(n + 1) for _ in range(4)]
    cols[0][0], cols[1][0] = x0, v0
    assert J.run_steps(m, k, 1.0 / gamma, tau, dt, bdf2, *code, np.empty(0), *cols) == n
    x, v, Fd, _ = cols
    stick = cycles = events = 0
    work = 0.0
    for i in range(1, n + 1):
        if v[i] == 0.0:
            stick += 1
            if v[i - 1] != 0.0:
                cycles += 1
                events += 1
        elif v[i - 1] == 0.0 or (v[i] > 0.0) != (v[i - 1] > 0.0):
            events += 1
        work += dt * Fd[i] * v[i]
    return [x[n], v[n], n, stick, cycles, events, work, Fd[n]]


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
@pytest.mark.parametrize("code", [(J.FORCE_ZERO, 0.0, 0.0, 0.0),
                                  (J.FORCE_CONSTANT, 30.0, 0.0, 0.0),
                                  (J.FORCE_SINE, 10.0, 5.0 * math.pi, 1.0)],
                         ids=["zero", "constant", "sine-burst"])
@pytest.mark.parametrize("x0,gamma", [(0.2, 1.0), (0.1, 100.0), (0.005, 1.0)])
def test_summary_rest_shortcut_equals_stepping_to_the_end(method, code, x0, gamma):
    """The summary kernel stops at a state at rest that every later step maps onto
    itself: its summary is bit for bit the one of all ``n`` steps (these runs come to
    rest long before the end, under zero, constant and switched-off forcing)."""
    dt, n = 1e-3, 6000
    out = np.empty(len(J.SUMMARY_FIELDS))
    J.summary_one(1.0, 100.0, 1.0 / gamma, 1.0, dt, n, method == "bdf2", x0, 0.0, *code, out)
    want = _stepped_summary(1.0, 100.0, gamma, 1.0, x0, 0.0, code, dt, n, method == "bdf2")
    assert out.tolist() == want
    assert want[3] > n // 4  # at rest for a good part of the run: the shortcut had work
