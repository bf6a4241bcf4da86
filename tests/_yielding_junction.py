"""A junction's Herschel-Bulkley dashpot at exactly its yield force, slipping at ``1e-9``
under a loaded mass hung on it by a stuck Bingham dashpot: the draw of seed 22228 of the
property of both loops (issue 29), shared by its tests."""

from __future__ import annotations

from lumped.laws import get_law
from lumped.scene import Element, Junction, Mass, Scene

TAU = 0.31622776601683794


def yielding_junction() -> Scene:
    """The scene (junctions ``j0, j1, j3``, mass ``m2`` under the load ``2 + tau``)."""
    def law(name, **values):
        return get_law(name).bind(**values)

    return Scene(
        [Junction("j0"), Junction("j1"), Mass("m2", m=1.0, v0=1e-9), Junction("j3")],
        [Element("e0", law("newtonian", c=1.0), "ground", "j0"),
         Element("e1", law("herschel_bulkley", gamma=1.0, tau=TAU, n=0.3), "ground", "j1"),
         Element("e2", law("bingham", gamma=1.0, tau=1.0), "j1", "m2"),
         Element("e3", law("newtonian", c=1.0), "j1", "j3"),
         Element("e4", law("linear_spring", k=1.0), "ground", "j0"),
         Element("e5", law("linear_spring", k=1.0), "j0", "j3")],
        {"m2": 2.0 + TAU})
