r"""Named supports with a prescribed motion of their own (multi-support excitation).

A support is a node whose displacement ``x_s(t)`` (and velocity ``v_s``, acceleration
``a_s``) is prescribed, a :class:`~lumped.scene.GroundMotion` (an expression of ``t``,
a :class:`~lumped.scene.SineBurst` or a :class:`~lumped.io.Table` of one of the three
quantities, the other two exact). Elements name it as an end, like ``"ground"``; it has
no state and no balance. Unlike a ground motion (:mod:`lumped.scene.ground`, a moving
frame) the states stay **absolute**: a support moves the ends attached to it, not the
frame.

**Element end offsets.** An element with one end on support ``s`` has

.. math::

    q_e = y_b - y_a + o_e(t), \qquad
    o_e(t) = \sigma_e\, y_s(t), \qquad
    \sigma_e = \begin{cases} +1 & b_e = s \\ -1 & a_e = s \end{cases}

with ``y = x`` for a spring-like law and ``y = v`` for a dashpot-like law, and the
support's own end counting ``0`` in ``y_b - y_a`` (as the ground's does). So an element
from mass ``i`` to support ``s`` has ``q = x_s(t) - x_i`` (``v_s(t) - v_i``), one from
``s`` to ``i`` has ``q = x_i - x_s(t)``. The force sign convention is unchanged: ``+F``
acts on ``a``, ``-F`` on ``b``; the reaction on the support is not a state.

In the solver's index arrays a support end is ``-1``, as the ground: for the structure
of the network (cycles, indeterminate forces) every prescribed node is the one fixed
vertex. Only the laws see the motion. :func:`supported_scene` makes the scene the
time-stepping solvers run: each support element's law is replaced by its *shifted* law
``R_e(y_b - y_a + o_e(t), F)``, an ordinary law in the node states whose offset is the
value set by :meth:`SupportFrame.at_time` (the time of the system being solved,
``t_{n+1}`` for a BDF step).

**The adaptive method** (``radau5``) runs on the same view: its laws' branches are the
shifted branches (:class:`ShiftedBranches`: every kernel, guard and branch selector of
the law reads ``q + o_e``), and the driver sets the clock to the time of every system it
solves or state it reads (each stage time ``t_n + c_k h`` in turn, the probe's
``t + h_p``, an event's ``t``). Where it reads ``q`` along a step's collocation
polynomial it forms the law's argument itself, ``q_e + o_e(t_n + s h)`` at the
polynomial's nodes (:meth:`SupportFrame.offsets_at`), with the clock *bare*
(:meth:`SupportFrame.bare`: every offset 0, so the shifted functions are the law's own).
A locking branch of an element on a support reports no ``lock_value``: its lock
``q_e + o_e(t) = L`` moves with the support, so the rules that set rates or positions
exactly onto a lock value leave it to the system being solved.

**A string on a support** (a spring-like element whose law locks ``q``; every
time-stepping method). The support has a prescribed
motion (infinite mass): the lock ``y_b - y_a + x_s(t) = L`` moves the attached mass
with it, and its force comes from the balance. An impact at ``t`` reads the
elongation rate with the support's, ``q' = v_b - v_a + o_e'(t)``
(:func:`clock_rates`, at the clock's time): the impulse ``P`` sets the free masses so
that ``q'^+ = -e q'^-``, ``M dv = -B^T P``; the support's motion is unchanged and it does
the work ``o_e'(t) P``, so the energy lost is ``sum m (v^-2 - v^+2) / 2 + sum o_e' P``
(``m (v^- - v_s)^2 / 2`` for one mass, plastic). The snap onto the lock and the
locking test read the shifted law at that ``t``; the forces of a lock reached late in a
step (and of one taut at ``t = 0``) come from the balance of accelerations with
``q'' = a_b - a_a + o_e''(t)`` (:func:`support_accelerations`). ``radau5``'s stage
system holds a taut string on the velocity level, as a fixed one: the kernel of a
locking branch (:meth:`ShiftedBranches.kernel_for`) keeps the branch's ``lock_value``
``L`` and the law's own kernel as ``bare``, and the stage ``k`` reads
``R(L) + dR/dq (h sum_j a_kj (V_jb - V_ja) + m_k)`` with the lock's move
``m_k = h sum_j a_kj o_e'(t_n + c_j h)`` from the support's rates
(:meth:`SupportFrame.lock_moves`; the difference ``o_e(t_n + c_k h) - o_e(t_n)`` would
carry ``ulp(x_s)``, forces of ``m ulp / h^2`` on short steps).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Iterator, Mapping, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from .shifted_laws import ShiftedBranches, ShiftedLaw, branches_of

if TYPE_CHECKING:
    from .ground import GroundMotion
    from .network import Scene

__all__ = ["SupportEnd", "check_supports", "SupportFrame", "ShiftedBranches", "branches_of",
           "solver_view", "supported_scene", "support_offsets", "support_rates",
           "support_accelerations", "clock_rates", "support_time",
           "support_time_events", "support_time_restored"]


@dataclass(frozen=True)
class SupportEnd:
    """Element ``element`` has an end on support ``support``; ``sign`` is ``+1`` when it is
    the element's end ``b`` (``q = y_s - y_a``), ``-1`` when it is end ``a``."""

    element: int
    support: str
    sign: float


