r"""Hysteresis loops and steady cycles: how engineers judge a damper, from any Solution.

Sign convention (as in :mod:`lumped.scene`): an element drawn from node ``a`` to node
``b`` has the elongation ``q = x_b - x_a`` (the ground has ``x = 0``), the rate
``qdot = v_b - v_a`` and the force ``F``, positive in tension (``+F`` on ``a``, ``-F`` on
``b``). Whatever the element's kind (a spring's law reads ``q``, a dashpot's reads
``qdot``), its loop is drawn in these three: ``F`` against ``q``, or against ``qdot``.
Several elements joining the same two nodes (in parallel, e.g. the spring and the
friction slider of an isolator) form one loop: ``q`` of the first one's orientation and
the sum of their forces, a reversed element's force counted with ``-1``.

**The work done on the element per cycle.** The power taken from the nodes is ``F qdot``
(:mod:`lumped.post.energy`), so over a cycle ``[t_0, t_0 + T]`` of the forcing

.. math::  E_d = \int_{t_0}^{t_0 + T} F\,\dot q\,dt = \oint F\,dq,

the area of the loop, traversed clockwise in the ``(q, F)`` plane for a dissipative
element (``E_d > 0``). It is the energy the element dissipates per cycle once the
motion is periodic (an elastic element's stored energy returns to its value, so its
loop encloses no area); in the transient it also holds the change of stored energy.
It is computed by the trapezoidal rule in ``q`` on the samples of the cycle, whose ends
are taken from the dense output ``sol.sol(t)`` (or on ``points_per_cycle`` equally
spaced times of the dense output).

**Amplitude, effective stiffness and equivalent viscous damping.** Over a cycle, with
the extremes of the elongation and the force,

.. math::

    u_0 = \tfrac12 (q_{max} - q_{min}), \qquad F_0 = \tfrac12 (F_{max} - F_{min}),
    \qquad k_{eff} = F_0 / u_0,

the amplitude, the force amplitude and the secant stiffness (peak to peak; for a loop
symmetric about the origin ``k_eff = F_max / q_max``). With the strain energy at the
peak ``E_s = k_eff u_0^2 / 2``, the equivalent viscous damping ratio is

.. math::  \zeta_{eq} = \frac{E_d}{4 \pi E_s},

the damping ratio of the linear viscous oscillator of stiffness ``k_eff`` that
dissipates ``E_d`` per cycle at amplitude ``u_0`` in resonance (Chopra, *Dynamics of
Structures*, section 3.9). ``k_eff`` uses the largest force over the cycle, which is
the force at the peak elongation for a spring-and-friction (bilinear) isolator
(``k_eff = k + tau / u_0``), as in ASCE 7 and AASHTO; where a viscous force makes the
peak force lead the peak elongation, ``k_eff`` here is larger (a spring ``k`` in
parallel with a dashpot ``c`` under ``q = u_0 sin(omega t)``:
``k_eff = sqrt(k^2 + (c omega)^2)``). A damper with no stiffness of its own (a lone
dashpot: ``F_0 = c omega u_0``, so ``zeta_eq = 1/2`` whatever ``c``) is judged against
the structure it damps: pass ``stiffness=k``, and ``zeta_eq = E_d / (2 pi k u_0^2)``
(``c omega / (2 k)`` for the dashpot).

**The steady state.** The cycles start at ``t_start`` (the forcing's phase origin,
default 0) and follow each other every period. Cycle ``j`` *agrees* with cycle ``j - 1``
when

.. math::

    |u_{0,j} - u_{0,j-1}| \le rtol\,\max(u_{0,j}, u_{0,j-1}), \qquad
    |E_{d,j} - E_{d,j-1}| \le rtol\,\max(|E_{d,j}|, |E_{d,j-1}|, 10^{-3} W_j),

with ``W_j = 4 F_0 u_0`` the area of the loop's bounding box (so an elastic loop, whose
area is round-off, can agree). The transient ends at the first cycle from which every
later cycle agrees with the one before; those cycles are *steady*, and the report
averages their energy, amplitude, ``k_eff`` and ``zeta_eq``.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from lumped._optional import require
from lumped._validate import as_finite, as_int_at_least, as_positive

from .columns import F_col, displacements, velocities

__all__ = ["Cycle", "CycleReport", "HysteresisLoop", "cycles", "hysteresis"]

_AGAINST = {"elongation": "elongation q = x_b - x_a [m]",
            "rate": "rate dq/dt = v_b - v_a [m/s]"}


@dataclass(frozen=True, eq=False)
class HysteresisLoop:
    """An element's force against its elongation and its rate, sample by sample.

    Attributes
    ----------
    element : str
        The element's name (several in parallel: joined by ``+``).
    t : numpy.ndarray
        Times (s).
    elongation : numpy.ndarray
        ``q = x_b - x_a`` (m).
    rate : numpy.ndarray
        ``qdot = v_b - v_a`` (m/s).
    force : numpy.ndarray
        ``F`` (N), positive in tension.
    """

    element: str
    t: np.ndarray
    elongation: np.ndarray
    rate: np.ndarray
    force: np.ndarray

    def work(self) -> float:
        """``int F dq`` along the loop (J), trapezoidal in ``q``: the energy dissipated
        per cycle for a closed steady loop (see :mod:`lumped.post.loops`)."""
        q, F = self.elongation, self.force
        return float(np.sum(0.5 * (F[1:] + F[:-1]) * np.diff(q)))

    def plot(self, ax=None, *, against: str = "elongation", **kwargs):
        """Draw ``F`` against the elongation (default) or the rate. Needs matplotlib.

        Parameters
        ----------
        ax : matplotlib Axes, optional
            Where to draw; default a new figure.
        against : str
            ``"elongation"`` or ``"rate"``.
        **kwargs
            Passed to ``ax.plot`` (default ``lw=1.0``, ``label=element``).

        Returns
        -------
        matplotlib Axes
        """
        if against not in _AGAINST:
            raise ValueError(f"`against` must be 'elongation' or 'rate', got {against!r}")
        plt = require("matplotlib.pyplot", "HysteresisLoop.plot()")
        if ax is None:
            _, ax = plt.subplots(figsize=(5.0, 4.0), constrained_layout=True)
        kwargs.setdefault("lw", 1.0)
        kwargs.setdefault("label", self.element)
        ax.plot(self.elongation if against == "elongation" else self.rate, self.force,
                **kwargs)
        ax.set_xlabel(_AGAINST[against])
        ax.set_ylabel("force F [N] (tension > 0)")
        ax.grid(True, alpha=0.3)
        return ax

    def __repr__(self) -> str:
        return (f"HysteresisLoop({self.element!r}, {len(self.t)} samples on "
                f"[{self.t[0]:g}, {self.t[-1]:g}] s)")


@dataclass(frozen=True)
class Cycle:
    """One period of the forcing (see :mod:`lumped.post.loops` for the definitions).

    Attributes
    ----------
    index : int
        From 0, the cycle starting at ``t_start``.
    t0, t1 : float
        Its start and end (s).
    energy : float
        ``E_d``, the work done on the element over the cycle (J).
    amplitude, offset : float
        ``u_0 = (q_max - q_min) / 2`` and the centre ``(q_max + q_min) / 2`` (m).
    force_amplitude : float
        ``F_0 = (F_max - F_min) / 2`` (N).
    k_eff : float
        ``F_0 / u_0``, or the ``stiffness`` given (N/m); NaN if ``u_0 = 0``.
    zeta_eq : float
        ``E_d / (4 pi E_s)``, ``E_s = k_eff u_0^2 / 2``; NaN if ``E_s = 0``.
    steady : bool
        In the steady state.
    """

    index: int
    t0: float
    t1: float
    energy: float
    amplitude: float
    offset: float
    force_amplitude: float
    k_eff: float
    zeta_eq: float
    steady: bool


@dataclass(frozen=True)
class CycleReport:
    """The cycles of a run under periodic forcing, and its steady state.

    Attributes
    ----------
    element : str
    period : float
        ``T`` (s).
    cycles : tuple of Cycle
        Every complete cycle in ``[t_start, t_end]``.
    steady_from : int or None
        Index of the first steady cycle; ``None`` if the run ends in the transient.
    energy, amplitude, k_eff, zeta_eq : float or None
        Means over the steady cycles; ``None`` without any.
    """

    element: str
    period: float
    cycles: tuple[Cycle, ...]
    steady_from: int | None
    energy: float | None
    amplitude: float | None
    k_eff: float | None
    zeta_eq: float | None

    @property
    def steady(self) -> tuple[Cycle, ...]:
        """The steady cycles."""
        return tuple(c for c in self.cycles if c.steady)

    def to_dict(self) -> dict[str, np.ndarray]:
        """``{field: array over the cycles}`` (``index``, ``t0``, ... ``steady``)."""
        names = Cycle.__dataclass_fields__
        return {n: np.array([getattr(c, n) for c in self.cycles]) for n in names}

    def __repr__(self) -> str:
        if self.steady_from is None:
            state = "no steady cycle"
        else:
            state = (f"steady from cycle {self.steady_from}: E_d = {self.energy:.6g} J, "
                     f"u_0 = {self.amplitude:.6g} m, zeta_eq = {self.zeta_eq:.4g}")
        return f"CycleReport({self.element!r}, T = {self.period:g} s, " \
               f"{len(self.cycles)} cycles, {state})"


def _element_sign(sol, element: str | Sequence[str]) -> tuple[str, list[tuple[int, float]]]:
    """The elements' indices and signs (``-1`` for one drawn the other way)."""
    scene = sol.scene
    if scene is None:
        raise ValueError("loops need the scene; this Solution was built without one")
    names = [element] if isinstance(element, str) else \
        list(element) if isinstance(element, Sequence) else []
    if not names or not all(isinstance(n, str) for n in names):
        raise TypeError(f"`element` must be an element name or a sequence of them, "
                        f"got {element!r}")
    picked: list[tuple[int, float]] = []
    for name in names:
        if name not in scene.element_index:
            raise ValueError(f"`element`: no element {name!r} in the scene "
                             f"(elements: {', '.join(scene.element_names)})")
        e = scene.element_index[name]
        ends = (scene.elem_a[e], scene.elem_b[e])
        if not picked:
            first = ends
            picked.append((e, 1.0))
        elif ends == first:
            picked.append((e, 1.0))
        elif ends == first[::-1]:
            picked.append((e, -1.0))
        else:
            raise ValueError(f"`element`: {name!r} does not join the same two nodes as "
                             f"{names[0]!r}, so they do not form one loop")
    return "+".join(names), picked


