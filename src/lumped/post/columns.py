r"""The column layout of a run and the scene quantities every post-processor needs.

A run's ``data`` has the columns of :meth:`lumped.scene.Scene.columns`: ``t``, then
``x_i, v_i`` per node, then ``F_e`` per element. The helpers below evaluate, for all
samples at once (numpy arrays of length ``n_samples``):

* the elongation ``q_e = x_b - x_a`` of a spring and the rate ``q_e = v_b - v_a`` of a
  dashpot (ground contributes 0, a support its prescribed ``x_s(t)``, ``v_s(t)``), and
  the elongation of either kind for the energy ledger;
* the net force on each node, ``f_i(t) + sum_{a_e = i} F_e - sum_{b_e = i} F_e``
  (element forces positive in tension: ``+F`` on ``a``, ``-F`` on ``b``; external
  forces positive towards ``+x``).
"""

from __future__ import annotations

import numpy as np

from lumped.scene import Scene

__all__ = ["x_col", "v_col", "F_col", "displacements", "velocities", "elongations",
           "external_forces", "net_forces"]


def x_col(i: int) -> int:
    """Column of the displacement of node ``i``."""
    return 1 + 2 * i


def v_col(i: int) -> int:
    """Column of the velocity of node ``i``."""
    return 2 + 2 * i


def F_col(scene: Scene, e: int) -> int:
    """Column of the force of element ``e``."""
    return 1 + 2 * len(scene.nodes) + e


def _difference(data: np.ndarray, a: int, b: int, col) -> np.ndarray:
    out = np.zeros(len(data))
    if b >= 0:
        out = out + data[:, col(b)]
    if a >= 0:
        out = out - data[:, col(a)]
    return out


def _support_offset(scene: Scene, data: np.ndarray, e: int, derivative: int):
    """``sign * x_s(t)`` (``derivative`` 0) or ``sign * v_s(t)`` (1) at every sample for
    an element with an end on support ``s``, else 0 (:mod:`lumped.scene.supports`)."""
    for end in getattr(scene, "support_ends", ()):
        if end.element == e:
            return end.sign * scene.supports[end.support].motion(data[:, 0])[derivative]
    return 0.0


def displacements(scene: Scene, data: np.ndarray, e: int) -> np.ndarray:
    """``x_b - x_a`` of element ``e`` at every sample (its elongation, either kind; a
    support end moves with the support)."""
    return (_difference(data, scene.elem_a[e], scene.elem_b[e], x_col)
            + _support_offset(scene, data, e, 0))


def velocities(scene: Scene, data: np.ndarray, e: int) -> np.ndarray:
    """``v_b - v_a`` of element ``e`` at every sample (its elongation rate, either kind; a
    support end moves with the support)."""
    return (_difference(data, scene.elem_a[e], scene.elem_b[e], v_col)
            + _support_offset(scene, data, e, 1))


def elongations(scene: Scene, data: np.ndarray, e: int) -> np.ndarray:
    """The argument ``q`` of element ``e``'s law at every sample: the elongation of a
    spring, the elongation rate of a dashpot."""
    if scene.elements[e].kind == "spring":
        return displacements(scene, data, e)
    return velocities(scene, data, e)


def external_forces(scene: Scene, t: np.ndarray) -> np.ndarray:
    """``(len(t), n_nodes)`` array of ``f_i(t)`` (zero where a node has no forcing)."""
    t = np.asarray(t, dtype=float)
    if all(f is None for f in scene.forcing):
        return np.zeros((len(t), len(scene.nodes)))
    return np.array([scene.external_forces(float(tk)) for tk in t], dtype=float).reshape(
        len(t), len(scene.nodes))


def net_forces(scene: Scene, data: np.ndarray) -> np.ndarray:
    """``(n_samples, n_nodes)`` array of the net force on each node (eq. 4a's right side)."""
    net = external_forces(scene, data[:, 0])
    for e, (a, b) in enumerate(zip(scene.elem_a, scene.elem_b, strict=True)):
        F = data[:, F_col(scene, e)]
        if a >= 0:
            net[:, a] += F
        if b >= 0:
            net[:, b] -= F
    return net