def check_supports(supports: object, node_names: Sequence[str],
                   ground_motion: object) -> dict[str, GroundMotion]:
    """The validated ``{name: GroundMotion}`` of a scene's ``supports`` argument.

    Raises
    ------
    TypeError
        If ``supports`` is not a mapping, a name not a str or a motion not a GroundMotion.
    ValueError
        For a name that is ``"ground"``, a node's name or not a valid name, or supports
        together with a ``ground_motion`` (the states would be relative to a moving
        ground while the supports are absolute: give every moving support as a support).
    """
    from .ground import GroundMotion
    from .network import GROUND, check_name

    if supports is None:
        return {}
    if not isinstance(supports, Mapping):
        raise TypeError(f"`supports` must be a mapping {{name: GroundMotion}}, got {supports!r}")
    out: dict[str, GroundMotion] = {}
    for name, motion in supports.items():
        check_name("Support name", name)
        if name == GROUND:
            raise ValueError(f"support name {GROUND!r} is reserved for the fixed node")
        if name in node_names:
            raise ValueError(f"support name {name!r} is also the name of a node")
        if not isinstance(motion, GroundMotion):
            raise TypeError(f"`supports[{name!r}]` must be a GroundMotion, got {motion!r}")
        out[name] = motion
    if out and ground_motion is not None:
        raise ValueError("`supports` and `ground_motion` together are not supported (the "
                         "states would be relative to the ground, the supports absolute): "
                         f"give the ground's motion as one more support, got supports "
                         f"{sorted(out)} and ground_motion={ground_motion!r}")
    return out


def support_offsets(scene: Scene, t: float | None) -> list[float]:
    """``o_e(t)`` per element of ``scene``: ``+-x_s(t)`` (spring) or ``+-v_s(t)``
    (dashpot) for an end on support ``s`` (``+`` at end ``b``, ``-`` at end ``a``), else
    ``0``; each support's motion is evaluated once.

    Raises
    ------
    ValueError
        If ``t`` is not a finite time."""
    return _support_values(scene, t, 0)


def support_rates(scene: Scene, t: float) -> list[float]:
    """``o_e'(t)`` per element of ``scene`` (the scene a :class:`SupportFrame` was made
    from, or its view): ``+-v_s(t)`` (spring) or ``+-a_s(t)`` (dashpot) for an end on a
    support, else ``0`` (a stuck dashpot's rate stays 0 only if its nodes take the
    support's acceleration: the initial state's limit system reads it)."""
    frame = getattr(scene, "support_frame", None)
    return _support_values(scene if frame is None else frame.source, t, 1)


def support_accelerations(scene: Scene, t: float) -> list[float]:
    """``+-a_s(t)`` per element of ``scene`` (or its view) with an end on a support
    (``+`` at end ``b``), else ``0``, whatever its kind: the acceleration the support adds
    to the rate of a locked spring's elongation (``q'' = a_b - a_a + o_e''``) and of a
    stuck dashpot's rate (``q' = a_b - a_a + o_e'``)."""
    frame = getattr(scene, "support_frame", None)
    return _support_values(scene if frame is None else frame.source, t, 2)


