"""Beyond one mass (issue 8): the chain and Maxwell scenes, radau5's error against the
tolerance, against the fixed-step BDF2 extrapolated to dt -> 0, and the tanh-smoothed
network peer."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

from lumped import load_scene, simulate
from lumped.bench.network_peers import TanhNetwork, solve_tanh_network
from lumped.bench.network_scenes import (
    NETWORK_SCENES,
    bingham_chain,
    maxwell_exact,
    maxwell_example,
    network_scene,
)
from lumped.bench.network_study import (
    BdfLadder,
    bdf2_ladder,
    bdf2_limit,
    grid,
    node_x,
    richardson,
)
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


# ------------------------------------------------------------------------- the scenes


def test_the_maxwell_scene_is_the_example_file():
    scene, _ = load_scene(EXAMPLES / "maxwell.toml")
    built = maxwell_example()
    assert scene.node_names == built.node_names
    assert [(n.x0, getattr(n, "m", None)) for n in scene.nodes] == [
        (n.x0, getattr(n, "m", None)) for n in built.nodes]
    assert [(e.name, e.a, e.b, e.law_name, dict(e.law.params)) for e in scene.elements] == [
        (e.name, e.a, e.b, e.law_name, dict(e.law.params)) for e in built.elements]


def test_the_chain_example_file_is_the_three_mass_chain():
    scene, settings = load_scene(EXAMPLES / "bingham-chain-3.toml")
    kw = {"method": "radau5", "t_end": 3.5, "rtol": 1e-6, "atol": 1e-9}
    a, b = simulate(scene, **kw), simulate(bingham_chain(3), **kw)
    assert settings["method"] == "radau5" and a.columns == b.columns
    # the file's forcing is an expression, so its run steps through the stuck start that
    # the built chain's sine burst takes in one piece (lumped.solvers.modes.stuck): the same
    # events (the burst's switch-off is one too) and the same motion to the tolerance
    assert [(e.element, e.kind) for e in a.events] == [(e.element, e.kind) for e in b.events]
    assert max(abs(e.t - f.t) for e, f in zip(a.events, b.events, strict=True)) <= 1e-9
    assert b.stats["held_intervals"] >= 1 and a.stats["held_intervals"] == 0
    t = np.linspace(0.0, 3.5, 701)
    assert np.abs(a.sol(t)[:, 1:7] - b.sol(t)[:, 1:7]).max() <= 1e-6


@pytest.mark.parametrize("n", [2, 3])
def test_every_chain_dashpot_sticks_and_slips(n):
    scene = bingham_chain(n)
    sol = simulate(scene, method="radau5", t_end=5.0, rtol=1e-6, atol=1e-9)
    assert sol.ok
    for i in range(1, n + 1):
        v_rel = sol.column(f"v_m{i}") - (sol.column(f"v_m{i - 1}") if i > 1 else 0.0)
        stuck = v_rel == 0.0
        # exactly stuck on some steps, slipping both ways on others, and at rest at the end
        assert stuck.any() and (v_rel > 1e-3).any() and (v_rel < -1e-3).any(), i
        assert stuck[-1]
        assert any(ev.element == f"d{i}" for ev in sol.events)


def test_network_scene_names():
    assert [s.name for s in NETWORK_SCENES] == ["chain-2", "chain-3", "maxwell"]
    assert network_scene("maxwell").build().node_names == ("mass", "j")
    with pytest.raises(ValueError, match=r"`name` .*'chain-9'"):
        network_scene("chain-9")
    with pytest.raises(ValueError, match=r"`n` .*got 4"):
        bingham_chain(4)


# ------------------------------------------------------------ error against tolerance


def _errors(scene, t_end, rtols, x_ref, g):
    return [float(np.max(np.abs(node_x(simulate(scene, method="radau5", t_end=t_end,
                                                 rtol=r, atol=1e-3 * r), scene, g) - x_ref)))
            for r in rtols]


def test_maxwell_error_falls_with_the_tolerance():
    scene, g = maxwell_example(), grid(2.0, 1e-2)
    errs = _errors(scene, 2.0, (1e-5, 1e-7, 1e-9), maxwell_exact(g), g)
    # about 0.1 rtol at each level, falling by at least 30 per factor 100
    assert all(e <= r for e, r in zip(errs, (1e-5, 1e-7, 1e-9), strict=True)), errs
    assert errs[0] >= 30 * errs[1] and errs[1] >= 30 * errs[2], errs


def test_chain_error_falls_with_the_tolerance():
    scene, g = bingham_chain(2), grid(1.5, 1e-2)
    ref = simulate(scene, method="radau5", t_end=1.5, rtol=1e-11, atol=1e-14)
    assert sum(ev.kind == "switch" for ev in ref.events) >= 4
    errs = _errors(scene, 1.5, (1e-5, 1e-7, 1e-9), node_x(ref, scene, g), g)
    assert all(e <= r for e, r in zip(errs, (1e-5, 1e-7, 1e-9), strict=True)), errs
    assert errs[0] >= 30 * errs[1] and errs[1] >= 30 * errs[2], errs


# ------------------------------------------------------ against BDF2 as dt -> 0


def test_richardson_removes_a_smooth_error_term_exactly():
    y = np.array([[1.0, -2.0]])
    runs = [y + 3.0 * h ** 2 - 0.5 * h ** 3 for h in (0.1, 0.05, 0.025, 0.0125)]
    ladder = BdfLadder([0.1, 0.05, 0.025, 0.0125], runs, [1, 2, 4, 8])
    assert ladder.orders()[-1] == pytest.approx(2.0, abs=0.05)
    lim = bdf2_limit(ladder)
    assert lim.how == "richardson p=2"
    # what is left of -0.5 h^3 from the pair (h, h/2) = (0.025, 0.0125) is
    # -0.5 (4 (h/2)^3 - h^3) / 3 = h^3 / 12, and the estimate is larger
    left = np.max(np.abs(lim.x - y))
    assert left == pytest.approx(0.025 ** 3 / 12, rel=1e-6) and lim.error_estimate >= left
    first = [y + 2.0 * h for h in (0.1, 0.05, 0.025)]
    np.testing.assert_allclose(richardson(first[1], first[2], 1.0), y, atol=1e-15)
    erratic = BdfLadder([0.1, 0.05, 0.025], [y + h * (1 + (i % 2)) for i, h in
                                             enumerate((0.1, 0.05, 0.025))], [1, 2, 4])
    assert bdf2_limit(erratic).how == "finest run"
    with pytest.raises(ValueError, match="`order`"):
        richardson(first[0], first[1], 0.0)


def test_maxwell_bdf2_extrapolates_at_order_two_to_radau5():
    scene = maxwell_example()
    lad = bdf2_ladder(scene, 1.0, [1e-3 / 2 ** j for j in range(0, 4)], 1e-3, method="bdf2")
    assert all(abs(p - 2.0) < 0.1 for p in lad.orders()), lad.orders()
    lim = bdf2_limit(lad)
    g = grid(1.0, 1e-3)
    exact = maxwell_exact(g[::50])
    assert lim.how == "richardson p=2"
    assert np.max(np.abs(lim.x[::50] - exact)) <= lim.error_estimate
    ours = simulate(scene, method="radau5", t_end=1.0, rtol=1e-10, atol=1e-13)
    assert np.max(np.abs(node_x(ours, scene, g) - lim.x)) <= 2 * lim.error_estimate + 1e-9


def test_chain_radau5_agrees_with_the_bdf2_limit():
    """Across stick-slip events BDF2's error is about ``C h`` with a constant ``C`` that
    jumps between halvings (each event's place inside its step jumps), so no Richardson
    extrapolation applies: the limit is the finest run ``y_H`` and its error is at most
    about ``C_max H``, ``C_max`` the largest ``|y_h - y_{h/2}| / (h/2)`` of the ladder
    (:func:`bdf2_limit`). radau5 at rtol 1e-10 (error near 1e-11) must lie within 1.5
    times that of the limit (the margin covers a later halving with a larger ``C``)."""
    scene = bingham_chain(2)
    lad = bdf2_ladder(scene, 1.0, [1e-3 / 2 ** j for j in range(1, 5)], 1e-3, method="bdf2")
    lim = bdf2_limit(lad)
    assert lim.how == "finest run" and lim.error_estimate < 2e-5
    ours = simulate(scene, method="radau5", t_end=1.0, rtol=1e-10, atol=1e-13)
    assert sum(ev.kind == "switch" for ev in ours.events) >= 4
    diff = np.max(np.abs(node_x(ours, scene, grid(1.0, 1e-3)) - lim.x))
    assert diff <= 1.5 * lim.error_estimate, (diff, lim.error_estimate, lim.orders)
    # and BDF2 does converge: the differences shrink over the ladder
    d = lad.differences()
    assert d[-1] <= 0.4 * d[0], d


# ------------------------------------------------------------- the tanh network peer


def _junction_bingham_scene():
    """ground --bingham-- j --spring-- m1 --bingham-- m2, with a force on m2: a junction
    whose velocity solves a nonlinear (tanh) balance."""
    lin, bing = get_law("linear_spring"), get_law("bingham")
    return Scene(
        [Mass("m1", 1.0), Junction("j"), Mass("m2", 0.5)],
        [Element("dj", bing.bind(gamma=0.5, tau=1.0), "ground", "j"),
         Element("sj", lin.bind(k=30.0), "j", "m1"),
         Element("s2", lin.bind(k=20.0), "m1", "m2"),
         Element("d2", bing.bind(gamma=2.0, tau=0.4), "m1", "m2"),
         Element("c", get_law("coulomb").bind(tau=0.3, r=1.0), "ground", "m2")],
        {"m2": "2*sin(3*t)"})


SCENES = {"chain-3": lambda: bingham_chain(3), "maxwell": maxwell_example,
          "junction": _junction_bingham_scene}


@given(st.sampled_from(sorted(SCENES)), st.floats(0.0, 5.0),
       st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_the_peer_rhs_obeys_the_exact_laws_away_from_zero_rate(which, t, vals):
    """Where every dashpot slips (``|q| >> eps``), the smoothed model's state and rates
    satisfy the scene's own DAE (momentum, kinematics, junction balances and the exact
    laws' residuals) to round-off."""
    scene = SCENES[which]()
    eps = 1e-9
    model = TanhNetwork(scene, eps)
    y = vals[: len(model.y0)]
    dy = model.rhs(t, y)
    n = len(scene.nodes)
    x, v = y[:n], dy[:n]
    vdot = [0.0] * n
    for s, i in enumerate(model.masses):
        vdot[i] = dy[n + s]
    q = scene.elongations(x, v)
    assume(all(abs(q[e]) > 1e-5 for e, el in enumerate(scene.elements)
               if el.kind == "dashpot"))
    F = [model.force(e, q[e]) for e in range(len(q))]
    res = scene.dae_residual(t, x, v, v, vdot, F)
    scale = 1.0 + max(abs(f) for f in F) + max(abs(c) for c in v)
    assert max(abs(r) for r in res) <= 1e-12 * scale, res


@given(st.sampled_from(sorted(SCENES)), st.floats(0.0, 5.0),
       st.lists(st.floats(-1.0, 1.0), min_size=6, max_size=6))
def test_the_peer_jacobian_is_the_derivative_of_its_rhs(which, t, vals):
    model = TanhNetwork(SCENES[which](), eps=0.3)
    y = np.array(vals[: len(model.y0)])
    J = model.jac(t, y)
    h = 1e-6
    for k in range(len(y)):
        e = np.zeros_like(y)
        e[k] = h
        fd = (np.array(model.rhs(t, y + e)) - np.array(model.rhs(t, y - e))) / (2 * h)
        np.testing.assert_allclose(J[:, k], fd, rtol=1e-5, atol=1e-5 * (1 + np.abs(fd).max()))


def test_the_peer_converges_to_radau5_as_eps_shrinks():
    scene, g = bingham_chain(2), grid(1.5, 1e-2)
    ref = node_x(simulate(scene, method="radau5", t_end=1.5, rtol=1e-10, atol=1e-13),
                 scene, g)
    errs = []
    for eps in (1e-3, 1e-5, 1e-7):
        x, stats = solve_tanh_network(scene, 1.5, g, eps=eps, rtol=1e-3 * eps,
                                      atol=1e-6 * eps)
        errs.append(float(np.max(np.abs(x - ref))))
        assert stats["steps"] > 0 and stats["nfev"] > stats["steps"]
    assert errs[0] > 30 * errs[1] > 900 * errs[2] and errs[2] < 1e-6, errs
    # the Maxwell junction (algebraic velocity) against its exact solution
    gm = grid(2.0, 1e-2)
    xm, _ = solve_tanh_network(maxwell_example(), 2.0, gm, eps=1e-6, rtol=1e-10,
                               atol=1e-13)
    assert np.max(np.abs(xm - maxwell_exact(gm))) <= 1e-8


def test_the_peer_refuses_what_it_cannot_smooth():
    lin = get_law("linear_spring")
    hb = Scene([Mass("m", 1.0)],
               [Element("d", get_law("herschel_bulkley").bind(gamma=1.0, tau=1.0, n=2.0),
                        "ground", "m")])
    with pytest.raises(ValueError, match=r"law 'herschel_bulkley' \(element 'd'\)"):
        TanhNetwork(hb, 1e-3)
    springs_only = Scene([Mass("m", 1.0), Junction("j")],
                         [Element("a", lin.bind(k=1.0), "ground", "j"),
                          Element("b", lin.bind(k=1.0), "j", "m")])
    with pytest.raises(ValueError, match="junction 'j' is touched by no dashpot"):
        TanhNetwork(springs_only, 1e-3)
    for bad in (0.0, -1.0, math.nan, "1"):
        with pytest.raises(ValueError, match=r"`eps` .*" + re.escape(repr(bad))):
            TanhNetwork(maxwell_example(), bad)
