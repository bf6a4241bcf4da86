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
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    from .ground import GroundMotion
    from .network import Scene

__all__ = ["SupportEnd", "check_supports", "SupportFrame", "solver_view", "supported_scene",
           "support_lock", "support_offsets"]


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
    if t is None or not isinstance(t, numbers.Real) or not math.isfinite(t):
        raise ValueError(f"`t` must be a finite time on a scene with supports, got {t!r}")
    out = [0.0] * len(scene.elements)
    motions: dict[str, tuple[float, float, float]] = {}
    for end in scene.support_ends:
        got = motions.get(end.support)
        if got is None:
            got = motions[end.support] = scene.supports[end.support].at(t)
        spring = scene.elements[end.element].kind == "spring"
        out[end.element] = end.sign * (got[0] if spring else got[1])
    return out


def support_lock(scene: Scene) -> str | None:
    """Why the time-stepping solvers refuse ``scene``'s support elements, or ``None``: a
    spring-like element on a support whose law has a position lock (a taut string:
    impacts against a moving support are not implemented)."""
    from ..codegen.branches import law_branches

    for end in scene.support_ends:
        el = scene.elements[end.element]
        if el.kind == "spring" and any(info.locks for info in law_branches(el.law).info):
            return (f"element {el.name!r} on support {end.support!r}: its law "
                    f"{el.law_name!r} has a position lock (impacts against a moving support "
                    "are not implemented)")
    return None


class _ShiftedKernel:
    """``kernel(q + offsets[e], F)``, with the ``magnitude`` of the residual's terms
    shifted the same way where the kernel has one.

    It has no sympy ``expressions``: the branch analysis
    (:func:`lumped.codegen.branches.law_branches`) declines it, so whatever reads
    branches off it falls back to the shifted kernel's values at the point (e.g.
    :func:`lumped.solvers.nonsmooth.impacts.lock_state`), never to the law's branches in
    the unshifted argument."""

    __slots__ = ("kernel", "offsets", "e", "magnitude")

    def __init__(self, kernel: Any, offsets: list[float], e: int) -> None:
        self.kernel, self.offsets, self.e = kernel, offsets, e
        mag = getattr(kernel, "magnitude", None)
        if mag is not None:
            self.magnitude = lambda q, F: mag(q + offsets[e], F)

    def __call__(self, q: float, F: float) -> tuple[float, float, float]:
        return self.kernel(q + self.offsets[self.e], F)


class _ShiftedLaw:
    """A bound law whose kernel reads ``q + o_e(t)`` (see the module notes)."""

    __slots__ = ("bound", "law", "params", "kernel")

    def __init__(self, bound: Any, offsets: list[float], e: int) -> None:
        self.bound, self.law, self.params = bound, bound.law, bound.params
        self.kernel = _ShiftedKernel(bound.kernel, offsets, e)

    def __repr__(self) -> str:
        return f"shifted({self.bound!r})"


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
                el.name, _ShiftedLaw(el.law, self.offsets, end.element), el.a, el.b, F0=el.F0)
        view = copy.copy(scene)
        view.elements = tuple(elements)
        view.support_ends = ()
        view.supports = {}
        view.support_clock = self.at_time
        self.scene = view
        self.at_time(0.0)

    def at_time(self, t: float) -> None:
        """Set every offset to ``o_e(t)`` (the shifted laws read them at their next call);
        nothing to do when they are at ``t`` already."""
        if t == self._t:
            return
        self._t = t
        self.offsets[:] = support_offsets(self.source, t)  # (in place: the laws read it)


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

    Raises
    ------
    ValueError
        If an element on a support has a position lock (:func:`support_lock`).
    """
    why = support_lock(scene)
    if why is not None:
        raise ValueError(f"method {method!r} does not take this scene: {why}")
    return SupportFrame(scene)
