"""A string (a position lock) on a moving support: the impact when the support jerks it
taut, and the lock that then moves the mass with the support (``bdf1``, ``bdf2`` and
``radau5``, each against closed forms, and ``bdf2`` converging to ``radau5``).

Closed forms. A mass ``m`` at rest at ``x = 0`` hangs on a spring-string (``string_spring``:
spring ``k``, taut at ``q = L``) to a support moving at ``V``, ``q = x_s - x``. The
relative motion is free, ``q'' = -w^2 q`` (``w^2 = k / m``), from ``q(0) = 0``,
``q'(0) = V``: ``q = V sin(w t) / w`` until ``q = L`` at ``t* = asin(L w / V) / w``, with
the rate ``q'_- = V cos(w t*)``. The impact (restitution ``e``, the support unmoved)
gives ``q'_+ = -e q'_-``, the impulse ``P = (1 + e) m q'_-`` and loses
``(1 - e^2) m q'_-^2 / 2``; then the string's spring ``k L`` pulls the mass ahead of the
support, ``q = L cos(w s) - e q'_- sin(w s) / w`` (``s = t - t*``), below ``L``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.scene import GroundMotion

M, K, L, V = 2.0, 1.0, 0.1, 0.5
W0 = math.sqrt(K / M)
T_END = 1.0


def jerked(e_sign: float = 1.0, k: float = K) -> Scene:
    """The mass on a string to a belt moving at ``V`` (``e_sign = -1``: the mirror image,
    the string drawn from the belt, moving at ``-V``, to the mass: ``q = x - x_s``)."""
    rope = get_law("string_spring").bind(k=k, L=L)
    ends = ("m", "belt") if e_sign > 0 else ("belt", "m")
    return Scene([Mass("m", M)], [Element("rope", rope, *ends)],
                 supports={"belt": GroundMotion(velocity=e_sign * V)})


def jerked_exact(t: np.ndarray, e: float, w: float = W0):
    """``(t*, q'_-, x(t), v(t))`` of :func:`jerked` (``e_sign = 1``)."""
    ts = math.asin(L * w / V) / w
    qd = V * math.cos(w * ts)
    s = np.maximum(t - ts, 0.0)
    q = np.where(t < ts, V * np.sin(w * t) / w, L * np.cos(w * s) - e * qd * np.sin(w * s) / w)
    dq = np.where(t < ts, V * np.cos(w * t), -L * w * np.sin(w * s) - e * qd * np.cos(w * s))
    return ts, qd, V * t - q, V - dq


def errors(sol, e: float, sign: float = 1.0) -> tuple[float, float, float, float]:
    """Errors of the impact's time and impulse and of ``x``, ``v`` after it (the samples
    one step clear of it: the exact velocity jumps there)."""
    (hit,) = [ev for ev in sol.events if ev.kind == "impact"]
    ts, qd, x, v = jerked_exact(sol.t, e)
    clear = np.abs(sol.t - ts) > 1.5 * (sol.t[1] - sol.t[0])
    return (abs(hit.t - ts), abs(hit.impulse - (1.0 + e) * M * qd),
            float(np.abs(sign * sol.x["m"] - x)[clear].max()),
            float(np.abs(sign * sol.v["m"] - v)[clear].max()))


# ---------------------------------------------------------------- the jerk taut

RADAU = {"rtol": 1e-8, "atol": 1e-10}


def run(scene: Scene, method: str, dt: float = 1e-3, **kw):
    """``simulate`` with ``dt`` (bdf) or :data:`RADAU`'s tolerances (radau5)."""
    step = RADAU if method == "radau5" else {"dt": dt}
    return simulate(scene, method=method, **step, **kw)


@pytest.mark.parametrize(("method", "order", "bound"), [("bdf1", 1, 0.1), ("bdf2", 2, 1.0)])
@pytest.mark.parametrize("e", [0.0, 0.5])
def test_the_jerk_taut_is_the_closed_form_to_the_methods_order(method, order, bound, e):
    """Measured (e = 0): bdf1 ``t*`` 1.0e-5, ``P`` 5.1e-5, ``x`` 1.6e-5, ``v`` 2.5e-5 at
    ``dt = 1e-3``, halving with ``dt``; bdf2 1.3e-7, 4.9e-7, 5.3e-8, 1.9e-7, about a
    quarter (``e = 0.5``: bdf1 1.0e-5, 7.6e-5, 3.3e-5, 5.9e-5; bdf2 1.3e-7, 7.4e-7,
    2.0e-7, 2.3e-7)."""
    errs = []
    for dt in (2e-3, 1e-3):
        sol = simulate(jerked(), method=method, dt=dt, t_end=T_END, restitution=e)
        assert sol.ok and sol.stats["impacts"] == 1
        errs.append(errors(sol, e))
    assert max(errs[1]) <= bound * 1e-3**order, errs
    # each error shrinks with dt at the method's order (bdf2: its first step after the
    # impact is bdf1's, the local O(dt^2) of the restart)
    for coarse, fine in zip(*errs, strict=True):
        assert fine <= coarse / (2.0**order * 0.7), errs


@pytest.mark.parametrize("e", [0.0, 0.5])
def test_radau5_jerks_the_string_taut_at_the_closed_forms_time_and_impulse(e):
    """Measured: ``t*`` 2.5e-15, ``P`` 1.2e-14 (1.8e-14 for ``e = 0.5``), ``x`` and ``v``
    after it 1.4e-12 and 6.3e-13 (1.8e-12, 4.3e-12) at rtol 1e-8."""
    sol = run(jerked(), "radau5", t_end=T_END, restitution=e)
    assert sol.ok
    t_err, p_err, x_err, v_err = errors(sol, e)
    assert t_err < 1e-13 and p_err < 1e-12 and x_err < 2e-11 and v_err < 5e-11


@pytest.mark.parametrize("method", ["bdf1", "bdf2", "radau5"])
def test_a_mirrored_string_gives_the_mirrored_motion(method):
    """The string drawn from the support to the mass (``q = x - x_s``, ``o_e = -x_s``),
    the support moving the other way: ``x`` and ``v`` change sign, nothing else."""
    sol = run(jerked(), method, t_end=T_END)
    mirror = run(jerked(-1.0), method, t_end=T_END)
    np.testing.assert_allclose(mirror.x["m"], -sol.x["m"], rtol=0, atol=1e-14)
    np.testing.assert_allclose(mirror.v["m"], -sol.v["m"], rtol=0, atol=1e-13)
    np.testing.assert_allclose(mirror.F["rope"], sol.F["rope"], rtol=0, atol=1e-11)
    (a,), (b,) = ([ev for ev in s.events if ev.kind == "impact"] for s in (sol, mirror))
    assert a.t == pytest.approx(b.t, abs=1e-15)
    assert a.impulse == pytest.approx(b.impulse, rel=1e-12)
    assert a.energy_lost == pytest.approx(b.energy_lost, rel=1e-12)


@pytest.mark.parametrize("method", ["bdf1", "bdf2", "radau5"])
@pytest.mark.parametrize("e", [0.0, 0.5, 1.0])
def test_a_mass_at_rest_jerked_by_a_string_takes_1_plus_e_times_the_support_speed(method, e):
    """A nearly pure string (``k = 1e-8``): taut at ``t* = L / V``, the mass jumps from rest
    to ``(1 + e) V``, the impulse is ``(1 + e) m V`` and the energy lost
    ``(1 - e^2) m V^2 / 2`` (the support's work ``(1 + e) m V^2`` less the kinetic energy
    gained)."""
    dt = 1e-3
    sol = run(jerked(k=1e-8), method, dt, t_end=0.5, restitution=e)
    (hit,) = [ev for ev in sol.events if ev.kind == "impact"]
    assert hit.t == pytest.approx(L / V, abs=1e-9)
    assert hit.impulse == pytest.approx((1.0 + e) * M * V, rel=1e-8)
    assert hit.energy_lost == pytest.approx((1.0 - e * e) * M * V * V / 2.0, abs=1e-8)
    after = sol.t > hit.t + (1.5 * dt if method != "radau5" else 0.0)
    np.testing.assert_allclose(sol.v["m"][after], (1.0 + e) * V, rtol=1e-7)
    if e == 0.0:  # plastic: then it moves with the support, on the lock
        np.testing.assert_allclose(sol.x["m"][after], V * sol.t[after] - L, rtol=0,
                                   atol=1e-8)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_the_energy_ledger_closes_with_the_supports_work_through_the_impulse(method):
    res = []
    for dt in (2e-3, 1e-3):
        sol = simulate(jerked(), method=method, dt=dt, t_end=T_END)
        ledger = sol.energy()
        res.append(float(np.max(np.abs(ledger.residual))))
    (hit,) = [ev for ev in sol.events if ev.kind == "impact"]
    work = ledger.support["belt"][-1]
    # the belt's work: V P at the impact plus int V F dt; the impulse's share dominates
    assert work > V * hit.impulse > 0.4
    assert res[1] < {"bdf1": 1e-5, "bdf2": 5e-8}[method] and res[1] < 0.6 * res[0], res


def test_the_energy_ledger_of_radau5_closes_with_the_supports_work():
    """Sampled on a grid (the ledger's trapezoidal rule is the error: measured 9.6e-7
    at ``dt = 1e-2``, 2.9e-8 at ``1e-3``; on radau5's own steps, 30 of them, 6.1e-6, and
    the impact's own sample holds the state just before it while the ledger books the
    impulse there, as for a string to the ground)."""
    res = []
    for dt in (1e-2, 1e-3):
        sol = simulate(jerked(), method="radau5", dt=dt, t_end=T_END, **RADAU)
        (hit,) = [ev for ev in sol.events if ev.kind == "impact"]
        ledger = sol.energy()
        assert ledger.support["belt"][-1] > V * hit.impulse > 0.4
        res.append(float(np.max(np.abs(ledger.residual))))
    assert res[1] < 1e-7 and res[1] < res[0] / 10.0, res


# ---------------------------------------------------------------- a lock moving with the support

P0, D, W = 3.0, 0.05, 4.0


def shaken_taut() -> Scene:
    """A mass on a taut string to a support shaken ``x_s = D sin(W t)``, pulled away from
    it by a constant load ``P0 > m D W^2 + k L``: it stays taut, ``x = x_s - L``, and the
    string carries ``F = P0 + m a_s(t)`` (``+F`` on the mass, at the string's end
    ``a``: ``m a = -P0 + F``)."""
    return Scene([Mass("m", M, x0=-L, v0=D * W)],
                 [Element("rope", get_law("string_spring").bind(k=K, L=L), "m", "shaker")],
                 forces={"m": f"-{P0}"},
                 supports={"shaker": GroundMotion(displacement=f"{D}*sin({W}*t)")})


@pytest.mark.parametrize("method", ["bdf2", "radau5"])
def test_the_string_starts_taut_with_the_load_and_the_supports_inertia(method):
    sol = run(shaken_taut(), method, t_end=1e-3)
    assert sol.F["rope"][0] == pytest.approx(P0, rel=1e-14)   # a_s(0) = 0
    assert not [ev for ev in sol.events if ev.kind == "impact"]


@pytest.mark.parametrize(("method", "order"), [("bdf1", 1), ("bdf2", 2)])
def test_a_string_kept_taut_moves_the_mass_with_the_support(method, order):
    """Measured at ``dt = 1e-3``: ``x`` exact to 3e-17 (the lock holds it), ``v`` 4.0e-4
    (bdf1) and 1.1e-6 (bdf2); ``F`` past the first steps 6.4e-3 (bdf1), 1.7e-5 (bdf2)."""
    errs = []
    for dt in (2e-3, 1e-3):
        sol = simulate(shaken_taut(), method=method, dt=dt, t_end=2.0)
        assert sol.ok and not [ev for ev in sol.events if ev.kind == "impact"]
        t = sol.t
        np.testing.assert_allclose(sol.x["m"], D * np.sin(W * t) - L, rtol=0, atol=1e-15)
        late = t > 20 * dt  # bdf2: past its bdf1 start
        errs.append((float(np.abs(sol.v["m"] - D * W * np.cos(W * t)).max()),
                     float(np.abs(sol.F["rope"] - (P0 - M * D * W**2 * np.sin(W * t)))[late]
                           .max())))
    for coarse, fine in zip(*errs, strict=True):
        assert fine <= coarse / (2.0**order * 0.7), errs
    assert errs[1][1] <= {"bdf1": 1e-2, "bdf2": 5e-5}[method], errs


def test_radau5_moves_the_mass_with_the_support_on_a_taut_string():
    """The stage system holds the lock on the velocity level, moved by the support's
    rates: measured ``x`` 2.2e-16, ``v`` 4.7e-16, ``F`` 8.6e-7 (the lock's force, an
    algebraic component the error estimate does not weigh) at rtol 1e-8."""
    sol = run(shaken_taut(), "radau5", t_end=2.0)
    assert sol.ok and not sol.events
    t = sol.t
    np.testing.assert_allclose(sol.x["m"], D * np.sin(W * t) - L, rtol=0, atol=1e-14)
    np.testing.assert_allclose(sol.v["m"], D * W * np.cos(W * t), rtol=0, atol=1e-13)
    np.testing.assert_allclose(sol.F["rope"], P0 - M * D * W**2 * np.sin(W * t), rtol=0,
                               atol=5e-6)


def test_bdf2_converges_to_radau5_on_a_string_that_goes_slack_and_taut_again():
    """A string to a shaken support without the load: it is jerked taut, goes slack and
    is jerked again (3 impacts by t = 3). bdf2 converges to radau5 (rtol 1e-10) at order
    >= 1 (the impacts limit it; measured ``x(3)`` 2.2e-7, 4.9e-8, 1.7e-8 at ``dt = 2e-3,
    1e-3, 5e-4``, slopes 2.2 and 1.5) and bdf1 toward the same motion (2.6e-5,
    1.3e-5)."""
    scene = Scene([Mass("m", 1.0)],
                  [Element("rope", get_law("string_spring").bind(k=4.0, L=0.02), "m",
                           "shaker"),
                   Element("damp", get_law("newtonian").bind(c=0.5), "ground", "m")],
                  supports={"shaker": GroundMotion(displacement="0.05*sin(5*t)")})
    t_end = 3.0
    ref = simulate(scene, method="radau5", rtol=1e-10, atol=1e-12, t_end=t_end)
    impacts = len([ev for ev in ref.events if ev.kind == "impact"])
    assert ref.ok and impacts == 3

    def err(method, dt):
        sol = simulate(scene, method=method, dt=dt, t_end=t_end)
        assert sol.stats["impacts"] == impacts
        return abs(sol.x["m"][-1] - ref.x["m"][-1])

    e2 = [err("bdf2", dt) for dt in (2e-3, 1e-3, 5e-4)]
    slopes = np.diff(np.log(e2)) / np.log(0.5)
    assert np.all(slopes >= 0.9), (e2, slopes)
    e1 = [err("bdf1", dt) for dt in (2e-3, 1e-3)]
    assert e1[1] <= 0.7 * e1[0] and e2[0] <= e1[0], (e1, e2)


def test_a_string_that_goes_slack_on_a_decelerating_support_and_taut_again():
    """The taut string of :func:`shaken_taut` with a load ``P0 = 1`` below ``m D W^2 +
    k L``: it goes slack where ``P0 + m a_s = k L`` (``t = asin(0.5625) / W``), is jerked
    taut at ``t = 1.1968``; at ``t = 1.5`` it is taut again. radau5 bridges the
    taut-to-slack point by backward Euler (its mode probe reads the lock's force only to
    ``m ulp(x_s) / h_p^2``, see the docs); bdf2 converges to it at order 2 in ``v(1.5)``
    (measured 1.0e-6, 2.6e-7, 6.4e-8 at ``dt = 1e-3, 5e-4, 2.5e-4``)."""
    scene = Scene([Mass("m", M, x0=-L, v0=D * W)],
                  [Element("rope", get_law("string_spring").bind(k=K, L=L), "m", "shaker")],
                  forces={"m": "-1.0"},
                  supports={"shaker": GroundMotion(displacement=f"{D}*sin({W}*t)")})
    ref = simulate(scene, method="radau5", rtol=1e-10, atol=1e-12, t_end=1.5)
    switch = [ev for ev in ref.events if ev.kind == "switch"]
    # (recorded at the bridge's end, 8e-7 s after the exact time)
    assert switch and switch[0].t == pytest.approx(math.asin(0.5625) / W, abs=2e-6)
    # (at rtol 1e-10 a second impact event at the same time, of impulse ~1e-17)
    assert {round(ev.t, 4) for ev in ref.events if ev.kind == "impact"} == {1.1968}
    assert ref.x["m"][-1] == pytest.approx(D * math.sin(W * 1.5) - L, abs=1e-15)
    errs = [abs(simulate(scene, method="bdf2", dt=dt, t_end=1.5).v["m"][-1] - ref.v["m"][-1])
            for dt in (1e-3, 5e-4, 2.5e-4)]
    slopes = np.diff(np.log(errs)) / np.log(0.5)
    assert errs[0] < 2e-6 and np.all(slopes > 1.8), (errs, slopes)


def test_two_masses_chattering_on_a_string_to_a_support_agree_across_methods():
    """A mass on a wall spring and a second one tied to it by a stiff spring and to a
    support by a string: each jerk taut is followed by a train of small impacts (the
    stiff spring pulls the second mass back). Every method runs it (the forces after a
    lock at a step's end from the balance of accelerations, where a hair of a substep
    would read ``m ulp(x_s) / h^2``); bdf2 and radau5 agree at ``t = 3`` (measured
    4e-7 in ``x_1``)."""
    scene = Scene([Mass("m1", 1.0), Mass("m2", 0.5)],
                  [Element("k1", get_law("linear_spring").bind(k=20.0), "ground", "m1"),
                   Element("k12", get_law("linear_spring").bind(k=50.0), "m1", "m2"),
                   Element("rope", get_law("string_spring").bind(k=1.0, L=0.05), "m2",
                           "belt"),
                   Element("c", get_law("newtonian").bind(c=0.2), "m1", "m2")],
                  supports={"belt": GroundMotion(velocity="0.3*sin(3*t)")})
    runs = {m: run(scene, m, t_end=3.0) for m in ("bdf1", "bdf2", "radau5")}
    assert all(sol.ok for sol in runs.values())
    assert abs(runs["bdf2"].x["m1"][-1] - runs["radau5"].x["m1"][-1]) < 2e-6
    assert abs(runs["bdf1"].x["m1"][-1] - runs["radau5"].x["m1"][-1]) < 2e-4
    for sol in runs.values():  # taut at the end: the second mass moves with the belt
        assert sol.x["m2"][-1] == pytest.approx(sol.supports["belt"].x[-1] - 0.05, abs=1e-14)
