"""The exact, event-driven reference solution of the Bingham oscillator (the yardstick).

:mod:`.model` (problem, phases, events, errors), :mod:`.arcs` (one slip arc in closed
form), :mod:`.events` (the event loop) and :mod:`.solution` (:func:`exact_solution`,
:func:`reference_for_grid`).
"""

from .model import Event, Interval, ReferenceNotApplicable, TooManyEvents
from .solution import ExactSolution, exact_solution, reference_for_grid

__all__ = [
    "Event",
    "ExactSolution",
    "Interval",
    "ReferenceNotApplicable",
    "TooManyEvents",
    "exact_solution",
    "reference_for_grid",
]
