"""radau5 ends a step at a kink of the force split among locks in parallel
(:mod:`lumped.solvers.modes.split_kink`): the held force's dense output stays in its lock's
interval, and the split's kink is where the tight run puts it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from _yield_check import check_yield

from lumped import simulate
from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene
from lumped.solvers.modes.crossing_root import collocation_at
from lumped.solvers.modes.split_kink import split_kink
from lumped.solvers.radau.tableau import C

TAU = 0.15900919888305598


#: The initial forces of :func:`_junction_cycle`: one split of the stuck cycle (``e3`` at
#: 0.06, inside its interval). The split is free; the consistent initial state picks one by
#: a Newton path whose last bits differ between machines, and on a fresh machine it picked
#: 0.028 for one run and ``tau`` itself for the other (their kinks 1 step apart, 2.4e-4 in
#: ``F_e3``): both runs start from this one.
_SPLIT = (-0.3197037700196149, -0.025827860923702376, -0.38684705544573383, 0.06,
          -0.29387590909591255, -0.007143285426118845)


def _junction_cycle() -> Scene:
    """Found by the random-network suite (seed 904): junctions ``j0, j1`` on a cycle of
    stuck dashpots (``e0`` to ground, ``e1`` and ``e4`` between them, the Coulomb element
    ``e3`` back to ground); the mass ``m2`` loads ``j1`` through ``e2`` and the spring;
    the initial split :data:`_SPLIT`."""
    hb = get_law("herschel_bulkley")
    coulomb = get_law("coulomb")
    scene = Scene(
        [Junction("j0", x0=-0.5063525432748816), Junction("j1", x0=0.06879456941831275),
         Mass("m2", m=0.49084106631382324, x0=0.07593785680518894, v0=-1.5781904564584641)],
        [Element("e0", hb.bind(gamma=1.0, tau=0.4272371205408794, n=0.8), "ground", "j0"),
         Element("e1", coulomb.bind(tau=0.025827860923701536, r=4.547637422802911), "j0", "j1"),
         Element("e2", hb.bind(gamma=3.1622776601683795, tau=0.1377785437600763, n=0.5),
                 "j1", "m2"),
         Element("e3", coulomb.bind(tau=TAU, r=1.3230933669863767), "j1", "ground"),
         Element("e4", hb.bind(gamma=0.4507733809541305, tau=1.0, n=0.3), "j0", "j1"),
         Element("e5", get_law("linear_spring").bind(k=0.9999997255105045), "m2", "j1")])
    return Scene(scene.nodes, [dataclasses.replace(el, F0=f)
                               for el, f in zip(scene.elements, _SPLIT, strict=True)])


def test_a_held_share_stays_below_the_yield_force_between_nodes():
    """The stuck cycle carries the load of ``m2``; ``e3``'s share rises to its yield force
    at t = 0.0626 and is held there (1e-6 of it inside) until the cycle breaks at t =
    0.1717. One step of 0.058 s spanned the kink: the cubic through its stages read
    ``e3`` 1.2e-4 above ``tau`` at t = 0.075 (rtol 3.9e-5), and the landing on the guard
    crossed between its samples gave up after 40 passes. The step now ends at the kink."""
    scene = _junction_cycle()
    h = 0.00625
    sol = simulate(scene, method="radau5", dt=h, t_end=0.5, rtol=h**2, atol=h**3,
                   compiled=False)
    assert sol.ok
    assert sol.stats["split_rejected"] >= 1
    check_yield(scene, sol, min(1e-3, 100.0 * h**2), 0.0, h**2)
    ts = np.linspace(0.05, 0.1, 501)
    F3 = sol.sol(ts)[:, sol.columns.index("F_e3")]
    assert F3.max() <= TAU
    tight = simulate(scene, method="radau5", dt=h, t_end=0.2, rtol=1e-10, atol=1e-12,
                     compiled=False)
    F3_tight = tight.sol(ts)[:, tight.columns.index("F_e3")]
    # the tight run's split: up to the kink near t = 0.063, then held at the bound (from
    # the split _SPLIT)
    assert F3_tight[ts > 0.064] == pytest.approx(TAU * (1 - 1e-6), rel=1e-12)
    assert np.abs(F3 - F3_tight).max() < 1e-4  # was 1.0e-3 (t = 0.063); rtol 3.9e-5
    assert [ev.element for ev in sol.events] == [ev.element for ev in tight.events]
    # (the break within the run's rtol: 1.8e-6 apart on a fresh machine, 1e-8 on another)
    assert sol.events[0].t == pytest.approx(tight.events[0].t, abs=h**2)


def _nodes(f) -> tuple[float, ...]:
    return (f(0.0), f(C[0]), f(C[1]), f(1.0))


def test_split_kink_where_the_free_split_leaves_its_interval():
    """A free share rising linearly through ``hi = 1`` at ``s = 0.6``; the held stages at
    the bound (1e-6 of the half-width inside) bend the cubic beyond it."""
    free = _nodes(lambda s: 0.4 + s)
    held = tuple(min(f, 1.0 - 1e-6) for f in free)
    assert max(collocation_at(s, *held) for s in np.linspace(0, 1, 101)) > 1.0 + 1e-4
    s = split_kink({0: (held, free)}, {0: (0.0, 1.0, -1.0, 1.0)}, 1e-8)
    assert s == pytest.approx(0.6, abs=1e-12)
    # nothing held, or an overshoot within the tolerance: no kink
    assert split_kink({0: (free[:1] + (0.5, 0.6, 0.7), free)},
                      {0: (0.0, 1.0, -1.0, 1.0)}, 1e-8) is None
    assert split_kink({0: (held, free)}, {0: (0.0, 1.0, -1.0, 1.0)}, 1.0) is None


def test_split_kink_where_a_held_share_comes_back():
    """Held at ``lo = -1`` from the start, the free share comes back above it at ``s =
    0.3``: the kink is there, not where the free split first left."""
    free = _nodes(lambda s: -1.0 + 1e-6 - 0.3 + s)
    held = tuple(max(f, -1.0 + 1e-6) for f in free)
    held = (-1.0 + 1e-6,) + held[1:]
    free = (-1.0 + 1e-6,) + free[1:]
    assert min(collocation_at(s, *held) for s in np.linspace(0, 1, 101)) < -1.0 - 1e-4
    s = split_kink({0: (held, free)}, {0: (0.0, 1.0, -1.0, 1.0)}, 1e-8)
    assert 0.2 < s < 0.5  # (the cubic through the held start is not the line)
    assert collocation_at(s, *free) == pytest.approx(-1.0 + 2e-6, abs=1e-12)
    assert all(collocation_at(r, *free) < -1.0 for r in np.linspace(0.05, s - 0.02, 20))


def test_no_kink_when_a_stage_is_beyond_its_interval():
    """A stage value itself beyond the interval: no split holds the locks, one of them
    breaks, and that is the guards' event, not a kink."""
    free = _nodes(lambda s: 0.4 + s)
    held = (0.4, 0.5, 0.9, 1.2)
    assert split_kink({0: (held, free)}, {0: (0.0, 1.0, -1.0, 1.0)}, 1e-8) is None


