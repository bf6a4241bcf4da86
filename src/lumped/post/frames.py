r"""Relative and absolute motion of a run whose ground moves (:mod:`lumped.scene.ground`).

The solver's states are **relative to the ground**: ``x_i``, ``v_i`` (the columns
``x_<node>``, ``v_<node>``; ``sol.x``, ``sol.v``). The relative acceleration of a mass
is read off the momentum balance at each sample,

.. math::  a_i = \frac{1}{m_i}\Big(f_i(t) - m_i a_g(t) + \sum_{e: a_e = i} F_e
                 - \sum_{e: b_e = i} F_e\Big),

with the sample's forces: the derivative the method itself used there (exact for
``radau5``'s collocation at its step points, the BDF difference quotient for
``bdf1``/``bdf2``). The **absolute** motion is post-processed from the prescribed
ground motion,

.. math::  x^{abs}_i = x_i + x_g(t), \qquad v^{abs}_i = v_i + v_g(t), \qquad
           a^{abs}_i = a_i + a_g(t),

for every node (accelerations for the masses only: a junction has no balance that
gives one). Without ground motion ``x_g = v_g = a_g = 0`` and both frames coincide.

**Supports** (:mod:`lumped.scene.supports`) do not move the frame: a scene with supports
has no ground motion, its states are absolute and both frames coincide. Each support's
prescribed absolute motion ``x_s, v_s, a_s`` at the samples is :func:`support_traces`;
its columns are ``x_<support>``, ``v_<support>``, ``a_<support>`` (a support's name is
never a node's, so they cannot be confused with ``x_<node>``, ``v_<node>``; as the
ground's are ``x_ground``, ...).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from lumped.scene import Mass, Scene

from .columns import net_forces, v_col, x_col

__all__ = ["Frame", "GroundTrace", "ground_trace", "support_traces", "relative_frame",
           "absolute_frame", "frame_columns"]


@dataclass(frozen=True)
class GroundTrace:
    """The prescribed ground motion at the sample times: ``x``, ``v``, ``a`` (m, m/s,
    m/s^2), zero when the ground does not move."""

    t: np.ndarray
    x: np.ndarray
    v: np.ndarray
    a: np.ndarray


@dataclass(frozen=True)
class Frame:
    """The motion of every node in one frame.

    Attributes
    ----------
    frame : str
        ``"relative"`` (to the ground; the solver's states) or ``"absolute"``.
    t : numpy.ndarray
    x, v : dict[str, numpy.ndarray]
        Displacement (m) and velocity (m/s) per node.
    a : dict[str, numpy.ndarray]
        Acceleration (m/s^2) per mass, from the momentum balance.
    """

    frame: str
    t: np.ndarray
    x: dict[str, np.ndarray]
    v: dict[str, np.ndarray]
    a: dict[str, np.ndarray]


def ground_trace(scene: Scene, t: np.ndarray) -> GroundTrace:
    """``x_g, v_g, a_g`` at the times ``t``."""
    t = np.asarray(t, dtype=float)
    gm = getattr(scene, "ground_motion", None)
    if gm is None:
        zero = np.zeros(len(t))
        return GroundTrace(t, zero, zero.copy(), zero.copy())
    x, v, a = gm.motion(t)
    return GroundTrace(t, x, v, a)


def support_traces(scene: Scene, t: np.ndarray) -> dict[str, GroundTrace]:
    """``{support: (x_s, v_s, a_s)}`` at the times ``t``, the prescribed absolute motion
    of each support of ``scene`` (empty without supports)."""
    t = np.asarray(t, dtype=float)
    return {name: GroundTrace(t, *motion.motion(t))
            for name, motion in getattr(scene, "supports", {}).items()}


def relative_frame(scene: Scene, data: np.ndarray) -> Frame:
    """The solver's states and the masses' accelerations from the balance."""
    net = net_forces(scene, data)
    names = scene.node_names
    x = {n: data[:, x_col(i)] for i, n in enumerate(names)}
    v = {n: data[:, v_col(i)] for i, n in enumerate(names)}
    a = {node.name: net[:, i] / node.m for i, node in enumerate(scene.nodes)
         if isinstance(node, Mass)}
    return Frame("relative", data[:, 0], x, v, a)


def absolute_frame(scene: Scene, data: np.ndarray,
                   relative: Frame | None = None) -> Frame:
    """``x + x_g``, ``v + v_g``, ``a + a_g`` (see the module notes)."""
    rel = relative if relative is not None else relative_frame(scene, data)
    g = ground_trace(scene, data[:, 0])
    return Frame("absolute", rel.t, {n: arr + g.x for n, arr in rel.x.items()},
                 {n: arr + g.v for n, arr in rel.v.items()},
                 {n: arr + g.a for n, arr in rel.a.items()})


def frame_columns(scene: Scene, data: np.ndarray) -> tuple[list[str], np.ndarray]:
    """The extra columns of a run on a moving ground, for tables: ``x_ground``,
    ``v_ground``, ``a_ground``, the relative ``a_<mass>``, then the absolute
    ``x_abs_<node>``, ``v_abs_<node>``, ``a_abs_<mass>``.

    With supports (absolute states, no ground motion): ``x_<support>``,
    ``v_<support>``, ``a_<support>`` per support, then ``a_<mass>``."""
    rel = relative_frame(scene, data)
    supports = support_traces(scene, data[:, 0])
    if supports:
        names, cols = [], []
        for name, tr in supports.items():
            names += [f"x_{name}", f"v_{name}", f"a_{name}"]
            cols += [tr.x, tr.v, tr.a]
        names += [f"a_{n}" for n in rel.a]
        cols += list(rel.a.values())
        return names, np.column_stack(cols)
    ab = absolute_frame(scene, data, rel)
    g = ground_trace(scene, data[:, 0])
    names = ["x_ground", "v_ground", "a_ground"]
    cols = [g.x, g.v, g.a]
    names += [f"a_{n}" for n in rel.a]
    cols += list(rel.a.values())
    for prefix, table in (("x_abs", ab.x), ("v_abs", ab.v), ("a_abs", ab.a)):
        names += [f"{prefix}_{n}" for n in table]
        cols += list(table.values())
    return names, np.column_stack(cols) if cols else np.zeros((len(data), 0))
