r"""The class key of a bound law's numbers, in plain Python floats.

A law is derived once per *class* of its numbers (:mod:`lumped.codegen.parametric`).
The class fixes each parameter's sign, the order sympy gives the floats ``+-v_j`` and the
law's own constants (:func:`_constants`; by value, and by their binary digits: that order
decides the order of the terms of a sum in the generated code). :func:`class_key` reads
that order without making a sympy number (:func:`float_content` is sympy's content of a
float, from ``float.as_integer_ratio``), and :func:`sympy_float` makes the sympy float a
swap needs from that content, about ten times cheaper than ``sympy.Float``.
"""

from __future__ import annotations

import math

import sympy as sp

from .rewrite import exponent_symbols

__all__ = ["admitted", "class_key", "constant_magnitudes", "float_content", "numbers_key",
           "parameter_floats", "sympy_float"]

_ADMITTED: dict[object, bool] = {}
_LAW_CONSTANTS: dict[object, tuple] = {}


def admitted(law) -> bool:
    """Whether every comparison ``law``'s residual makes of numbers alone (an argument of
    ``Min``, ``Max``, ``Abs``, ``sign``, ``Heaviside`` or of a relation without ``q`` and
    ``F``) is of a number or ``+-`` a lone parameter, which the class's order of floats
    decides (see the module notes)."""
    hit = _ADMITTED.get(law)
    if hit is None:
        hit = _ADMITTED[law] = _lone_comparisons(law)
    return hit


_COMPARISONS = (sp.Min, sp.Max, sp.Abs, sp.sign, sp.Heaviside, sp.core.relational.Relational)


def _lone_comparisons(law) -> bool:
    params = set(law.symbols.values())
    for node in sp.preorder_traversal(law.residual):
        if not isinstance(node, _COMPARISONS):
            continue
        for arg in node.args:
            if arg.has(law.q, law.F) or arg.is_Number:
                continue
            if (-arg if arg.could_extract_minus_sign() else arg) not in params:
                return False
    return True


def _special(value: float, exponent: bool) -> bool:
    """A value sympy or the printer takes apart from the rest of its sign class: zero
    (its terms dropped), and in an ``exponent`` an integral value (a product, or no
    power) or ``+-1/2`` (a square root); or not finite. Derived from scratch. Elsewhere
    an integral value or ``1/2`` is a float like any other
    (:func:`~lumped.codegen.rewrite.constant_of`)."""
    if not math.isfinite(value) or value == 0.0:
        return True
    return exponent and (float(value).is_integer() or abs(value) == 0.5)


_EXPONENTS: dict[object, tuple[bool, ...]] = {}


def _exponent_flags(law) -> tuple[bool, ...]:
    """Whether each of ``law``'s parameters appears in the exponent of a power of its
    residual (once per law)."""
    hit = _EXPONENTS.get(law)
    if hit is None:
        exponents = exponent_symbols(law.residual)
        hit = _EXPONENTS[law] = tuple(law.symbols[p] in exponents for p in law.parameters)
    return hit


def _constants(law) -> tuple[sp.Float, ...]:
    """The law's constants its class orders the parameters against: its non-integral
    numbers, and every number a comparison of numbers alone reads (``k > 1``: an integer
    there decides a branch of the code by the parameter's value, so ``k = 1.3`` and
    ``k = 0.7`` are two classes)."""
    hit = _LAW_CONSTANTS.get(law)
    if hit is None:
        numbers = {c for c in law.residual.atoms(sp.Number) if not c.is_Integer}
        for node in sp.preorder_traversal(law.residual):
            if isinstance(node, _COMPARISONS):
                numbers |= {a for a in node.args
                            if a.is_Number and not a.has(law.q, law.F)}
        hit = _LAW_CONSTANTS[law] = tuple(sp.Float(c) for c in sorted(numbers, key=float))
    return hit


_CONSTANT_KEYS: dict[object, tuple[list, list]] = {}


def _constant_keys(law) -> tuple[list, list]:
    """The law's constants (:func:`_constants`) by value and by sympy's order (once)."""
    hit = _CONSTANT_KEYS.get(law)
    if hit is None:
        consts = _constants(law)
        hit = _CONSTANT_KEYS[law] = ([float(c) for c in consts],
                                     [c._hashable_content() for c in consts])
    return hit


def constant_magnitudes(law) -> set[float]:
    """The magnitudes of ``law``'s constants (:func:`_constants`: a parameter equal to one
    is tied to it in the class key)."""
    return {abs(c) for c in _constant_keys(law)[0]}


def float_content(x: float) -> tuple:
    """``sympy.Float(x)._hashable_content()`` of a finite nonzero float ``x``, in plain
    Python: ``((sign, man, exp, bc), 53)``, ``|x| = man 2^exp`` with ``man`` odd of ``bc``
    bits (mpmath's normal form at the 53 bits of a double), what sympy orders its floats
    by (:func:`class_key`)."""
    n, d = abs(x).as_integer_ratio()  # d a power of 2
    tz = (n & -n).bit_length() - 1
    man = n >> tz
    return (int(x < 0.0), man, tz - (d.bit_length() - 1), man.bit_length()), 53


def numbers_key(law, values: tuple[float, ...]) -> tuple | None:
    """:func:`class_key` of ``law`` bound to ``values``, in plain floats (no sympy)."""
    if not admitted(law) or any(map(_special, values, _exponent_flags(law))):
        return None
    pm, contents = [], []
    for v in values:  # (the content of -v is that of v with the other sign)
        mpf, prec = float_content(v)
        pm += (v, -v)
        contents += ((mpf, prec), ((1 - mpf[0],) + mpf[1:], prec))
    by_value, by_sympy = _constant_keys(law)
    return (law, tuple(math.copysign(1.0, v) for v in values), _dense_ranks(pm + by_value),
            _dense_ranks(contents + by_sympy))


def sympy_float(x: float) -> sp.Float:
    """``sympy.Float(x)`` of a finite nonzero float ``x``, made from its content
    (:func:`float_content`) without sympy's parsing of the number (about 10 times
    faster; the same object content)."""
    mpf, prec = float_content(x)
    return _FLOAT._new(mpf, prec, zero=False)


_FLOAT = sp.Float


def parameter_floats(values: tuple[float, ...]) -> list:
    """The sympy floats ``+v_j, -v_j`` of the parameters' ``values``, in the key's order
    (finite and nonzero: :func:`_special` values have no class)."""
    return [sympy_float(s * v) for v in values for s in (1.0, -1.0)]


def class_key(bound) -> tuple | None:
    """The class of a bound law's numbers, ``None`` when it is derived from scratch.

    ``(law, signs, order by value, order by sympy)`` of the floats ``+-v_j`` and the
    law's non-integral constants, equal floats in one place; ``None`` for a law not
    :func:`admitted`, a value :func:`_special`, or a law not given as a sympy residual.
    """
    law = getattr(bound, "law", None)
    if law is None or not isinstance(getattr(law, "residual", None), sp.Expr):
        return None
    params = bound.params
    return numbers_key(law, tuple(params[p] for p in law.parameters))


def _dense_ranks(keys: list) -> tuple[int, ...]:
    """Each key's place among the distinct keys (equal keys share a place)."""
    if len(keys) == 2:  # (one parameter, no constant: the common case)
        a, b = keys
        return (0, 0) if a == b else (0, 1) if a < b else (1, 0)
    order = {k: r for r, k in enumerate(sorted(set(keys)))}
    return tuple(order[k] for k in keys)
