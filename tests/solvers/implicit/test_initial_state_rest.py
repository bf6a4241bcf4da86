"""The consistent initial state's shortcut without Newton (every force fixed by its law,
or the rest held by locks on a regular balance) against the limit system it skips."""

from __future__ import annotations

import math

from hypothesis import HealthCheck, event, example, given, settings
from hypothesis import strategies as st

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene
from lumped.solvers.implicit import initial_kept, initial_state
from lumped.solvers.implicit.initial_state import consistent_initial_state

DASHPOTS = ("newtonian", "bingham", "coulomb", "herschel_bulkley")
SPRINGS = ("linear_spring", "string_spring")


def _with_newton(scene: Scene, time_scale: float):
    """The initial state by the limit system's Newton (the shortcut off; the state kept
    for this scene object, the shortcut's, is not read and not kept)."""
    keep = initial_state.initial_rest_forces
    initial_state.initial_rest_forces = lambda *args: None
    initial_kept.forget(scene)
    try:
        return consistent_initial_state(scene, time_scale=time_scale)
    finally:
        initial_state.initial_rest_forces = keep
        initial_kept.forget(scene)


def _same(a: list[float], b: list[float]) -> bool:
    """Equal to 2 ulps of the largest force of the two states: a force is a balance of
    the others, so its round-off is that of the largest one (a stuck element's force is
    0 from the shortcut and 7.5e-17 from Newton's balance of forces 0.75, in a draw)."""
    scale = max((abs(x) for x in (*a, *b)), default=0.0)
    return all(x == y or abs(x - y) <= 2.0 * math.ulp(scale)
               for x, y in zip(a, b, strict=True))


def _decade(lo: float, hi: float):
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0 ** e)


def _law(draw, name: str, q0: float):
    if name == "linear_spring":
        return get_law(name).bind(k=draw(_decade(0.1, 1e4)))
    if name == "string_spring":  # slack, or taut at exactly its length
        L = max(q0, 0.0) + draw(st.sampled_from([0.0, 1e-3, 0.5]))
        return get_law(name).bind(k=draw(_decade(0.1, 100.0)), L=L)
    if name == "newtonian":
        return get_law(name).bind(c=draw(_decade(0.01, 10.0)))
    if name == "bingham":
        return get_law(name).bind(gamma=draw(_decade(0.1, 10.0)), tau=draw(_decade(0.01, 10.0)))
    if name == "coulomb":
        return get_law(name).bind(tau=draw(_decade(0.01, 10.0)), r=draw(_decade(1.0, 100.0)))
    return get_law(name).bind(gamma=draw(_decade(0.1, 10.0)), tau=draw(_decade(0.01, 10.0)),
                              n=draw(st.sampled_from([0.5, 1.0, 2.0])))


def _value(lo: float, hi: float):
    """Floats in ``[lo, hi]``, zero or above ``1e-6`` in size: Newton stops within its
    ``atol = 1e-12``, so forces far below it are Newton's only to that tolerance (loads of
    ``1e-156`` came out a few ulps apart, the two forces of one chain differing from each
    other; a load of ``1e-309`` underflows in the LU and stays on the acceleration), where
    the shortcut gives the balance to round-off."""
    return st.floats(lo, hi).filter(lambda f: f == 0.0 or abs(f) > 1e-6)


@st.composite
def mass_networks(draw):
    """1 to 4 masses (mostly at rest) joined to ground and to each other by springs and
    dashpots; a constant load on some masses."""
    n = draw(st.integers(1, 4))
    x0 = [draw(_value(-1.0, 1.0)) for _ in range(n)]
    nodes = [Mass(f"m{i}", m=draw(_decade(0.1, 10.0)), x0=x0[i],
                  v0=draw(st.sampled_from([0.0, 0.0, 0.0, 0.3]))) for i in range(n)]
    names = ["ground"] + [nd.name for nd in nodes]
    pos = {"ground": 0.0, **{nd.name: x0[i] for i, nd in enumerate(nodes)}}
    pairs = [(names[draw(st.integers(0, i))], names[i + 1]) for i in range(n)]
    for _ in range(draw(st.integers(0, 3))):
        a, b = draw(st.permutations(names))[:2]
        pairs.append((a, b))
    elements = []
    for e, (a, b) in enumerate(pairs):
        name = draw(st.sampled_from(DASHPOTS + SPRINGS + DASHPOTS))
        elements.append(Element(f"e{e}", _law(draw, name, pos[b] - pos[a]), a, b))
    forces = {nd.name: draw(_value(-5.0, 5.0)) for nd in nodes if draw(st.booleans())}
    return Scene(nodes, elements, forces)


