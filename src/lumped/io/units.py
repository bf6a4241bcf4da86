r"""Units of tabulated inputs: what each quantity may be measured in, and its SI factor.

A table holds one of four quantities; its values are converted to SI on reading,

.. math::  y_{SI} = \text{factor} \times s_{\text{unit}} \times y_{\text{file}},

with ``s_unit`` the SI value of one unit (below). ``factor`` is the user's own scale
(OpenSees' ``-factor``), e.g. to scale a record to a target peak.

==============  ===========  ======================================================
quantity        SI unit      units known (SI value of one unit)
==============  ===========  ======================================================
acceleration    m/s^2        ``g`` (9.80665, standard gravity), ``m/s^2``,
                             ``cm/s^2`` and ``gal`` (0.01), ``mm/s^2`` (0.001)
velocity        m/s          ``m/s``, ``cm/s`` (0.01), ``mm/s`` (0.001)
displacement    m            ``m``, ``cm`` (0.01), ``mm`` (0.001)
force           N            ``N``, ``kN`` (1000)
==============  ===========  ======================================================

Names are matched exactly (``mm`` is not ``Mm``), after removing surrounding blanks;
``m/s2`` and ``m/s**2`` are read as ``m/s^2`` (likewise for ``cm`` and ``mm``) and
``Gal`` as ``gal``.

Examples
--------
>>> unit_scale("g", "acceleration")
9.80665
>>> unit_scale("cm/s2", "acceleration")
0.01
>>> unit_scale("kN", "force")
1000.0
"""

from __future__ import annotations

__all__ = ["G", "QUANTITIES", "SI_UNITS", "UNITS", "unit_scale", "check_quantity"]

#: Standard gravity (m/s^2), the SI value of the unit ``g``.
G = 9.80665

#: The quantities a table may hold.
QUANTITIES = ("force", "acceleration", "velocity", "displacement")

#: The SI unit of each quantity (a table's values after conversion).
SI_UNITS = {"force": "N", "acceleration": "m/s^2", "velocity": "m/s", "displacement": "m"}

#: Unit name -> (quantity, SI value of one unit).
UNITS: dict[str, tuple[str, float]] = {
    "g": ("acceleration", G),
    "m/s^2": ("acceleration", 1.0),
    "cm/s^2": ("acceleration", 0.01),
    "gal": ("acceleration", 0.01),
    "mm/s^2": ("acceleration", 0.001),
    "m/s": ("velocity", 1.0),
    "cm/s": ("velocity", 0.01),
    "mm/s": ("velocity", 0.001),
    "m": ("displacement", 1.0),
    "cm": ("displacement", 0.01),
    "mm": ("displacement", 0.001),
    "N": ("force", 1.0),
    "kN": ("force", 1000.0),
}

_ALIASES = {"Gal": "gal"}
for _p in ("m", "cm", "mm"):
    _ALIASES[f"{_p}/s2"] = _ALIASES[f"{_p}/s**2"] = f"{_p}/s^2"


def check_quantity(quantity: object) -> str:
    """Return ``quantity`` if it is one of :data:`QUANTITIES`, else raise.

    Raises
    ------
    TypeError
        If ``quantity`` is not a str.
    ValueError
        If it is not a known quantity (the message lists them).
    """
    if not isinstance(quantity, str):
        raise TypeError(f"`quantity` must be a str, one of {QUANTITIES}, got {quantity!r}")
    if quantity not in QUANTITIES:
        raise ValueError(f"`quantity` must be one of {', '.join(QUANTITIES)}, got {quantity!r}")
    return quantity


def unit_scale(unit: str | None, quantity: str) -> float:
    """The SI value of one ``unit`` of ``quantity`` (``1.0`` for ``unit=None``: SI already).

    Parameters
    ----------
    unit : str or None
        A name from :data:`UNITS` (or an alias, see the module notes).
    quantity : str
        One of :data:`QUANTITIES`.

    Raises
    ------
    ValueError
        For a unit nobody knows (the message names it and lists the known ones), or one
        of another quantity (``units='cm'`` for an acceleration).
    TypeError
        If ``unit`` is neither a str nor None.
    """
    check_quantity(quantity)
    if unit is None:
        return 1.0
    if not isinstance(unit, str):
        raise TypeError(f"`units` must be a str or None, got {unit!r}")
    name = _ALIASES.get(unit.strip(), unit.strip())
    if name not in UNITS:
        raise ValueError(f"`units`: unknown unit {unit!r}; known units: {', '.join(UNITS)}")
    kind, scale = UNITS[name]
    if kind != quantity:
        fits = [u for u, (q, _) in UNITS.items() if q == quantity]
        raise ValueError(f"`units` {unit!r} is a unit of {kind}, not of {quantity} "
                         f"(units of {quantity}: {', '.join(fits)})")
    return scale
