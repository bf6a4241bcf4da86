r"""The energy ledger of a run: where the work of the forcing went, element by element.

Sign convention (see :mod:`lumped.scene`): an element from node ``a`` to node ``b``
carries the force ``F`` (positive in tension), ``+F`` on ``a`` and ``-F`` on ``b``. The
power it takes from the nodes is therefore ``F (v_b - v_a) = F qdot`` with
``q = x_b - x_a``, and the momentum balance gives, summed over the masses,

.. math::

    \frac{d}{dt} \sum_i \tfrac12 m_i v_i^2
      = \sum_i f_i(t)\, v_i - \sum_{e} F_e\, (v_{b_e} - v_{a_e}).

Integrated from ``0`` to ``t`` this is the ledger, each entry a function of time:

``kinetic[i]``
    ``T_i(t) = m_i v_i(t)^2 / 2`` per mass (absolute).
``stored[e]``
    ``U_e(t) = int_0^t F_e dq_e`` per spring, the path integral of the force along the
    elongation, so the change since ``t = 0`` (for an elastic law ``F = F(q)`` this is
    the state function ``U(q(t)) - U(q(0))``; for a linear spring ``k (q^2 - q_0^2)/2``).
``dissipated[e]``
    ``D_e(t) = int_0^t F_e q_e dt`` per dashpot, ``q_e = v_b - v_a`` its rate
    (``>= 0`` for a dissipative law, e.g. Bingham: ``F q >= 0``).
``work[i]``
    ``W_i(t) = int_0^t f_i(t) v_i dt`` per node with a forcing (masses and junctions).
``support``
    the work of the moving ground (:mod:`lumped.scene.ground`), empty when it does not
    move; see "Two frames" below. For a scene with supports
    (:mod:`lumped.scene.supports`; absolute states, one frame), ``support[s]`` is the
    work support ``s`` does through the elements attached to it,
    ``int v_s (sum_{b_e = s} F_e - sum_{a_e = s} F_e) dt``, plus ``+-v_s(t_k) P_k`` for
    each impulse ``P_k`` of an impact at ``t_k`` on an element attached to it (``+`` at
    its end ``b``: a string jerked taut by the support), and ``stored``/``dissipated``
    use the elongations with the support's motion.
``impacts``
    the kinetic energy lost at the impacts a method reported (``Event.energy_lost``),
    cumulated at the first sample at or after each impact. An impact event stands for a
    velocity jump that no force sample carries (two samples at the same time); a method
    that spreads the impulse over a step as a large force (BDF1 across a lock) already
    has its loss in the integrals below and must not also report it as an event.
``residual``
    ``sum_i (T_i(t) - T_i(0)) + sum U_e + sum D_e + impacts - sum W_i``: zero for the
    exact motion. The integrals use the trapezoidal rule on the samples (exact for a
    linear spring), so the residual measures the method's error: ``O(dt)`` for BDF1
    (whose numerical dissipation is ``sum m (v_{n+1} - v_n)^2 / 2``), smaller for BDF2.

**Two frames (a moving ground).** The run's states are relative to the ground and each
mass is pushed by the inertial force ``-m_i a_g``. The element terms ``U_e`` and
``D_e`` are the same in both frames (an elongation is a difference of displacements).

* ``frame="relative"`` (default): ``kinetic`` is ``m_i v_i^2 / 2`` with the relative
  velocity, ``work`` the work of the applied forces ``int f_i v_i dt``, and
  ``support[i] = -int m_i a_g v_i dt`` per mass, the work of the inertial force:

  .. math::  \sum_i \Delta T_i + \sum U_e + \sum D_e + E_{imp}
             = \sum_i \int f_i v_i\,dt - \sum_i \int m_i a_g v_i\,dt .

* ``frame="absolute"``: ``kinetic`` is ``m_i (v_i + v_g)^2 / 2``, ``work`` is
  ``int f_i (v_i + v_g) dt``, and ``support["ground"]`` is the work the ground does
  through the elements attached to it, ``int v_g (sum_{b_e = g} F_e - sum_{a_e = g}
  F_e) dt`` (an element from ``a`` to ``b`` pulls its ends together with ``F``).

Both close to the method's error (tested).
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass, field

import numpy as np

from lumped._optional import require
from lumped.scene import Mass, Scene

from .columns import F_col, displacements, external_forces, v_col, velocities

__all__ = ["EnergyLedger", "energy_ledger"]


@dataclass(frozen=True)
class EnergyLedger:
    """Energy per element and per node over time, in joules (see :mod:`lumped.post.energy`).

    Attributes
    ----------
    t : numpy.ndarray
        Sample times (s).
    kinetic : dict[str, numpy.ndarray]
        Mass name -> kinetic energy ``m v^2 / 2``.
    stored : dict[str, numpy.ndarray]
        Spring element name -> ``int_0^t F dq`` (change of its stored energy since 0).
    dissipated : dict[str, numpy.ndarray]
        Dashpot element name -> ``int_0^t F q dt`` (energy it dissipated since 0).
    work : dict[str, numpy.ndarray]
        Forced node name -> ``int_0^t f v dt`` (work done on it by its forcing).
    impacts : numpy.ndarray
        Cumulative kinetic energy lost at impacts.
    residual : numpy.ndarray
        The balance ``dT + U + D + impacts - W - S``; zero for the exact motion.
    support : dict[str, numpy.ndarray]
        The work ``S`` of the moving ground: per mass in the relative frame, one entry
        ``"ground"`` in the absolute frame; empty when the ground does not move.
    frame : str
        ``"relative"`` or ``"absolute"``.
    """

    t: np.ndarray
    kinetic: dict[str, np.ndarray]
    stored: dict[str, np.ndarray]
    dissipated: dict[str, np.ndarray]
    work: dict[str, np.ndarray]
    impacts: np.ndarray
    residual: np.ndarray
    support: dict[str, np.ndarray] = field(default_factory=dict)
    frame: str = "relative"

    def scale(self) -> float:
        """The largest magnitude of any entry (J): the yardstick for the residual."""
        entries = [*self.kinetic.values(), *self.stored.values(),
                   *self.dissipated.values(), *self.work.values(), *self.support.values(),
                   self.impacts]
        return max((float(np.max(np.abs(a))) for a in entries if len(a)), default=0.0)

    def to_dict(self) -> dict[str, np.ndarray]:
        """Flat ``{column: array}``: ``t``, ``kinetic_<mass>``, ``stored_<element>``,
        ``dissipated_<element>``, ``work_<node>``, ``support_<name>``, ``impacts``,
        ``residual``."""
        out: dict[str, np.ndarray] = {"t": self.t}
        for prefix, table in (("kinetic", self.kinetic), ("stored", self.stored),
                              ("dissipated", self.dissipated), ("work", self.work),
                              ("support", self.support)):
            out.update({f"{prefix}_{name}": arr for name, arr in table.items()})
        out["impacts"] = self.impacts
        out["residual"] = self.residual
        return out

    def to_pandas(self):
        """The ledger as a ``pandas.DataFrame`` indexed by ``t`` (needs pandas)."""
        pd = require("pandas", "EnergyLedger.to_pandas()")
        table = self.to_dict()
        return pd.DataFrame(table).set_index("t")

    def __repr__(self) -> str:
        return (f"EnergyLedger({len(self.t)} samples, masses {list(self.kinetic)}, springs "
                f"{list(self.stored)}, dashpots {list(self.dissipated)}, forced "
                f"{list(self.work)}, max |residual| = {float(np.max(np.abs(self.residual))):.3g} J)"
                if len(self.t) else "EnergyLedger(empty)")


def _cumulative_trapezoid(y: np.ndarray, x: np.ndarray) -> np.ndarray:
    """``int_{x_0}^{x_n} y`` by the trapezoidal rule, for every ``n`` (starts at 0)."""
    out = np.zeros(len(y))
    if len(y) > 1:
        out[1:] = np.cumsum(0.5 * (y[1:] + y[:-1]) * np.diff(x))
    return out


def energy_ledger(scene: Scene, data: np.ndarray, events: Iterable = (), *,
                  frame: str = "relative") -> EnergyLedger:
    """Build the :class:`EnergyLedger` of the samples ``data`` of ``scene``.

    Parameters
    ----------
    scene : Scene
    data : numpy.ndarray
        ``(n_samples, len(scene.columns()))`` samples.
    events : iterable of Event
        The run's events; those of kind ``"impact"`` contribute their ``energy_lost``.
    frame : {"relative", "absolute"}
        The frame of the kinetic energy and of the work (see "Two frames" above).
    """
    if frame not in ("relative", "absolute"):
        raise ValueError(f"`frame` must be 'relative' or 'absolute', got {frame!r}")
    t = data[:, 0]
    events = list(events)
    gm = getattr(scene, "ground_motion", None)
    if gm is not None:
        _, v_g, a_g = gm.motion(t)
    else:
        v_g = a_g = np.zeros(len(t))
    shift = v_g if frame == "absolute" else 0.0
    kinetic = {n.name: 0.5 * n.m * (data[:, v_col(i)] + shift) ** 2
               for i, n in enumerate(scene.nodes) if isinstance(n, Mass)}
    stored: dict[str, np.ndarray] = {}
    dissipated: dict[str, np.ndarray] = {}
    for e, el in enumerate(scene.elements):
        F = data[:, F_col(scene, e)]
        if el.kind == "spring":
            stored[el.name] = _cumulative_trapezoid(F, displacements(scene, data, e))
        else:
            dissipated[el.name] = _cumulative_trapezoid(F * velocities(scene, data, e), t)
    f = external_forces(scene, t)
    support: dict[str, np.ndarray] = {}
    applied = getattr(scene, "applied_forcing", scene.forcing)
    if gm is not None:
        for i, n in enumerate(scene.nodes):
            if isinstance(n, Mass):
                f[:, i] += n.m * a_g  # the applied force alone
                if frame == "relative":
                    support[n.name] = _cumulative_trapezoid(
                        -n.m * a_g * data[:, v_col(i)], t)
        if frame == "absolute":
            pull = np.zeros(len(t))
            for e, (a, b) in enumerate(zip(scene.elem_a, scene.elem_b, strict=True)):
                if b < 0:
                    pull += data[:, F_col(scene, e)]
                if a < 0:
                    pull -= data[:, F_col(scene, e)]
            support["ground"] = _cumulative_trapezoid(v_g * pull, t)
    names = {el.name: e for e, el in enumerate(scene.elements)}
    for end in getattr(scene, "support_ends", ()):
        v_s = scene.supports[end.support].motion(t)[1]
        work_s = _cumulative_trapezoid(end.sign * v_s * data[:, F_col(scene, end.element)], t)
        for ev in events:  # an impulse P through the element: the support's work o_e' P
            if (getattr(ev, "kind", None) == "impact" and ev.impulse
                    and names.get(ev.element) == end.element):
                v_hit = float(scene.supports[end.support].at(ev.t)[1])
                work_s[np.searchsorted(t, ev.t, side="left"):] += end.sign * v_hit * ev.impulse
        support[end.support] = support.get(end.support, 0.0) + work_s
    work = {n.name: _cumulative_trapezoid(f[:, i] * (data[:, v_col(i)] + shift), t)
            for i, n in enumerate(scene.nodes) if applied[i] is not None}
    impacts = np.zeros(len(t))
    for ev in events:
        if getattr(ev, "kind", None) == "impact" and ev.energy_lost:
            impacts[np.searchsorted(t, ev.t, side="left"):] += ev.energy_lost
    residual = impacts.copy()
    for arr in kinetic.values():
        residual += arr - arr[0]
    for arr in (*stored.values(), *dissipated.values()):
        residual += arr
    for arr in (*work.values(), *support.values()):
        residual -= arr
    return EnergyLedger(t, kinetic, stored, dissipated, work, impacts, residual, support,
                        frame)