#: A Herschel-Bulkley dashpot (``n = 0.5``) slipping from rest under a load: Newton stops
#: at ``0.09999999532787847``, inside the set, the shortcut at the edge ``0.1``.
_DEGENERATE_EDGE = Scene(
    [Mass("m0", m=1.0)],
    [Element("e0", get_law("herschel_bulkley").bind(gamma=1.0, tau=0.1, n=0.5), "ground", "m0")],
    {"m0": 1.0})


@settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(mass_networks())
@example(_DEGENERATE_EDGE)
def test_shortcut_agrees_with_the_limit_system(scene):
    try:
        v1, F1, st1 = _with_newton(scene, 1.0)
    except Exception as err:  # noqa: BLE001 - the shortcut must then refuse the same way
        event("no initial state")
        try:
            consistent_initial_state(scene, time_scale=1.0)
        except type(err):
            return
        raise AssertionError(f"the shortcut found a state where Newton raised {err!r}") from None
    v2, F2, st2 = consistent_initial_state(scene, time_scale=1.0)
    event("shortcut" if st2["newton_iterations"] == 0 else "newton")
    assert v1 == v2
    edges = _slip_edges(scene, F2)
    if edges:
        event("a dashpot slips from rest")
    for e in edges:  # the shortcut exactly at the edge; Newton in the set, near it
        assert _within_edge(scene.elements[e].law.kernel, F1[e], F2[e]), (e, F1, F2)
    others = [e for e in range(len(F1)) if e not in edges]
    assert _same([F1[e] for e in others], [F2[e] for e in others]), (F1, F2)


def _slip_edges(scene: Scene, F: list[float]) -> list[int]:
    """The dashpots at the edge of their set at rest (``F`` admitted at rest, the next
    float outwards not) on a moving mass: those the shortcut puts at the edge of a
    dashpot slipping from rest."""
    net = scene.net_forces(0.0, F)
    out = []
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot" or F[e] == 0.0:
            continue
        kernel = el.law.kernel
        outwards = math.nextafter(F[e], math.copysign(math.inf, F[e]))
        end = scene.elem_b[e] if scene.elem_b[e] >= 0 else scene.elem_a[e]
        if (kernel(0.0, F[e])[0] == 0.0 and kernel(0.0, outwards)[0] != 0.0
                and abs(net[end]) > 1e-9 * (abs(F[e]) + 1.0)):
            out.append(e)
    return out


def _within_edge(kernel, newton: float, edge: float) -> bool:
    """Newton's force of a dashpot slipping from rest: in its set at rest, on the edge's
    side, within ``1e-6`` of the edge. The limit system's rate ``eps a`` (``eps =
    1e-20``) is met to Newton's ``atol`` anywhere in the set, so Newton stops where its
    correction falls below its tolerance, short of the edge where the slip is degenerate
    (Herschel-Bulkley ``n = 0.5``, ``tau = 0.1``, a load 1: ``0.09999999532787847``); the
    shortcut gives the limit ``tau + (eps a / gamma)^(1/n)``, the edge, exactly."""
    return (kernel(0.0, newton)[0] == 0.0 and newton * edge > 0.0
            and abs(newton - edge) <= 1e-6 * abs(edge))


def test_shortcut_is_taken_at_rest():
    """A mass at rest under a spring load its stuck dashpot holds (the paper's
    release-0.005), and a chain of three stuck masses under loads: no Newton, the
    forces of the limit system."""
    bingham = get_law("bingham").bind(gamma=1.0, tau=1.0)
    one = Scene([Mass("mass", m=1.0, x0=0.005)],
                [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
                 Element("dashpot", bingham, "ground", "mass")])
    chain = Scene([Mass(f"m{i}", m=1.0 + i, x0=0.01 * i) for i in range(3)],
                  [Element("d0", bingham, "ground", "m0"), Element("d1", bingham, "m0", "m1"),
                   Element("d2", bingham, "m1", "m2"),
                   Element("s0", get_law("linear_spring").bind(k=7.0), "ground", "m2")],
                  {"m0": 0.3, "m1": -0.2})
    for scene in (one, chain):
        v, F, stats = consistent_initial_state(scene, time_scale=2.0)
        assert stats["newton_iterations"] == 0
        v1, F1, stats1 = _with_newton(scene, 2.0)
        assert stats1["newton_iterations"] > 0
        assert v == v1
        assert _same(F, F1), (F, F1)
    assert consistent_initial_state(one)[1] == [0.5, -0.5]


