"""The inertial force of a mass on a moving ground, merged with its applied forcing.

In the frame of the ground (:mod:`lumped.scene.ground`) each mass ``i`` is pushed by
``-m_i a_g(t)`` besides its applied force ``f_i(t)`` (positive towards ``+x``). The sum
is one forcing callable: a :class:`~lumped.scene.SineBurst` or a constant where both
parts are (so compiled loops and the closed form take it exactly), else a sum that keeps
the ``breakpoints(t0, t1)`` of its parts (time events of ``radau5``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

from .forcing import SineBurst, jumps

if TYPE_CHECKING:
    from .ground import GroundMotion

__all__ = ["inertial_forcing", "combine_forcing", "SumForcing"]


class _Scaled:
    """``scale * fn(t)``, keeping ``fn``'s breakpoints."""

    __slots__ = ("fn", "scale")

    def __init__(self, fn: Callable[[float], float], scale: float) -> None:
        self.fn, self.scale = fn, scale

    def __call__(self, t: float) -> float:
        return self.scale * self.fn(t)

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        get = getattr(self.fn, "breakpoints", None)
        return list(get(t0, t1)) if get is not None else []

    def kinks(self, t0: float, t1: float) -> list[float]:
        get = getattr(self.fn, "kinks", None)
        return list(get(t0, t1)) if get is not None else []

    def interpolant(self) -> tuple | None:
        """The scaled function's ``interpolant()`` with this scale (see
        :func:`lumped.scene.forcing_jit.linear_row`), or ``None``."""
        get = getattr(self.fn, "interpolant", None)
        parts = get() if get is not None else None
        if parts is None or parts[-1] != 1.0:
            return None
        return (*parts[:-1], float(self.scale))

    def __repr__(self) -> str:
        return f"{self.scale!r} * {self.fn!r}"


class SumForcing:
    """``sum_k fn_k(t)`` (added in order, from ``0.0``), with the union of the parts'
    breakpoints."""

    __slots__ = ("parts",)

    def __init__(self, parts: tuple) -> None:
        self.parts = parts

    def __call__(self, t: float) -> float:
        total = 0.0
        for fn in self.parts:
            total += fn(t)
        return total

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        out: set[float] = set()
        for fn in self.parts:
            get = getattr(fn, "breakpoints", None)
            if get is not None:
                out.update(get(t0, t1))
        return sorted(out)

    def kinks(self, t0: float, t1: float) -> list[float]:
        """The breakpoints at which every part is continuous."""
        jumped: set[float] = set()
        for fn in self.parts:
            jumped.update(jumps(fn, t0, t1))
        return [b for b in self.breakpoints(t0, t1) if b not in jumped]

    def __repr__(self) -> str:
        return " + ".join(repr(fn) for fn in self.parts)


def inertial_forcing(m: float, ground: GroundMotion) -> Callable[[float], float]:
    """The inertial force ``-m a_g(t)`` of a mass in the frame of the ground: a
    :class:`SineBurst` or a constant where ``a_g`` is one (so the compiled and closed
    forms take it exactly), else ``-m`` times ``a_g``."""
    from .forcing_spec import ConstantForce

    a = ground.acceleration
    if isinstance(a, SineBurst):
        return SineBurst(amplitude=-m * a.amplitude, omega=a.omega, t_off=a.t_off)
    if type(a) is ConstantForce:
        return ConstantForce(-m * a.value)
    return _Scaled(a, -m)


def combine_forcing(applied: Callable[[float], float] | None,
                    inertial: Callable[[float], float]) -> Callable[[float], float]:
    """``applied + inertial``: merged into one :class:`SineBurst` (same ``omega`` and
    ``t_off``) or one constant where both are, else a sum keeping both breakpoints."""
    from .forcing import zero_forcing
    from .forcing_spec import ConstantForce

    if applied is None or applied is zero_forcing:
        return inertial
    if (isinstance(applied, SineBurst) and isinstance(inertial, SineBurst)
            and applied.omega == inertial.omega and applied.t_off == inertial.t_off):
        return SineBurst(amplitude=applied.amplitude + inertial.amplitude,
                         omega=applied.omega, t_off=applied.t_off)
    if type(applied) is ConstantForce and type(inertial) is ConstantForce:
        return ConstantForce(applied.value + inertial.value)
    return SumForcing((applied, inertial))
