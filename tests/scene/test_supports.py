"""Named supports with a prescribed motion (issue 28, item 1): exact solutions of a
harmonically driven linear oscillator and of a mass on a moving belt (stick-slip),
orders of convergence of bdf1/bdf2, a still support is the fixed ground exactly, scene
files, and every refused input or method."""

from __future__ import annotations

import math

import numpy as np
import pytest

from lumped import Element, Mass, Scene, get_law, simulate
from lumped.io import Table
from lumped.io.scenefile import SceneFileError, scene_from_dict
from lumped.scene import GroundMotion, Junction, SineBurst, paper_F1

# ---------------------------------------------------------------- a shaken oscillator

M, K1, K2, C = 1.0, 60.0, 40.0, 0.8
D, W = 0.05, 3.0  # x_s(t) = D sin(W t)


def shaken(support_end: str = "b") -> Scene:
    """A mass between a wall spring ``K1`` and a spring ``K2`` + dashpot ``C`` to a shaker:
    ``M x'' + C x' + (K1 + K2) x = K2 x_s + C v_s``. ``support_end`` says which end of the
    shaker elements the support is (``q = x_s - x`` at ``b``, ``x - x_s`` at ``a``)."""
    ends = ("m", "shaker") if support_end == "b" else ("shaker", "m")
    return Scene([Mass("m", M)],
                 [Element("wall", get_law("linear_spring").bind(k=K1), "ground", "m"),
                  Element("drive", get_law("linear_spring").bind(k=K2), *ends),
                  Element("damp", get_law("newtonian").bind(c=C), *ends)],
                 supports={"shaker": GroundMotion(displacement=SineBurst(amplitude=D,
                                                                         omega=W))})