def _window(sol, t0: float | None, t1: float | None, points: int | None) -> np.ndarray:
    """Rows of the run on ``[t0, t1]``: the samples inside, the ends from the dense
    output (or ``points`` equally spaced rows of it)."""
    first, last = float(sol.t[0]), float(sol.t[-1])
    a = first if t0 is None else as_finite("t0", t0)
    b = last if t1 is None else as_finite("t1", t1)
    if not first <= a < b <= last:
        raise ValueError(f"the window [t0, t1] = [{a!r}, {b!r}] must be a non-empty part of "
                         f"the solved interval [{first!r}, {last!r}]")
    if points is not None:
        as_int_at_least("points", points, 2)
        return sol.sol(np.linspace(a, b, points))
    t = sol.t
    inside = sol.data[np.searchsorted(t, a, side="right"):np.searchsorted(t, b, side="left")]
    return np.vstack([sol.sol([a]), inside, sol.sol([b])])


def _loop(sol, name: str, picked, rows: np.ndarray) -> HysteresisLoop:
    scene = sol.scene
    e0 = picked[0][0]
    force = sum(sign * rows[:, F_col(scene, e)] for e, sign in picked)
    return HysteresisLoop(name, rows[:, 0].copy(), displacements(scene, rows, e0),
                          velocities(scene, rows, e0), np.asarray(force, dtype=float))


