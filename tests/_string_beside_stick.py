"""Seed 25049's scene (the tight property of ``radau5``): a heavy mass on a short taut
string beside a Bingham dashpot that sticks, the string's tension far from 0 at the
stick. The guessed mode (the dashpot stuck, the string taut) was refused by its probe,
which held the string in positions' form: the string's length, off by ``5e-18`` (below
``ulp(x)``), became a rate of ``ulp(x) / h_p`` and forces of ``m ulp(x) / h_p^2``, and
Newton did not converge; the full search read the string slack at its length (to
round-off, over a probe of ``7e-11`` s), and 2e-9 s later it went taut again: 10 000
events, ``TOO_MANY_EVENTS`` after 35 s."""

from __future__ import annotations

from lumped.laws import get_law
from lumped.scene import Element, Mass, Scene

__all__ = ["string_beside_stick", "string_thrown"]


def string_beside_stick() -> Scene:
    """The scene (three masses, two linear springs, an implicit spring, a Bingham dashpot
    ``e3`` and two strings; no forcing), as the property drew it."""
    law = get_law
    return Scene(
        [Mass("m0", 0.9076640662518887, x0=0.9054775189561624, v0=1e-10),
         Mass("m1", 0.16489423883930157, x0=0.03, v0=-0.00916166238600491),
         Mass("m2", 5.6968598529086565, x0=0.0, v0=0.5)],
        [Element("e0", law("implicit_spring").bind(k=33.17111795970351,
                                                   L0=0.009571799028834437,
                                                   F0=4.538401020596991), "ground", "m0"),
         Element("e1", law("linear_spring").bind(k=1.0000000002302585), "ground", "m1"),
         Element("e2", law("linear_spring").bind(k=74.96107729786324), "m0", "m2"),
         Element("e3", law("bingham").bind(gamma=0.5676474059484036,
                                           tau=0.9999999999976974), "m2", "m1"),
         Element("e4", law("string_spring").bind(k=1.0, L=1.0), "m1", "m2"),
         Element("e5", law("string_spring").bind(k=4.993805194394897,
                                                 L=0.005249326026062739), "m0", "m2")])


def string_thrown() -> Scene:
    """A mass thrown from another on a string (taut twice by impacts, then slack), a
    Bingham dashpot to ground that reverses: a run whose mode guesses hold a taut string,
    in the compiled loop (no locks in parallel)."""
    return Scene([Mass("m0", 1.0, x0=0.0), Mass("m1", 2.0, x0=0.3, v0=1.0)],
                 [Element("s", get_law("linear_spring").bind(k=10.0), "ground", "m0"),
                  Element("r", get_law("string_spring").bind(k=1.0, L=0.35), "m0", "m1"),
                  Element("d", get_law("bingham").bind(gamma=1.0, tau=0.5), "ground", "m1")])
