r"""The exact reference's problem statement: its parameters, input checks, the
phases (:class:`Interval`) and events (:class:`Event`) it reports, and its errors.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import numpy as np

from .._validate import as_finite, as_nonnegative, as_positive
from ..scene.forcing import SineBurst, zero_forcing
from ..solvers.closed.closed_form import BinghamOscillator

__all__ = ['Event', 'Interval', 'ReferenceNotApplicable', 'TooManyEvents']


class ReferenceNotApplicable(ValueError):
    """The exact reference does not cover this problem (e.g. another kind of forcing)."""


class TooManyEvents(RuntimeError):
    """More stick/slip events than ``max_events``: a Zeno-like accumulation or a runaway."""


@dataclass(frozen=True)
class Interval:
    """One phase of the exact solution on ``[t_start, t_end]``.

    Attributes
    ----------
    t_start, t_end : float
        The phase's time span.
    phase : {"stick", "slip"}
        ``"stick"``: ``v = 0`` and ``|F_d| <= tau``; ``"slip"``: the linear ODE above.
    direction : int
        ``s = sgn(v)`` during a slip (``+1`` or ``-1``; ``0`` when ``tau = 0``, where
        the direction does not enter the equations), ``0`` while stuck.
    x_start, v_start : float
        State at ``t_start``.
    forced : bool
        Whether the sine forcing is on during the interval.
    """

    t_start: float
    t_end: float
    phase: Literal["stick", "slip"]
    direction: int
    x_start: float
    v_start: float
    forced: bool


@dataclass(frozen=True)
class Event:
    """A change of phase (or a forcing breakpoint) at time ``t`` and position ``x``.

    ``kind`` is one of ``"stick"`` (slip -> stick, ``v = 0``), ``"reversal"`` (``v``
    passes through zero and the slip continues the other way), ``"breakout"``
    (stick -> slip), ``"forcing-off"`` (the sine burst is switched off), or
    ``"continue"`` (``v`` touches zero and the slip continues the same way).
    """

    t: float
    kind: Literal["stick", "reversal", "breakout", "forcing-off", "continue"]
    x: float
    v: float


@dataclass(frozen=True)
class Params:
    m: float
    k: float
    c: float  # 1 / gamma, 0 for Coulomb
    tau: float
    A: float
    w: float
    t_off: float

    def force(self, t: float, forced: bool) -> float:
        return self.A * math.sin(self.w * t) if forced else 0.0

    def dforce(self, t: float, forced: bool) -> float:
        return self.A * self.w * math.cos(self.w * t) if forced else 0.0

    def forced_at(self, t: float) -> bool:
        """Whether the forcing is on just *after* ``t`` (the dynamics' point of view)."""
        return self.A != 0.0 and self.w != 0.0 and t < self.t_off


# ----------------------------------------------------------------------------------------------
# input checking


def params_from(osc, m, k, gamma, tau, coulomb, forcing) -> Params:
    if not isinstance(coulomb, bool):
        raise TypeError(f"`coulomb` must be True or False, got {coulomb!r}")
    given = {"m": m, "k": k, "gamma": gamma, "tau": tau}
    if osc is not None:
        if not isinstance(osc, BinghamOscillator):
            raise TypeError(f"`osc` must be a BinghamOscillator, got {type(osc).__name__}")
        extra = [name for name, val in given.items() if val is not None]
        if extra:
            raise ValueError(f"give either `osc` or the keywords m, k, gamma, tau, not both "
                             f"(got `osc` and {', '.join(extra)})")
        m, k, gamma, tau = osc.m, osc.k, osc.gamma, osc.tau
    else:
        missing = [name for name, val in given.items()
                   if val is None and not (name == "gamma" and coulomb)]
        if missing:
            raise ValueError(f"missing parameter(s) {', '.join(missing)} (or pass `osc`)")
        m = as_positive("m", m)
        k = as_positive("k", k)
        tau = as_nonnegative("tau", tau)
        if gamma is not None:
            gamma = as_positive("gamma", gamma)
    c = 0.0 if coulomb else 1.0 / gamma
    if forcing is None or forcing is zero_forcing:
        A, w, t_off = 0.0, 0.0, math.inf
    elif isinstance(forcing, SineBurst):
        A = as_finite("forcing.amplitude", forcing.amplitude)
        w = as_finite("forcing.omega", forcing.omega)
        t_off = float(forcing.t_off)
    else:
        raise ReferenceNotApplicable(
            "the exact reference covers only forcing=None, lumped.scene.zero_forcing or a "
            f"lumped.scene.SineBurst, got `forcing` = {forcing!r}"
        )
    return Params(m=m, k=k, c=c, tau=tau, A=A, w=w, t_off=t_off)


def as_times(t, name: str) -> np.ndarray:
    try:
        arr = np.asarray(t, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"`{name}` must be an array of real times, got {t!r}") from None
    if arr.ndim != 1 or arr.size == 0:
        raise ValueError(f"`{name}` must be a non-empty 1-D array of times, got shape {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = float(arr[~np.isfinite(arr)][0])
        raise ValueError(f"`{name}` must be finite, got {bad!r}")
    if arr[0] < 0.0:
        raise ValueError(f"`{name}` must be non-negative, got {float(arr[0])!r}")
    if arr.size > 1 and np.any(np.diff(arr) < 0.0):
        i = int(np.flatnonzero(np.diff(arr) < 0.0)[0])
        raise ValueError(f"`{name}` must be non-decreasing, got {float(arr[i])!r} "
                         f"before {float(arr[i + 1])!r}")
    return arr