def hysteresis(sol, element: str | Sequence[str], *, t0: float | None = None,
               t1: float | None = None, points: int | None = None) -> HysteresisLoop:
    """The hysteresis loop of an element (or of elements in parallel) of a run.

    Parameters
    ----------
    sol : Solution
        Any run of :func:`lumped.simulate` (it must carry its scene).
    element : str or sequence of str
        An element's name, or several joining the same two nodes (their forces add).
    t0, t1 : float, optional
        The window, default the whole run; its ends are read from the dense output.
    points : int, optional
        Resample the window at this many equally spaced times of the dense output
        (``sol.sol``) instead of the samples (e.g. for an adaptive run's sparse samples).

    Returns
    -------
    HysteresisLoop

    Examples
    --------
    >>> from lumped import simulate
    >>> from lumped.scene import bingham_oscillator, paper_F2
    >>> sol = simulate(bingham_oscillator(forcing=paper_F2), method="closed-bdf1",
    ...                dt=1e-3, t_end=1.0)
    >>> loop = hysteresis(sol, "dashpot", t0=0.2, t1=0.6)
    >>> loop
    HysteresisLoop('dashpot', 401 samples on [0.2, 0.6] s)
    >>> bool(loop.work() > 0)          # a Bingham dashpot dissipates
    True
    """
    name, picked = _element_sign(sol, element)
    return _loop(sol, name, picked, _window(sol, t0, t1, points))