def _support_values(scene: Scene, t: float | None, order: int) -> list[float]:
    """``o_e`` (``order`` 0) or ``o_e'`` (``order`` 1) per element at ``t``; ``order`` 2:
    ``+-a_s`` for every kind (:func:`support_accelerations`)."""
    if t is None or not isinstance(t, numbers.Real) or not math.isfinite(t):
        raise ValueError(f"`t` must be a finite time on a scene with supports, got {t!r}")
    out = [0.0] * len(scene.elements)
    motions: dict[str, tuple[float, float, float]] = {}
    for end in scene.support_ends:
        got = motions.get(end.support)
        if got is None:
            got = motions[end.support] = scene.supports[end.support].at(t)
        spring = scene.elements[end.element].kind == "spring"
        out[end.element] = end.sign * (got[order] if spring or order == 2 else got[order + 1])
    return out


def clock_rates(scene: Any) -> list[float] | None:
    """``o_e'`` per element at the time of the support clock of ``scene`` (a
    :class:`SupportFrame`'s view: :meth:`SupportFrame.rates_now`), ``None`` on any other
    scene or while the clock is bare: the rate a support adds to an element's
    elongation rate, which the impact law reads (:mod:`lumped.solvers.nonsmooth.impacts`)."""
    frame = getattr(scene, "support_frame", None)
    return None if frame is None else frame.rates_now()


def support_time(scene: Any, t: float) -> None:
    """Set the support clock of ``scene`` (a :class:`SupportFrame`'s view) to ``t``;
    nothing on any other scene."""
    clock = getattr(scene, "support_clock", None)
    if clock is not None:
        clock(t)


@contextmanager
def support_time_restored(scene: Any, t: float) -> Iterator[None]:
    """Within the block the caller sets the clock where it needs it; on the way out it
    is set back to ``t`` (a probe at ``t + h_p`` inside a choice at ``t``)."""
    try:
        yield
    finally:
        support_time(scene, t)


def support_time_events(scene: Scene, t_end: float) -> tuple[list[float], list[float]]:
    """``(breaks, kinks)``: the times in ``(0, t_end)`` where a support's acceleration
    jumps or kinks (its :meth:`~lumped.scene.GroundMotion.breakpoints`), and those at
    which it is continuous (:meth:`~lumped.scene.GroundMotion.kinks`). The offsets
    ``x_s``, ``v_s`` are continuous at all of them."""
    breaks: set[float] = set()
    kinks: set[float] = set()
    for motion in getattr(scene, "supports", {}).values():
        breaks.update(float(b) for b in motion.breakpoints(0.0, t_end))
        kinks.update(float(b) for b in motion.kinks(0.0, t_end))
    return sorted(breaks), sorted(kinks)


