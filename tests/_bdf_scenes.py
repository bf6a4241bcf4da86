"""Scenes drawn by the random-network property suite that more than one regression file
of the fixed-step methods runs (tests/solvers/test_network_bdf_regressions*.py), each
written out as drawn."""

from __future__ import annotations

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene


def second_string_taut_within_the_step() -> Scene:
    """Drawn by the suite (session 5, as drawn): ``m1`` is tied to ground by string ``e1``
    and to ``m0`` by string ``e3`` with a Bingham dashpot ``e4`` (yield force 1) beside
    it; both masses move up."""
    return Scene(
        [Mass("m0", m=4.830543029274959, x0=0.1474191018521529, v0=1.772995387291422),
         Mass("m1", m=1.0, x0=-0.07879501088661, v0=0.9759256919748283)],
        [Element("e0", get_law("herschel_bulkley").bind(gamma=0.36123619139126,
                                                        tau=0.05033160533669336, n=0.5),
                 "ground", "m0"),
         Element("e1", get_law("string_spring").bind(k=1.010966804136899,
                                                     L=0.04194877103520564), "ground", "m1"),
         Element("e2", get_law("string_spring").bind(k=2.2034416293088865, L=1.0), "m0", "m1"),
         Element("e3", get_law("string_spring").bind(k=1.0, L=0.23621411273876292),
                 "m1", "m0"),
         Element("e4", get_law("bingham").bind(gamma=0.11275906247594833, tau=1.0),
                 "m1", "m0")])


def creeping_pair_on_a_string() -> Scene:
    """Drawn by the suite (session 6, as drawn): ``m0`` and ``m1`` joined by a
    Herschel-Bulkley dashpot ``e1`` (``n = 0.5``, yield force 0.011) and a string ``e2``
    (``L = 0.0268``) in parallel; ``m1`` hangs on a stiff string ``e3`` to ground."""
    return Scene(
        [Mass("m0", m=2.945419949336432, x0=8.866785507495781e-141, v0=0.7210209576693374),
         Mass("m1", m=0.9715625632515835, x0=-0.025553999064556132, v0=-0.9267147053332196)],
        [Element("e0", get_law("newtonian").bind(c=0.026329964176047806), "ground", "m0"),
         Element("e1", get_law("herschel_bulkley").bind(gamma=0.15585846863008437,
                                                        tau=0.011042871848402393, n=0.5),
                 "m0", "m1"),
         Element("e2", get_law("string_spring").bind(k=5.117433925866938,
                                                     L=0.026777554952301115), "m1", "m0"),
         Element("e3", get_law("string_spring").bind(k=98.15927843579738,
                                                     L=0.06113590223120681), "ground", "m1")])