def cycles(sol, element: str | Sequence[str], *, period: float | None = None,
           omega: float | None = None, t_start: float = 0.0, rtol: float = 1e-2,
           stiffness: float | None = None, points_per_cycle: int | None = None
           ) -> CycleReport:
    """Split a run under periodic forcing into cycles; find and report the steady state.

    Parameters
    ----------
    sol : Solution
    element : str or sequence of str
        As for :func:`hysteresis`.
    period, omega : float
        The forcing's period ``T`` (s) or circular frequency ``omega = 2 pi / T``
        (rad/s): exactly one.
    t_start : float
        Where the first cycle starts (the forcing's phase origin).
    rtol : float
        The relative agreement of consecutive steady cycles (see the module notes).
    stiffness : float, optional
        Use this ``k_eff`` (N/m, e.g. the structure's stiffness for a damper with none
        of its own) instead of the loop's secant stiffness ``F_0 / u_0``.
    points_per_cycle : int, optional
        Resample each cycle at this many times of the dense output instead of the
        samples.

    Returns
    -------
    CycleReport

    Raises
    ------
    ValueError
        For a bad argument (named), or no complete cycle in the run.
    """
    if (period is None) == (omega is None):
        raise ValueError(f"give exactly one of `period` and `omega`, got period={period!r}, "
                         f"omega={omega!r}")
    T = as_positive("period", period) if period is not None else \
        2.0 * math.pi / as_positive("omega", omega)
    start = as_finite("t_start", t_start)
    tol = as_positive("rtol", rtol)
    k_fixed = None if stiffness is None else as_positive("stiffness", stiffness)
    if points_per_cycle is not None:
        as_int_at_least("points_per_cycle", points_per_cycle, 8)
    name, picked = _element_sign(sol, element)
    first, last = float(sol.t[0]), float(sol.t[-1])
    if not first <= start < last:
        raise ValueError(f"`t_start` must lie in [{first!r}, {last!r}), got {start!r}")
    n = math.floor((last - start) / T * (1.0 + 1e-12))
    if n < 1:
        raise ValueError(f"no complete cycle of period {T!r} s between t_start = {start!r} "
                         f"and the end of the run, {last!r}")
    raw = []
    for k in range(n):
        a, b = start + k * T, min(start + (k + 1) * T, last)
        loop = _loop(sol, name, picked, _window(sol, a, b, points_per_cycle))
        q, F = loop.elongation, loop.force
        u0 = 0.5 * float(q.max() - q.min())
        F0 = 0.5 * float(F.max() - F.min())
        k_eff = k_fixed if k_fixed is not None else (F0 / u0 if u0 > 0.0 else math.nan)
        E_s = 0.5 * k_eff * u0 * u0
        E = loop.work()
        zeta = E / (4.0 * math.pi * E_s) if E_s > 0.0 else math.nan
        raw.append(dict(index=k, t0=a, t1=b, energy=E, amplitude=u0,
                        offset=0.5 * float(q.max() + q.min()), force_amplitude=F0,
                        k_eff=k_eff, zeta_eq=zeta))
    steady_from = _steady_from(raw, tol)
    found = tuple(Cycle(**c, steady=steady_from is not None and c["index"] >= steady_from)
                  for c in raw)
    steady = [c for c in found if c.steady]

    def mean(field: str) -> float | None:
        return float(np.mean([getattr(c, field) for c in steady])) if steady else None

    return CycleReport(name, T, found, steady_from, mean("energy"), mean("amplitude"),
                       mean("k_eff"), mean("zeta_eq"))


def _steady_from(raw: list[dict], rtol: float) -> int | None:
    """The first cycle from which every later one agrees with the one before."""
    def agree(j: int) -> bool:
        now, before = raw[j], raw[j - 1]
        u, u_prev = now["amplitude"], before["amplitude"]
        E, E_prev = now["energy"], before["energy"]
        box = 4.0 * now["force_amplitude"] * u
        return (abs(u - u_prev) <= rtol * max(u, u_prev)
                and abs(E - E_prev) <= rtol * max(abs(E), abs(E_prev), 1e-3 * box))

    j = len(raw)
    while j > 1 and agree(j - 1):
        j -= 1
    return j - 1 if j < len(raw) else None
