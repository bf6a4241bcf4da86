"""Element laws: implicit constitutive relations ``R(q, F; params) = 0``.

:mod:`.element_law` holds :class:`ElementLaw` and :class:`BoundLaw`, :mod:`.catalogue`
the built-in laws (:func:`get_law`, :data:`BUILTIN_LAWS`) and :mod:`.parser` the safe
parser for user-written residuals.
"""

from .catalogue import (
    BUILTIN_LAWS,
    bingham,
    coulomb,
    get_law,
    herschel_bulkley,
    implicit_spring,
    linear_spring,
    newtonian,
    s_shaped,
    s_shaped_point,
    s_shaped_turning_points,
    string_spring,
)
from .element_law import KINDS, BoundLaw, ElementLaw
from .parser import parse_expression

__all__ = [
    "BUILTIN_LAWS",
    "KINDS",
    "BoundLaw",
    "ElementLaw",
    "bingham",
    "coulomb",
    "get_law",
    "herschel_bulkley",
    "implicit_spring",
    "linear_spring",
    "newtonian",
    "parse_expression",
    "s_shaped",
    "s_shaped_point",
    "s_shaped_turning_points",
    "string_spring",
]