def _oscillator(m: float, k: float, dashpot, x0: float, F0: float) -> Scene:
    return Scene([Mass("mass", m=m, x0=x0)],
                 [Element("spring", get_law("linear_spring").bind(k=k), "ground", "mass"),
                  Element("dashpot", dashpot, "ground", "mass")], {"mass": F0})


def test_a_dashpot_slipping_from_rest_takes_its_yield_force_without_newton():
    """The bench's viscous-soft (``k x0 = 3 > tau = 0.5``) and an oscillator under a load
    (issue 27): the dashpot slips from rest, its initial force is the yield force with the
    load's sign, exactly, as the closed form's
    :func:`~lumped.solvers.closed.closed_form.initial_dashpot_force`, with no Newton. The
    limit system's Newton stops within its tolerance, at or inside the yield force
    (``-0.09999999999999964`` for ``tau = 0.1``, ``k x0 = 5``)."""
    from lumped.solvers.closed.closed_form import BinghamOscillator, initial_dashpot_force

    cases = [(1.0, 10.0, 0.2, 0.5, 0.3, 0.0, 5.0), (1.0, 100.0, 1.0, 0.1, 0.05, 0.0, 1.0),
             (0.5, 100.0, 0.2, 1.0, -0.3, 0.0, 5.0), (2.0, 3.0, 50.0, 0.7, 0.1, -4.0, 1e3)]
    for m, k, gamma, tau, x0, F0, time_scale in cases:
        scene = _oscillator(m, k, get_law("bingham").bind(gamma=gamma, tau=tau), x0, F0)
        v, F, stats = consistent_initial_state(scene, time_scale=time_scale)
        osc = BinghamOscillator(m=m, k=k, gamma=gamma, tau=tau)
        assert stats["newton_iterations"] == 0, (m, k, x0)
        assert v == [0.0]
        assert F[1] == initial_dashpot_force(osc, x0, 0.0, F0) == math.copysign(tau, F0 - k * x0)
        assert F[0] == _with_newton(scene, time_scale)[1][0]  # (the spring's, by its law)


@st.composite
def _slipping_oscillators(draw):
    """One to three masses, each on a spring to ground and on one yield dashpot (Bingham,
    Coulomb or Herschel-Bulkley) to ground, under a load, springs between them; at rest."""
    n = draw(st.integers(1, 3))
    nodes = [Mass(f"m{i}", m=draw(_decade(0.01, 100.0)), x0=draw(_value(-1.0, 1.0)))
             for i in range(n)]
    elements = []
    for i, nd in enumerate(nodes):
        name = draw(st.sampled_from(("bingham", "coulomb", "herschel_bulkley")))
        ends = ("ground", nd.name) if draw(st.booleans()) else (nd.name, "ground")
        elements += [Element(f"d{i}", _law(draw, name, 0.0), *ends),
                     Element(f"s{i}", _law(draw, "linear_spring", nd.x0), "ground", nd.name)]
        if i and draw(st.booleans()):
            elements.append(Element(f"k{i}", _law(draw, "linear_spring", 0.0),
                                    nodes[i - 1].name, nd.name))
    forces = {nd.name: draw(_value(-5.0, 5.0)) for nd in nodes if draw(st.booleans())}
    return Scene(nodes, elements, forces)


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(_slipping_oscillators(), _decade(1e-3, 1e3))
def test_dashpots_slipping_from_rest_take_the_limit_systems_edge(scene, time_scale):
    """Each yield dashpot alone on its mass: held by it (its law admits the balance's force
    at rest) or slipping, with the edge of its set at rest nearest that force (the float
    in the set next to one outside), on which the rate of the limit step
    ``eps (a_b - a_a)`` slips the way the force resists (``F q > 0``, energy
    dissipated); all without Newton."""
    v, F, stats = consistent_initial_state(scene, time_scale=time_scale)
    assert stats["newton_iterations"] == 0 and v == [0.0] * len(scene.nodes)
    eps = 1e-20 * time_scale
    net = scene.net_forces(0.0, F)
    acc = [net[i] / nd.m for i, nd in enumerate(scene.nodes)]
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot":
            continue
        kernel = el.law.kernel
        assert kernel(0.0, F[e])[0] == 0.0  # on its set at rest
        a, b = scene.elem_a[e], scene.elem_b[e]
        q = eps * ((acc[b] if b >= 0 else 0.0) - (acc[a] if a >= 0 else 0.0))
        slips = kernel(0.0, math.nextafter(F[e], math.copysign(math.inf, F[e])))[0] != 0.0
        if abs(net[b if b >= 0 else a]) > 1e-9 * (abs(F[e]) + 1.0):  # it moves its mass
            event("slips")
            assert slips and F[e] != 0.0 and F[e] * q > 0.0, (F[e], q)
        else:
            event("held")
