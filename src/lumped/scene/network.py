r"""Scenes: masses, massless junctions and ground joined by elements with implicit laws.

A scene is a one-dimensional network. Every node other than ``ground`` has a
displacement ``x_i`` and a velocity ``v_i``; a :class:`Mass` has ``m_i > 0``, a
:class:`Junction` is massless. An :class:`Element` joins node ``a`` to node ``b``
(either may be ``ground``, which never moves) and carries one bound element law
``R(q, F) = 0``.

Sign convention (one element, drawn from ``a`` to ``b``)::

        a  o----[ element, force F ]----o  b
           +F on a  ---->          <----  -F on b        (F > 0: tension)

* the elongation is ``q = x_b - x_a`` for a spring-like law and the elongation rate
  ``q = v_b - v_a`` for a dashpot-like law;
* the element force ``F`` is positive in tension: a stretched spring (``q > 0``) with
  ``F > 0`` pulls ``b`` back by ``-F`` and ``a`` forward by ``+F``.

For the paper's oscillator, both elements run from ``ground`` to the mass, so
``q = x`` (spring) or ``q = v`` (dashpot), and ``F_s, F_d`` act on the mass as ``-F``.

The scene assembles the semi-explicit DAE (paper eqs. 4a-4d, generalised)::

    m_i v_i' = f_i(t) + sum_{e: a_e = i} F_e - sum_{e: b_e = i} F_e     (masses)
          0  = f_i(t) + sum_{e: a_e = i} F_e - sum_{e: b_e = i} F_e     (junctions)
       x_i'  = v_i                                                        (all nodes)
          0  = R_e(q_e, F_e)                                              (all elements)

A spring and a dashpot in series through a junction (a Maxwell element) is a scene of
one junction and two elements. A scene holds only the bound laws of its own elements,
so only their kernels are ever compiled.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

from .._validate import as_finite, as_positive
from .forcing_spec import Forcing, as_forcing

__all__ = ["GROUND", "Mass", "Junction", "Element", "Scene", "across", "as_forcing"]

#: The name of the fixed node every scene has.
GROUND = "ground"


class BoundLawLike(Protocol):
    """What a scene needs from a bound law (see :mod:`lumped.laws`)."""

    law: Any  # has ``name`` and ``kind`` ("spring" | "dashpot")
    params: Mapping[str, float]

    def kernel(self, q: float, F: float) -> tuple[float, float, float]: ...


@dataclass(frozen=True)
class Mass:
    """A node with mass ``m > 0``, initial displacement ``x0`` and velocity ``v0``."""

    name: str
    m: float
    x0: float = 0.0
    v0: float = 0.0

    def __post_init__(self) -> None:
        check_name("Mass name", self.name)
        object.__setattr__(self, "m", as_positive(f"mass of node {self.name!r}", self.m))
        object.__setattr__(self, "x0", as_finite(f"x0 of node {self.name!r}", self.x0))
        object.__setattr__(self, "v0", as_finite(f"v0 of node {self.name!r}", self.v0))


@dataclass(frozen=True)
class Junction:
    """A massless node: its force balance is algebraic.

    Its initial displacement ``x0`` is state (e.g. the internal strain of a Maxwell
    element); its initial velocity follows from the laws and is computed.
    """

    name: str
    x0: float = 0.0

    def __post_init__(self) -> None:
        check_name("Junction name", self.name)
        object.__setattr__(self, "x0", as_finite(f"x0 of node {self.name!r}", self.x0))


@dataclass(frozen=True)
class Element:
    """A bound law between node ``a`` and node ``b`` (either may be ``"ground"`` or a
    support of the scene, :mod:`lumped.scene.supports`).

    ``q = x_b - x_a`` (spring) or ``v_b - v_a`` (dashpot); ``+F`` acts on ``a`` and
    ``-F`` on ``b``. ``F0``, if given, is the user's initial force; it is checked
    against the law at the initial state and refused if it breaks it.
    """

    name: str
    law: BoundLawLike
    a: str
    b: str
    F0: float | None = None

    def __post_init__(self) -> None:
        check_name("Element name", self.name)
        for attr in ("a", "b"):
            val = getattr(self, attr)
            if not isinstance(val, str):
                raise TypeError(
                    f"node `{attr}` of element {self.name!r} must be a str, got {val!r}"
                )
        if not callable(getattr(self.law, "kernel", None)):
            raise TypeError(
                f"`law` of element {self.name!r} must be a bound law (ElementLaw.bind(...)), "
                f"got {self.law!r}"
            )
        kind = getattr(getattr(self.law, "law", None), "kind", None)
        if kind not in ("spring", "dashpot"):
            raise ValueError(
                f"law of element {self.name!r} must have kind 'spring' or 'dashpot', got {kind!r}"
            )
        if self.F0 is not None:
            object.__setattr__(self, "F0", as_finite(f"F0 of element {self.name!r}", self.F0))

    @property
    def kind(self) -> str:
        """``"spring"`` (law in the elongation) or ``"dashpot"`` (in its rate)."""
        return self.law.law.kind

    @property
    def law_name(self) -> str:
        return self.law.law.name


class Scene:
    """Nodes, elements and external forces of a lumped-parameter network.

    Parameters
    ----------
    nodes : sequence of Mass or Junction
        Every node except ``ground`` (which is implicit). At least one must be a Mass.
    elements : sequence of Element
        Each joins two distinct nodes, or a node and ground.
    forces : mapping, optional
        ``{node name: forcing}``, see :func:`as_forcing`. Positive forces push towards +x.
        A table (:class:`lumped.io.Table`) must hold a force (``quantity="force"``).
    ground_motion : GroundMotion, optional
        A prescribed motion of the ground (:class:`lumped.scene.GroundMotion`). The
        states are then relative to the ground and each mass ``i`` is also pushed by the
        inertial force ``-m_i a_g(t)`` (:mod:`lumped.scene.ground`); :attr:`forcing`
        holds the sum, :attr:`applied_forcing` the forces given in ``forces`` alone.
    supports : mapping, optional
        ``{name: GroundMotion}``: named supports, each with its own prescribed motion
        ``x_s(t)`` (:mod:`lumped.scene.supports`). Elements name a support as an end,
        like ``"ground"``; an element from node ``a`` to support ``s`` has
        ``q = x_s(t) - x_a`` (spring) or ``v_s(t) - v_a`` (dashpot). The states stay
        absolute. Not together with ``ground_motion``.

    Examples
    --------
    The paper's oscillator (m = 1, k = 100, gamma = 1, tau = mu_s N_f = 1), released from
    x0 = 0.5::

        from lumped.laws import get_law
        scene = Scene(
            [Mass("mass", m=1.0, x0=0.5)],
            [Element("spring", get_law("linear_spring").bind(k=100.0), "ground", "mass"),
             Element("dashpot", get_law("bingham").bind(gamma=1.0, tau=1.0), "ground", "mass")],
        )
    """

    def __init__(
        self,
        nodes: Sequence[Mass | Junction],
        elements: Sequence[Element],
        forces: Mapping[str, object] | None = None,
        *,
        ground_motion: object = None,
        supports: Mapping[str, object] | None = None,
    ) -> None:
        from .supports import SupportEnd, check_supports

        nodes = tuple(nodes)
        elements = tuple(elements)
        index: dict[str, int] = {}
        for node in nodes:
            if not isinstance(node, (Mass, Junction)):
                raise TypeError(f"nodes must be Mass or Junction, got {node!r}")
            if node.name == GROUND:
                raise ValueError(f"node name {GROUND!r} is reserved for the fixed node")
            if node.name in index:
                raise ValueError(f"duplicate node name {node.name!r}")
            index[node.name] = len(index)
        if not any(isinstance(n, Mass) for n in nodes):
            raise ValueError("a scene needs at least one Mass (none of its nodes has a mass)")
        support_motions = check_supports(supports, tuple(index), ground_motion)
        support_ends: list[SupportEnd] = []
        used: set[str] = set()
        seen: set[str] = set()
        a_idx: list[int] = []
        b_idx: list[int] = []
        touched: set[int] = set()
        for el in elements:
            if not isinstance(el, Element):
                raise TypeError(f"elements must be Element, got {el!r}")
            if el.name in seen:
                raise ValueError(f"duplicate element name {el.name!r}")
            seen.add(el.name)
            ends = []
            for sign, end in ((-1.0, el.a), (1.0, el.b)):
                if end == GROUND:
                    ends.append(-1)
                elif end in index:
                    ends.append(index[end])
                    touched.add(index[end])
                elif end in support_motions:
                    ends.append(-1)
                    used.add(end)
                    support_ends.append(SupportEnd(len(a_idx), end, sign))
                else:
                    known = f", supports: {sorted(support_motions)}" if support_motions else ""
                    raise ValueError(
                        f"element {el.name!r} joins unknown node {end!r} "
                        f"(nodes: {sorted(index)}{known}, or {GROUND!r})"
                    )
            if el.a == el.b:
                raise ValueError(f"element {el.name!r} joins node {el.a!r} to itself")
            if ends == [-1, -1]:
                raise ValueError(f"element {el.name!r} joins {el.a!r} to {el.b!r}: an element "
                                 "on a support needs a node (a Mass or Junction) at its "
                                 "other end")
            a_idx.append(ends[0])
            b_idx.append(ends[1])
        for i, node in enumerate(nodes):
            if isinstance(node, Junction) and i not in touched:
                raise ValueError(f"junction {node.name!r} is not joined by any element")
        for name in support_motions:
            if name not in used:
                raise ValueError(f"support {name!r} is not joined by any element")
        forcing: list[Forcing | None] = [None] * len(nodes)
        for name, spec in (forces or {}).items():
            if name not in index:
                raise ValueError(
                    f"force on unknown node {name!r} (nodes: {sorted(index)})"
                )
            quantity = getattr(spec, "quantity", None)
            if quantity is not None and quantity != "force" and hasattr(spec, "breakpoints"):
                raise ValueError(
                    f"`forces[{name!r}]` is a table of {quantity}, not of force: a "
                    f"{quantity} record pushing on a mass would be a wrong load (give a "
                    f"ground {quantity} as `ground_motion=GroundMotion({quantity}=...)`), "
                    f"got {spec!r}")
            forcing[index[name]] = as_forcing(spec, where=f"force on node {name!r}")
        applied = tuple(forcing)
        if ground_motion is not None:
            from .ground import GroundMotion
            from .inertial import combine_forcing, inertial_forcing

            if not isinstance(ground_motion, GroundMotion):
                raise TypeError(f"`ground_motion` must be a GroundMotion, got {ground_motion!r}")
            for i, node in enumerate(nodes):
                if isinstance(node, Mass):
                    forcing[i] = combine_forcing(forcing[i],
                                                 inertial_forcing(node.m, ground_motion))
        self.nodes: tuple[Mass | Junction, ...] = nodes
        self.elements: tuple[Element, ...] = elements
        self.node_index: dict[str, int] = index
        self.element_index: dict[str, int] = {el.name: e for e, el in enumerate(elements)}
        self.elem_a: tuple[int, ...] = tuple(a_idx)
        self.elem_b: tuple[int, ...] = tuple(b_idx)
        self.forcing: tuple[Forcing | None, ...] = tuple(forcing)
        self.applied_forcing: tuple[Forcing | None, ...] = applied
        self.ground_motion = ground_motion
        #: ``{name: GroundMotion}``, the prescribed motion of each support
        #: (:mod:`lumped.scene.supports`); empty without supports.
        self.supports: dict[str, Any] = support_motions
        #: The element ends on supports, in element order.
        self.support_ends: tuple[SupportEnd, ...] = tuple(support_ends)
        #: ``clock(t)`` setting the support offsets the laws read, on the view a solver
        #: runs (:class:`lumped.scene.supports.SupportFrame`); ``None`` on a user's scene.
        self.support_clock: Callable[[float], None] | None = None
        self.force_specs: dict[str, object] = dict(forces or {})

    # -- structure -------------------------------------------------------------------------
    @property
    def node_names(self) -> tuple[str, ...]:
        return self._names()[0]

    @property
    def element_names(self) -> tuple[str, ...]:
        return self._names()[1]

    def _names(self) -> tuple[tuple[str, ...], tuple[str, ...], tuple[str, ...]]:
        """``(node names, element names, columns)``, made once for the scene's ``nodes``
        and ``elements`` (again if either is replaced)."""
        got = self.__dict__.get("_names_of")
        if got is None or got[0] is not self.nodes or got[1] is not self.elements:
            nodes = tuple(n.name for n in self.nodes)
            elements = tuple(el.name for el in self.elements)
            cols = ["t"]
            for name in nodes:
                cols += [f"x_{name}", f"v_{name}"]
            cols += [f"F_{name}" for name in elements]
            got = self.__dict__["_names_of"] = (self.nodes, self.elements, nodes, elements,
                                                tuple(cols))
        return got[2:]

    @property
    def masses(self) -> tuple[float, ...]:
        """``m_i`` per node, ``0.0`` for junctions."""
        return tuple(n.m if isinstance(n, Mass) else 0.0 for n in self.nodes)

    @property
    def laws(self) -> tuple[BoundLawLike, ...]:
        """The distinct bound laws of this scene (the only ones it compiles)."""
        out: list[BoundLawLike] = []
        for el in self.elements:
            if not any(el.law is other for other in out):
                out.append(el.law)
        return tuple(out)

    def columns(self) -> tuple[str, ...]:
        """CSV / array column names: ``t``, ``x_<node>``, ``v_<node>`` per node, ``F_<el>``."""
        return self._names()[2]

    def external_forces(self, t: float) -> list[float]:
        """``f_i(t)`` per node (checked finite)."""
        out = []
        for i, f in enumerate(self.forcing):
            if f is None:
                out.append(0.0)
                continue
            val = f(t)
            if type(val) is float and math.isfinite(val):  # the common case, no ABC check
                out.append(val)
                continue
            if not (isinstance(val, numbers.Real) and math.isfinite(val)):
                raise ValueError(
                    f"force on node {self.nodes[i].name!r} returned {val!r} at t = {t!r}"
                )
            out.append(float(val))
        return out

    # -- the DAE ----------------------------------------------------------------------------
    def elongations(self, x: Sequence[float], v: Sequence[float],
                    t: float | None = None) -> list[float]:
        """``q_e``: ``x_b - x_a`` for springs, ``v_b - v_a`` for dashpots (ground = 0), plus
        the support offset ``o_e(t)`` of an element on a support
        (:func:`.supports.support_offsets`), for which ``t`` is required."""
        out = []
        for el, a, b in zip(self.elements, self.elem_a, self.elem_b, strict=True):
            out.append(across(x if el.kind == "spring" else v, a, b))
        if self.support_ends:
            from .supports import support_offsets

            for e, o in enumerate(support_offsets(self, t)):
                out[e] += o
        return out

    def net_forces(self, t: float, F: Sequence[float]) -> list[float]:
        """``f_i(t) + sum_{a_e = i} F_e - sum_{b_e = i} F_e`` per node (eq. 4a's right side)."""
        out = self.external_forces(t)
        for e, (a, b) in enumerate(zip(self.elem_a, self.elem_b, strict=True)):
            if a >= 0:
                out[a] += F[e]
            if b >= 0:
                out[b] -= F[e]
        return out

    def dae_residual(
        self,
        t: float,
        x: Sequence[float],
        v: Sequence[float],
        xdot: Sequence[float],
        vdot: Sequence[float],
        F: Sequence[float],
    ) -> list[float]:
        """The DAE ``0 = G(t, x, v, x', v', F)`` in the order: momentum (or junction balance)
        per node, kinematics ``x' - v`` per node, element laws ``R_e(q_e, F_e)``."""
        net = self.net_forces(t, F)
        out = [
            (n.m * vdot[i] if isinstance(n, Mass) else 0.0) - net[i]
            for i, n in enumerate(self.nodes)
        ]
        out += [xdot[i] - v[i] for i in range(len(self.nodes))]
        q = self.elongations(x, v, t if self.support_ends else None)
        out += [el.law.kernel(q[e], F[e])[0] for e, el in enumerate(self.elements)]
        return out

    def __repr__(self) -> str:
        parts = [f"{n.name}(m={n.m})" if isinstance(n, Mass) else f"{n.name}(junction)"
                 for n in self.nodes]
        els = [f"{el.name}: {el.law_name} {el.a}->{el.b}" for el in self.elements]
        ground = "" if self.ground_motion is None else f", ground_motion={self.ground_motion!r}"
        if self.supports:
            ground += f", supports={self.supports!r}"
        return f"Scene(nodes=[{', '.join(parts)}], elements=[{'; '.join(els)}]{ground})"


def across(y: Sequence[float], a: int, b: int) -> float:
    """The across variable ``y_b - y_a`` of an element from node ``a`` to node ``b``
    (indices into ``y``; ground, ``-1``, at ``0``): the elongation for positions, the
    elongation rate for velocities (the module's sign convention)."""
    return (y[b] if b >= 0 else 0.0) - (y[a] if a >= 0 else 0.0)


def check_name(what: str, name: object) -> None:
    """``TypeError`` unless ``name`` is a non-empty str, ``ValueError`` if it holds a
    character other than letters, digits, ``_``, ``-``, ``.`` (``what`` names it)."""
    if not isinstance(name, str) or not name:
        raise TypeError(f"{what} must be a non-empty str, got {name!r}")
    if not all(c.isalnum() or c in "_-." for c in name):
        raise ValueError(
            f"{what} {name!r} may contain only letters, digits, '_', '-' and '.'"
        )