def shaken_exact(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(x, v)`` from rest: the steady state ``A sin + B cos`` plus the damped free
    motion that starts the mass at rest."""
    k = K1 + K2
    # steady state: (k - M W^2 + i C W) X = (K2 + i C W) D
    X = (K2 + 1j * C * W) * D / (k - M * W**2 + 1j * C * W)
    A, B = X.real, X.imag  # x_p = A sin(W t) + B cos(W t)
    zeta_w = C / (2 * M)
    wd = math.sqrt(k / M - zeta_w**2)
    c1 = -B  # x_h(0) = -x_p(0)
    c2 = (-A * W + zeta_w * c1) / wd  # x_h'(0) = -x_p'(0)
    decay = np.exp(-zeta_w * t)
    x = A * np.sin(W * t) + B * np.cos(W * t) + decay * (c1 * np.cos(wd * t)
                                                           + c2 * np.sin(wd * t))
    v = (A * W * np.cos(W * t) - B * W * np.sin(W * t)
         + decay * ((-zeta_w * c1 + wd * c2) * np.cos(wd * t)
                    + (-zeta_w * c2 - wd * c1) * np.sin(wd * t)))
    return x, v


def _errors(method: str, scene: Scene, dts, t_end: float, exact) -> list[float]:
    out = []
    for dt in dts:
        sol = simulate(scene, method=method, dt=dt, t_end=t_end)
        assert sol.ok, sol.message
        x, _ = exact(sol.t)
        out.append(float(np.max(np.abs(sol.x["m"] - x))))
    return out


@pytest.mark.parametrize(("method", "dt", "order", "bound"),
                         [("bdf1", 2e-3, 1, 6e-4), ("bdf2", 1e-2, 2, 3e-4)])
@pytest.mark.parametrize("end", ["a", "b"])
def test_harmonic_support_converges_to_the_closed_form_at_the_method_order(method, dt, order,
                                                                           bound, end):
    # measured: bdf1 5.6e-4, 2.9e-4, 1.5e-4 (dt = 2e-3 ... 5e-4); bdf2 2.0e-4, 5.1e-5,
    # 1.3e-5 (dt = 1e-2 ... 2.5e-3)
    err = _errors(method, shaken(end), (dt, dt / 2, dt / 4), 3.0, shaken_exact)
    assert err[0] < bound, err
    rates = [math.log2(err[i] / err[i + 1]) for i in range(2)]
    assert all(order - 0.15 < r < order + 0.2 for r in rates), (err, rates)


def test_harmonic_support_forces_and_the_solution_columns():
    scene = shaken()
    sol = simulate(scene, method="bdf2", dt=1e-3, t_end=1.0)
    x_s = D * np.sin(W * sol.t)
    v_s = D * W * np.cos(W * sol.t)
    # the laws hold with the support's motion at every sample, exactly as solved
    np.testing.assert_allclose(sol.F["drive"], K2 * (x_s - sol.x["m"]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.F["damp"], C * (v_s - sol.v["m"]), rtol=0, atol=1e-12)
    np.testing.assert_allclose(sol.F["wall"], K1 * sol.x["m"], rtol=0, atol=1e-12)


# ---------------------------------------------------------------- a belt: stick-slip

MB, KB, TAU, VB = 1.0, 100.0, 1.0, 0.05


def belt(law: str = "coulomb") -> Scene:
    """A mass held by a wall spring on a belt moving at ``VB``: friction from the mass
    (``a``) to the belt (``b``), ``q = VB - v``."""
    params = {"tau": TAU, "r": 10.0} if law == "coulomb" else {"tau": TAU, "gamma": 1e8}
    return Scene([Mass("m", MB)],
                 [Element("wall", get_law("linear_spring").bind(k=KB), "ground", "m"),
                  Element("contact", get_law(law).bind(**params), "m", "belt")],
                 supports={"belt": GroundMotion(velocity=VB)})


def belt_phases() -> tuple[float, float]:
    """``(t1, t2)``: from rest the mass slips (friction ``+TAU``: a half-swing about
    ``TAU / KB``) until its velocity reaches the belt's at ``t1``, sticks (moves with the
    belt) until the spring force reaches ``TAU`` at ``t2``, then swings about ``TAU / KB``
    with amplitude ``VB / w``, touching the belt's velocity once per period."""
    w = math.sqrt(KB / MB)
    X = TAU / KB
    t1 = math.asin(VB / (X * w)) / w
    t2 = t1 + (X - X * (1.0 - math.cos(w * t1))) / VB
    return t1, t2


