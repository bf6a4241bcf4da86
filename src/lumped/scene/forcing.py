"""External forcing F(t) for the paper's scenarios and the exact reference.

Every forcing is a plain callable ``F(t: float) -> float`` evaluated on Python
floats, so it can sit inside a hot step loop. Positive ``F`` pushes the mass
towards positive ``x``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from .._validate import as_finite, as_nonnegative

__all__ = ["SineBurst", "zero_forcing", "paper_F1", "paper_F2", "jumps"]


@dataclass(frozen=True)
class SineBurst:
    r"""Sinusoid switched off at ``t_off``.

    .. math::  F(t) = A \sin(\omega t) \text{ for } 0 \le t \le t_{off}, \qquad 0 \text{ after.}

    ``t_off = math.inf`` is allowed and means "never switched off".

    Examples
    --------
    >>> F = SineBurst(amplitude=0.5, omega=5 * math.pi, t_off=1.0)   # the paper's F1
    >>> F(0.1), F(2.0)
    (0.5, 0.0)
    """

    amplitude: float
    omega: float
    t_off: float = math.inf

    def __post_init__(self) -> None:
        as_finite("amplitude", self.amplitude)
        as_finite("omega", self.omega)
        if not (isinstance(self.t_off, (int, float)) and self.t_off == math.inf):
            as_nonnegative("t_off", self.t_off)

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        """Times in ``(t0, t1)`` where ``F`` is not smooth: ``[t_off]`` if it lies there.

        An adaptive method steps exactly to them (a time event)."""
        return [self.t_off] if t0 < self.t_off < t1 else []

    def __call__(self, t: float) -> float:
        if t > self.t_off:
            return 0.0
        return self.amplitude * math.sin(self.omega * t)


def jumps(fn: object, t0: float, t1: float) -> list[float]:
    """The breakpoints of the forcing ``fn`` in ``(t0, t1)`` at which it may jump: those
    of its ``breakpoints(t0, t1)`` that its ``kinks(t0, t1)`` (the points where it is
    continuous) does not list; all of them for a forcing without ``kinks``."""
    get = getattr(fn, "breakpoints", None)
    if get is None:
        return []
    points = list(get(t0, t1))
    get_kinks = getattr(fn, "kinks", None)
    if get_kinks is None:
        return points
    continuous = set(get_kinks(t0, t1))
    return [b for b in points if b not in continuous]


def zero_forcing(t: float) -> float:
    """No external force: ``F(t) = 0``."""
    return 0.0


#: Eq. (17a): ``0.5 sin(5 pi t)`` on ``[0, 1]``, zero after (stays below ``mu_s N_f = 1``).
paper_F1 = SineBurst(amplitude=0.5, omega=5.0 * math.pi, t_off=1.0)
#: Eq. (17b): ``10 sin(5 pi t)`` on ``[0, 1]``, zero after (exceeds ``mu_s N_f = 1``).
paper_F2 = SineBurst(amplitude=10.0, omega=5.0 * math.pi, t_off=1.0)