class SupportFrame:
    """The scene a time-stepping solver runs (:func:`supported_scene`) and its clock.

    Attributes
    ----------
    scene : Scene
        The scene with each support element's law shifted by ``o_e(t)``; its ends on
        supports are index ``-1``, as the ground.
    offsets : list of float
        ``o_e`` per element at the last :meth:`at_time` (zero off supports).
    """

    def __init__(self, scene: Scene) -> None:
        import copy

        from .network import Element

        self.source = scene
        self.offsets = [0.0] * len(scene.elements)
        self._t = math.nan  # the time of the offsets
        elements = list(scene.elements)
        for end in scene.support_ends:
            el = elements[end.element]
            elements[end.element] = Element(
                el.name, ShiftedLaw(el.law, self.offsets, end.element), el.a, el.b, F0=el.F0)
        view = copy.copy(scene)
        view.elements = tuple(elements)
        view.support_ends = ()
        view.supports = {}
        view.support_clock = self.at_time
        view.support_frame = self
        self.scene = view
        self._cache: dict[float, list[float]] = {}
        self._along: tuple = (None, [])
        self._rates: tuple = (None, [])
        self._moves: tuple = (None, [])
        self.at_time(0.0)

    def at_time(self, t: float) -> None:
        """Set every offset to ``o_e(t)`` (the shifted laws read them at their next call);
        nothing to do when they are at ``t`` already."""
        if t == self._t:
            return
        self._t = t
        self.offsets[:] = self.offsets_at(t)  # (in place: the laws read it)

    def offsets_at(self, t: float) -> list[float]:
        """``o_e(t)`` per element (a new list; the clock is not moved). The last few
        times are remembered: a stage solve asks for the same three stage times at every
        Newton iteration."""
        got = self._cache.get(t)
        if got is None:
            if len(self._cache) >= 16:
                self._cache.clear()
            got = self._cache[t] = support_offsets(self.source, t)
        return list(got)

    def offsets_along(self, t0: float, h: float, nodes: tuple[float, ...]
                      ) -> list[list[float]]:
        """``o_e`` per element at the times ``t0 + s h``, ``s`` in ``nodes`` (the nodes of
        a step's polynomial; the last ones asked are kept)."""
        key = (t0, h, nodes)
        if self._along[0] != key:
            self._along = (key, [self.offsets_at(t0 + s * h) for s in nodes])
        return self._along[1]

    def lock_moves(self, t0: float, h: float, A: Sequence[Sequence[float]],
                   C: Sequence[float]) -> list[list[float]]:
        """``h sum_j A_kj o_e'(t0 + c_j h)`` per stage ``k`` and element ``e``: how far
        a lock on a support moves from ``t0`` to the stage ``t0 + c_k h`` of a collocation
        step (``A``, ``C`` its tableau), from the rates (the difference
        ``o_e(t0 + c_k h) - o_e(t0)`` would carry ``ulp(x_s)``, a force ``m ulp / h^2``).
        The last step asked is kept (a stage solve asks at every Newton iteration)."""
        key = ("moves", t0, h)
        if self._moves[0] != key:
            rates = [support_rates(self.source, t0 + c * h) for c in C]
            self._moves = (key, [[h * sum(a * r[e] for a, r in zip(row, rates, strict=True))
                                  for e in range(len(self.offsets))] for row in A])
        return self._moves[1]

    def rates_now(self) -> list[float] | None:
        """``o_e'`` per element at the clock's time (:func:`support_rates`), ``None``
        while the clock is bare."""
        t = self._t
        if t != t:
            return None
        if self._rates[0] != t:
            self._rates = (t, support_rates(self.source, t))
        return self._rates[1]

    def bare(self) -> None:
        """Every offset ``0``: the shifted laws, branches and guards are the law's own,
        for arguments that already hold ``o_e`` (:meth:`offsets_at`)."""
        self._t = math.nan
        self.offsets[:] = [0.0] * len(self.offsets)


def _no_clock(t: float) -> None:
    """The clock of a scene without supports: nothing reads the time."""


def solver_view(scene: Scene, method: str, t0: float
                ) -> tuple[Scene, Callable[[float], None], Callable[..., list[float]]]:
    """``(scene, clock, law_q)`` for a time-stepping solver starting at ``t0``.

    Without supports: ``scene`` itself, a clock that does nothing and
    ``scene.elongations``. With supports: the view of :func:`supported_scene` with its
    offsets at ``t0``, :meth:`SupportFrame.at_time`, and ``law_q(x, v)``, each law's own
    argument ``q_e + o_e`` at the clock's time (the view's ``elongations`` leave
    ``o_e`` out: its laws add it)."""
    if not getattr(scene, "support_ends", ()):
        return scene, _no_clock, scene.elongations
    frame = supported_scene(scene, method)
    frame.at_time(float(t0))

    def law_q(x, v) -> list[float]:
        q = frame.scene.elongations(x, v)
        return [qe + oe for qe, oe in zip(q, frame.offsets, strict=True)]

    return frame.scene, frame.at_time, law_q


def supported_scene(scene: Scene, method: str) -> SupportFrame:
    """The :class:`SupportFrame` ``method`` runs ``scene`` (which has supports) on.

    Every element on a support is taken, a string (position lock) too (see the module
    notes); ``method`` is the caller's name, for its messages.
    """
    return SupportFrame(scene)