def test_the_start_after_an_impact_is_no_kink():
    """A mass hits the end of a string (to ground) beside three dashpots, and all four
    lock in parallel. The first step after the impact starts from the stage forces'
    quadratic, not from the event probe's forces (the string's read 0.50 there, its
    stages 0.077): read from the probe's, the cubic dipped below the string's ``k L`` and
    every step was cut to 0.12 of itself (20 000 steps moved ``t`` by 6e-12). Found by a
    counter of the random-network suite (seed 905)."""
    hb = get_law("herschel_bulkley")
    scene = Scene(
        [Mass("m0", m=1.333521432163324, x0=0.0, v0=-0.9695256114652275)],
        [Element("e0", hb.bind(gamma=1.0, tau=0.9998594712341624, n=2.0), "ground", "m0"),
         Element("e1", hb.bind(gamma=0.13487363131863606, tau=0.9998594712341624, n=0.8),
                 "ground", "m0"),
         Element("e2", get_law("bingham").bind(gamma=1.0001405485169472, tau=0.01), "m0",
                 "ground"),
         Element("e3", get_law("string_spring").bind(k=41.36766877814132,
                                                     L=0.0018130293922991414),
                 "m0", "ground")])
    h = 0.025
    sol = simulate(scene, method="radau5", dt=h, t_end=0.5, rtol=h**2, atol=h**3,
                   compiled=False, max_steps=2000)
    assert sol.ok and sol.stats["steps"] < 50
    assert [ev.kind for ev in sol.events][0] == "impact"
    # at rest on the taut string from the impact on
    after = sol.t > sol.events[0].t
    assert np.all(sol.v["m0"][after] == 0.0)
    assert sol.x["m0"][after] == pytest.approx(-0.0018130293922991414, rel=1e-9)
