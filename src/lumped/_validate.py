"""Argument checks shared by every public entry point.

Each check raises a ``ValueError`` (or ``TypeError``) whose message names the
argument and quotes the offending value, e.g. ``"`dt` must be positive, got -0.1"``.
"""

from __future__ import annotations

import math
from numbers import Real

__all__ = ["as_finite", "as_positive", "as_nonnegative", "as_int_at_least"]


def as_finite(name: str, value: object) -> float:
    """Return ``value`` as a Python float, refusing non-numbers, NaN and infinities."""
    if type(value) is float:  # the common case, without the abstract-class check
        if not math.isfinite(value):
            raise ValueError(f"`{name}` must be finite, got {value!r}")
        return value
    if isinstance(value, bool) or not isinstance(value, Real):
        try:
            import numpy as np  # local: only reached on the slow path

            if isinstance(value, np.generic) and np.isrealobj(value):
                value = value.item()
            else:
                raise TypeError
        except TypeError:
            raise TypeError(
                f"`{name}` must be a real number, got {value!r} of type {type(value).__name__}"
            ) from None
    x = float(value)  # type: ignore[arg-type]
    if not math.isfinite(x):
        raise ValueError(f"`{name}` must be finite, got {x!r}")
    return x


def as_positive(name: str, value: object) -> float:
    """Return ``value`` as a finite float that is strictly positive."""
    x = as_finite(name, value)
    if not x > 0.0:
        raise ValueError(f"`{name}` must be positive, got {x!r}")
    return x


def as_nonnegative(name: str, value: object) -> float:
    """Return ``value`` as a finite float that is zero or positive."""
    x = as_finite(name, value)
    if x < 0.0:
        raise ValueError(f"`{name}` must be non-negative, got {x!r}")
    return x


def as_int_at_least(name: str, value: object, lower: int) -> int:
    """Return ``value`` as an int no smaller than ``lower``."""
    if isinstance(value, bool) or not isinstance(value, int):
        raise TypeError(f"`{name}` must be an integer, got {value!r}")
    if value < lower:
        raise ValueError(f"`{name}` must be at least {lower}, got {value!r}")
    return value
