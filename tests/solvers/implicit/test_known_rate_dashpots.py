"""The dashpots whose rate at ``t = 0`` the masses give, read once per scene (a run with
new numbers asks four times: the initial state's two settlings, the start's rates, the
slip bounds) and again whenever the scene's nodes, elements or supports are replaced."""

from __future__ import annotations

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene, network
from lumped.solvers.implicit.initial_slip import known_rate_dashpots


def _scene() -> Scene:
    return Scene([Mass("a", m=1.0), Mass("b", m=2.0, x0=0.1)],
                 [Element("s", get_law("linear_spring").bind(k=3.0), "ground", "a"),
                  Element("d", get_law("bingham").bind(gamma=0.5, tau=0.2), "a", "b"),
                  Element("g", get_law("bingham").bind(gamma=0.7, tau=0.3), "ground", "b")])


def test_read_once_per_scene(monkeypatch):
    scene = _scene()
    reads = []
    kind = network.Element.kind
    monkeypatch.setattr(network.Element, "kind",
                        property(lambda el: reads.append(el.name) or kind.fget(el)))
    assert known_rate_dashpots(scene, [0, 1, 2]) == [1, 2]
    assert known_rate_dashpots(scene, [2, 0]) == [2]
    assert known_rate_dashpots(scene, [0]) == []
    assert known_rate_dashpots(scene, []) == []
    assert sorted(reads) == ["d", "g", "s"]  # each element's kind once, for every call


def test_read_again_when_the_scene_changes():
    """Never a stale answer: a node made a junction, elements replaced."""
    scene = _scene()
    assert known_rate_dashpots(scene, [0, 1, 2]) == [1, 2]
    scene.nodes = (scene.nodes[0], Junction("b", x0=0.1))  # b's velocity is now unknown
    assert known_rate_dashpots(scene, [0, 1, 2]) == []
    scene.nodes = _scene().nodes
    scene.elements = (scene.elements[1], scene.elements[0], scene.elements[2])
    assert known_rate_dashpots(scene, [0, 1, 2]) == [0, 2]
