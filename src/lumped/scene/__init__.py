"""Scenes: nodes (masses, junctions), elements, forcing (:mod:`.network`, :mod:`.forcing`),
ground motion (:mod:`.ground`)."""

from .forcing import SineBurst, paper_F1, paper_F2, zero_forcing
from .forcing_spec import as_forcing
from .ground import GroundMotion
from .network import GROUND, Element, Junction, Mass, Scene
from .oscillator import bingham_oscillator

__all__ = [
    "GROUND",
    "Element",
    "GroundMotion",
    "Junction",
    "Mass",
    "Scene",
    "SineBurst",
    "as_forcing",
    "bingham_oscillator",
    "paper_F1",
    "paper_F2",
    "zero_forcing",
]
