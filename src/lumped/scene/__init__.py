"""Scenes: nodes (masses, junctions), elements, forcing (:mod:`.network`, :mod:`.forcing`)."""

from .forcing import SineBurst, paper_F1, paper_F2, zero_forcing
from .network import GROUND, Element, Junction, Mass, Scene, as_forcing

__all__ = [
    "GROUND",
    "Element",
    "Junction",
    "Mass",
    "Scene",
    "SineBurst",
    "as_forcing",
    "paper_F1",
    "paper_F2",
    "zero_forcing",
]