def belt_exact(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The event-driven exact solution of :func:`belt` from rest (see :func:`belt_phases`):
    slip ``x = X (1 - cos w t)``, stick ``x = x1 + VB (t - t1)``, slip
    ``x = X + (VB / w) sin(w (t - t2))``."""
    w = math.sqrt(KB / MB)
    X = TAU / KB
    t1, t2 = belt_phases()
    x1 = X * (1.0 - math.cos(w * t1))
    x = np.where(t < t1, X * (1 - np.cos(w * t)),
                 np.where(t < t2, x1 + VB * (t - t1), X + VB / w * np.sin(w * (t - t2))))
    v = np.where(t < t1, X * w * np.sin(w * t),
                 np.where(t < t2, VB, VB * np.cos(w * (t - t2))))
    return x, v


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_belt_sticks_with_the_belt_exactly_and_slips_when_the_spring_reaches_tau(method):
    dt = 1e-3
    sol = simulate(belt(), method=method, dt=dt, t_end=1.0)
    assert sol.ok, sol.message
    t1, t2 = belt_phases()
    stick = (sol.t > t1 + 2 * dt) & (sol.t < t2 - 2 * dt)
    assert stick.sum() > 150
    assert np.all(sol.v["m"][stick] == VB)  # the mass moves with the belt, exactly
    # while it sticks the contact carries the spring force, below tau
    np.testing.assert_allclose(sol.F["contact"][stick], KB * sol.x["m"][stick], rtol=1e-12)
    assert np.all(KB * sol.x["m"][stick] < TAU)
    # the stick ends within a step of t2, where the spring force reaches tau
    after = np.flatnonzero((sol.t > t1 + 2 * dt) & (sol.v["m"] != VB))[0]
    assert abs(sol.t[after] - t2) <= 2 * dt
    assert KB * sol.x["m"][after - 1] == pytest.approx(TAU, abs=KB * VB * 2 * dt)


@pytest.mark.parametrize(("method", "order", "bound"),
                         [("bdf1", 1, 0.25 * 1e-3), ("bdf2", 2, 2e-6)])
def test_belt_converges_to_the_event_driven_exact_solution(method, order, bound):
    err = _errors(method, belt(), (1e-3, 5e-4, 2.5e-4), 1.0, belt_exact)
    assert err[0] < bound, err
    rates = [math.log2(err[i] / err[i + 1]) for i in range(2)]
    assert all(r > order - 0.3 for r in rates), (err, rates)


def test_belt_with_a_stiff_bingham_contact_agrees_with_coulomb():
    a = simulate(belt("coulomb"), method="bdf2", dt=1e-3, t_end=1.0)
    b = simulate(belt("bingham"), method="bdf2", dt=1e-3, t_end=1.0)
    # Bingham's viscous part adds |q| / gamma to the friction force while slipping
    np.testing.assert_allclose(b.x["m"], a.x["m"], rtol=0, atol=1e-10)


# ---------------------------------------------------------------- a still support


def _paper(end: str, supports: dict | None) -> Scene:
    return Scene([Mass("mass", 1.0, x0=0.5)],
                 [Element("spring", get_law("linear_spring").bind(k=100.0), end, "mass"),
                  Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "mass", end)],
                 {"mass": paper_F1}, supports=supports)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_a_still_support_is_the_fixed_ground_bit_for_bit(method):
    fixed = simulate(_paper("ground", None), method=method, dt=1e-3, t_end=2.0)
    still = simulate(_paper("post", {"post": GroundMotion(displacement=0.0)}), method=method,
                     dt=1e-3, t_end=2.0)
    assert np.array_equal(still.data, fixed.data)


def test_jit_bdf_runs_supports_on_the_reference_solver_and_auto_picks_bdf2():
    ref = simulate(belt(), method="bdf2", dt=1e-3, t_end=0.5)
    jit = simulate(belt(), method="jit-bdf2", dt=1e-3, t_end=0.5)
    assert "moving supports" in jit.stats["fallback"]
    assert np.array_equal(jit.data, ref.data)
    auto = simulate(belt(), dt=1e-3, t_end=0.5)
    assert auto.method == "bdf2" and np.array_equal(auto.data, ref.data)


# ---------------------------------------------------------------- scene files

BELT_FILE = {
    "nodes": {"m": {"mass": MB}},
    "elements": {
        "wall": {"law": "linear_spring", "between": ["ground", "m"], "parameters": {"k": KB}},
        "contact": {"law": "coulomb", "between": ["m", "belt"],
                    "parameters": {"tau": TAU, "r": 10.0}}},
    "supports": {"belt": {"motion": {"kind": "expression", "quantity": "velocity",
                                     "expression": str(VB)}}},
}


def test_a_scene_file_support_runs_as_the_python_scene():
    scene, _ = scene_from_dict(BELT_FILE)
    assert scene.supports["belt"].quantity == "velocity"
    a = simulate(scene, method="bdf2", dt=1e-3, t_end=0.5)
    b = simulate(belt(), method="bdf2", dt=1e-3, t_end=0.5)
    np.testing.assert_allclose(a.data, b.data, rtol=0, atol=1e-15)


@pytest.mark.parametrize(("change", "match"), [
    ({"supports": 3}, "supports: must be a table"),
    ({"supports": {"belt": {"v0": 1.0}}}, r"\[supports.belt\] motion: missing"),
    ({"supports": {"belt": {"motion": 1.0, "speed": 2}}}, r"\[supports.belt\] speed"),
    ({"supports": {"ground": {"motion": 1.0}}}, "reserved"),
    ({"supports": {"belt": {"motion": 0.0}}, "ground": {"motion": 1.0}}, "together"),
])
def test_bad_support_tables_are_refused_naming_the_key(change, match):
    with pytest.raises(SceneFileError, match=match):
        scene_from_dict({**BELT_FILE, **change})


# ---------------------------------------------------------------- refused inputs

def _spring(a: str, b: str, name: str = "s") -> Element:
    return Element(name, get_law("linear_spring").bind(k=1.0), a, b)


STILL = GroundMotion(displacement=0.0)


@pytest.mark.parametrize(("kwargs", "error", "match"), [
    ({"supports": [("s", STILL)]}, TypeError, "`supports` must be a mapping"),
    ({"supports": {"post": 1.0}}, TypeError, r"`supports\['post'\]` must be a GroundMotion"),
    ({"supports": {"ground": STILL}}, ValueError, "reserved"),
    ({"supports": {"m": STILL}}, ValueError, "also the name of a node"),
    ({"supports": {"bad name": STILL}}, ValueError, "may contain only"),
    ({"supports": {"post": STILL, "other": STILL}}, ValueError,
     "support 'other' is not joined"),
    ({"supports": {"post": STILL}, "ground_motion": STILL}, ValueError, "together"),
])
def test_bad_supports_are_refused(kwargs, error, match):
    with pytest.raises(error, match=match):
        Scene([Mass("m", 1.0)], [_spring("post", "m")], **kwargs)


@pytest.mark.parametrize("ends", [("post", "ground"), ("post", "other"), ("ground", "post")])
def test_an_element_needs_a_node_at_one_end(ends):
    with pytest.raises(ValueError, match="needs a node"):
        Scene([Mass("m", 1.0)], [_spring("m", "ground", "t"), _spring(*ends)],
              supports={"post": STILL, "other": STILL})


def test_an_unknown_end_lists_the_supports():
    with pytest.raises(ValueError, match=r"supports: \['post'\]"):
        Scene([Mass("m", 1.0)], [_spring("post", "m"), _spring("pots", "m", "t")],
              supports={"post": STILL})


def test_elongations_of_a_support_scene_need_the_time():
    scene = shaken()
    with pytest.raises(ValueError, match="`t` must be a finite time"):
        scene.elongations([0.0], [0.0])
    t = 0.3
    q = scene.elongations([0.01], [0.2], t)
    assert q == pytest.approx([0.01, D * math.sin(W * t) - 0.01, D * W * math.cos(W * t) - 0.2],
                              abs=1e-15)


@pytest.mark.parametrize(("method", "match"), [
    ("closed-bdf2", "moving supports"),
    ("exact", "moving supports"),
])
def test_methods_without_supports_refuse_them(method, match):
    with pytest.raises(ValueError, match=match):
        simulate(belt(), method=method, dt=1e-3, t_end=0.1)


def test_a_string_on_a_support_runs_on_bdf2():
    """(tests/scene/test_support_strings.py: the impact and the moving lock)"""
    scene = Scene([Mass("m", 1.0)],
                  [_spring("ground", "m"),
                   Element("rope", get_law("string_spring").bind(k=1.0, L=0.1), "m", "belt")],
                  supports={"belt": GroundMotion(velocity=1.0)})
    sol = simulate(scene, method="bdf2", dt=1e-3, t_end=0.3)
    assert sol.ok and sol.stats["impacts"] == 1


# ---------------------------------------------------------------- results


def test_the_solution_carries_each_supports_motion_and_the_csv_its_columns(tmp_path):
    sol = simulate(shaken(), method="bdf2", dt=1e-3, t_end=0.5)
    tr = sol.supports["shaker"]
    np.testing.assert_allclose(tr.x, D * np.sin(W * sol.t), rtol=0, atol=1e-15)
    np.testing.assert_allclose(tr.v, D * W * np.cos(W * sol.t), rtol=0, atol=1e-14)
    np.testing.assert_allclose(tr.a, -D * W**2 * np.sin(W * sol.t), rtol=0, atol=1e-13)
    path = sol.to_csv(tmp_path / "run.csv")
    header = path.read_text().splitlines()[0].split(",")
    assert header == ["t", "x_m", "v_m", "F_wall", "F_drive", "F_damp", "x_shaker",
                      "v_shaker", "a_shaker", "a_m"]
    table = np.loadtxt(path, delimiter=",", skiprows=1)
    assert np.array_equal(table[:, 7], tr.v)


def test_the_stick_interval_of_the_belt_contact_is_the_exact_one():
    dt = 5e-4
    sol = simulate(belt(), method="bdf2", dt=dt, t_end=0.5)
    (start, end), = sol.stick_intervals("contact")
    t1, t2 = belt_phases()
    assert abs(start - t1) <= dt and abs(end - t2) <= dt


@pytest.mark.parametrize(("scene", "first"), [(shaken, 2e-7), (belt, 1e-5)])
def test_the_energy_ledger_closes_with_the_supports_work(scene, first):
    res = []
    for dt in (1e-3, 5e-4):
        ledger = simulate(scene(), method="bdf2", dt=dt, t_end=2.0).energy()
        assert len(ledger.support) == 1
        res.append(float(np.max(np.abs(ledger.residual))))
    assert res[0] < first and res[1] < 0.75 * res[0], res
    # without the support's work the ledger is off by O(1)
    assert float(np.max(np.abs(next(iter(ledger.support.values()))))) > 1e3 * res[1]


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_a_string_to_the_wall_stops_a_mass_driven_by_a_support(method):
    L = 0.02
    scene = Scene([Mass("m", 1.0)],
                  [Element("rope", get_law("string_spring").bind(k=10.0, L=L), "ground", "m"),
                   Element("drive", get_law("linear_spring").bind(k=100.0), "m", "shaker")],
                  supports={"shaker": GroundMotion(displacement=SineBurst(amplitude=0.05,
                                                                          omega=5.0))})
    sol = simulate(scene, method=method, dt=1e-3, t_end=3.0)
    assert sol.ok and sol.stats["impacts"] >= 3
    assert sol.x["m"].max() <= L * (1 + 1e-12)
    impacts = [ev for ev in sol.events if ev.kind == "impact"]
    assert len(impacts) == sol.stats["impacts"]


def test_a_mass_starting_at_the_belt_speed_sticks_until_the_spring_reaches_tau():
    dt = 1e-3
    scene = Scene([Mass("m", MB, v0=VB)],
                  [Element("wall", get_law("linear_spring").bind(k=KB), "ground", "m"),
                   Element("contact", get_law("coulomb").bind(tau=TAU, r=10.0), "m", "belt")],
                  supports={"belt": GroundMotion(velocity=VB)})
    sol = simulate(scene, method="bdf2", dt=dt, t_end=0.4)
    (start, end), = sol.stick_intervals("contact")
    assert start == 0.0 and abs(end - TAU / (KB * VB)) <= dt
    stuck = sol.t < end - dt
    assert np.all(sol.v["m"][stuck] == VB)
    np.testing.assert_allclose(sol.x["m"][stuck], VB * sol.t[stuck], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(sol.F["contact"][stuck], KB * sol.x["m"][stuck], rtol=1e-12,
                               atol=1e-15)


# ---------------------------------------------------------------- one support = a moving ground

DG, WG = 0.1, 4.0


def _network(end: str, **kw) -> Scene:
    """Two masses, a Maxwell-like chain through a junction and Bingham dashpots, every
    outside element to ``end``. From rest in absolute terms: relative to a ground moving
    with ``v_g(0) = DG WG`` the masses start at ``-DG WG``."""
    v0 = -DG * WG if end == "ground" else 0.0
    return Scene([Mass("m", 1.0, v0=v0), Junction("j"), Mass("m2", 0.5, v0=v0)],
                 [Element("spring", get_law("linear_spring").bind(k=50.0), end, "m"),
                  Element("dash", get_law("bingham").bind(gamma=0.5, tau=0.8), "m", end),
                  Element("s2", get_law("linear_spring").bind(k=30.0), "m", "j"),
                  Element("d2", get_law("bingham").bind(gamma=1.0, tau=0.3), "j", "m2"),
                  Element("s3", get_law("linear_spring").bind(k=20.0), end, "m2")], **kw)


def test_a_network_on_one_support_is_the_moving_ground_network_in_absolute_terms():
    """The same motion two ways: elements on a support (absolute states, offsets in the
    laws) and elements to a ground moving the same way (relative states, inertial
    forces); the reference is ``radau5`` at rtol 1e-11 on the latter."""
    motion = GroundMotion(displacement=SineBurst(amplitude=DG, omega=WG))
    ref = simulate(_network("ground", ground_motion=motion), method="radau5", rtol=1e-11,
                   atol=1e-13, dt=5e-4, t_end=4.0)
    err = {}
    for method in ("bdf1", "bdf2"):
        for dt in (1e-3, 5e-4):
            sol = simulate(_network("base", supports={"base": motion}), method=method, dt=dt,
                           t_end=4.0)
            step = round(dt / 5e-4)
            err[method, dt] = max(float(np.max(np.abs(sol.x[n] - ref.absolute.x[n][::step])))
                                  for n in ("m", "j", "m2"))
    # measured: bdf1 1.6e-3, 7.9e-4; bdf2 6.1e-5, 2.0e-5 (Bingham's stick-slip kinks)
    assert err["bdf1", 1e-3] < 2e-3 and err["bdf1", 5e-4] < 0.55 * err["bdf1", 1e-3]
    assert err["bdf2", 1e-3] < 8e-5 and err["bdf2", 5e-4] < 0.4 * err["bdf2", 1e-3]


# ---------------------------------------------------------------- the motion at one time


@pytest.mark.parametrize("motion", [
    GroundMotion(displacement=SineBurst(amplitude=0.02, omega=3.0)),
    GroundMotion(velocity="0.1*t*exp(-t)", x0=0.01),
    GroundMotion(acceleration=SineBurst(amplitude=1.0, omega=2.0, t_off=1.0), v0=0.2),
    GroundMotion(velocity=Table(np.linspace(0.0, 2.0, 9), np.sin(np.linspace(0.0, 2.0, 9)),
                                quantity="velocity")),
    GroundMotion(displacement=Table(np.linspace(0.0, 2.0, 9),
                                    np.cos(np.linspace(0.0, 2.0, 9)), quantity="displacement")),
])
def test_the_motion_at_one_time_is_the_motion_of_the_arrays(motion):
    t = np.array([0.0, 0.37, 1.0, 1.5, 2.5])
    arrays = np.array(motion.motion(t))
    scalars = np.array([motion.at(float(tk)) for tk in t]).T
    np.testing.assert_allclose(scalars, arrays, rtol=1e-14, atol=1e-15)
    assert all(type(val) is float for val in motion.at(0.5))


def test_a_velocity_record_drives_the_belt():
    """A belt whose velocity is a table equal to the constant ``VB``: the run of the
    constant belt, to round-off."""
    record = Table([0.0, 0.5, 2.0], [VB, VB, VB], quantity="velocity")
    scene = Scene([Mass("m", MB)],
                  [Element("wall", get_law("linear_spring").bind(k=KB), "ground", "m"),
                   Element("contact", get_law("coulomb").bind(tau=TAU, r=10.0), "m", "belt")],
                  supports={"belt": GroundMotion(velocity=record)})
    a = simulate(scene, method="bdf2", dt=1e-3, t_end=1.0)
    b = simulate(belt(), method="bdf2", dt=1e-3, t_end=1.0)
    np.testing.assert_allclose(a.data, b.data, rtol=0, atol=1e-12)


def test_a_run_leaves_the_scene_as_it_was():
    scene = belt()
    laws = [el.law for el in scene.elements]
    simulate(scene, method="bdf1", dt=1e-3, t_end=0.1)
    assert [el.law for el in scene.elements] == laws
    assert scene.support_clock is None and len(scene.support_ends) == 1


def test_relative_table_files_of_supports_are_resolved(tmp_path):
    from lumped.io.scene_inputs import resolve_files

    data = {"supports": {"belt": {"motion": {"kind": "table", "file": "belt.csv",
                                             "quantity": "velocity"}}}}
    out = resolve_files(data, tmp_path)
    assert out["supports"]["belt"]["motion"]["file"] == str((tmp_path / "belt.csv").resolve())
    assert data["supports"]["belt"]["motion"]["file"] == "belt.csv"


def test_a_fold_reached_through_a_support_stops_as_through_a_moving_ground():
    """An S-shaped spring to a shaker driven past its force maximum (``q = 2 q0``): the
    run stops at the fold at the same step as the same motion as a moving ground, and
    the message gives the law's own argument ``q = x_s - x``."""
    from lumped.solvers.status import BranchError

    motion = GroundMotion(displacement=SineBurst(amplitude=3.0, omega=2.0))

    def scene(end: str, **kw) -> Scene:
        return Scene([Mass("m", 1.0, v0=-6.0 if end == "ground" else 0.0)],
                     [Element("s", get_law("s_shaped").bind(q0=1.0, F0=1.0), "m", end),
                      Element("d", get_law("newtonian").bind(c=0.5), "m", end)], **kw)

    stops = []
    for s in (scene("base", supports={"base": motion}), scene("ground", ground_motion=motion)):
        with pytest.raises(BranchError, match=r"from \(q, F\) = \(1\.999") as err:
            simulate(s, method="bdf2", dt=1e-3, t_end=3.0)
        stops.append(err.value.t)
    assert stops[0] == stops[1] == pytest.approx(0.434)


def test_the_belt_example_runs_from_the_command_line(tmp_path):
    from pathlib import Path

    from lumped.cli import main

    example = Path(__file__).resolve().parents[2] / "examples" / "belt.toml"
    out = tmp_path / "belt.csv"
    assert main(["run", str(example), "--out", str(out)]) == 0
    header = out.read_text().splitlines()[0].split(",")
    assert header == ["t", "x_mass", "v_mass", "F_wall", "F_contact", "x_belt", "v_belt",
                      "a_belt", "a_mass"]
    data = np.loadtxt(out, delimiter=",", skiprows=1)
    t1, t2 = belt_phases()
    stick = (data[:, 0] > t1 + 1e-3) & (data[:, 0] < t2 - 1e-3)
    assert np.all(data[stick, 2] == VB) and np.all(data[:, 6] == VB)


@pytest.mark.parametrize("method", ["bdf1", "bdf2"])
def test_the_belt_drawn_the_other_way_is_the_same_motion_with_the_force_negated(method):
    """Friction from the belt (``a``) to the mass (``b``): ``q = v - VB``, the opposite
    offset sign; the law is odd, so the motion is the same bit for bit and ``F`` flips."""
    scene = Scene([Mass("m", MB)],
                  [Element("wall", get_law("linear_spring").bind(k=KB), "ground", "m"),
                   Element("contact", get_law("coulomb").bind(tau=TAU, r=10.0), "belt", "m")],
                  supports={"belt": GroundMotion(velocity=VB)})
    a = simulate(scene, method=method, dt=1e-3, t_end=1.0)
    b = simulate(belt(), method=method, dt=1e-3, t_end=1.0)
    assert np.array_equal(a.x["m"], b.x["m"]) and np.array_equal(a.v["m"], b.v["m"])
    assert np.array_equal(a.F["contact"], -b.F["contact"])
