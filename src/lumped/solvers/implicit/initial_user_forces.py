r"""The user's initial forces (``Element.F0``): checked against the laws and the junction
balances at the initial state, then put in place of the computed ones.

This module owns :func:`apply_user_forces`, the last step of
:func:`lumped.solvers.implicit.initial_state.consistent_initial_state`.
"""

from __future__ import annotations

from ...scene import Junction, Scene
from ..status import InconsistentInitialForce

__all__ = ["apply_user_forces"]


def apply_user_forces(scene: Scene, x0: list[float], v: list[float], F: list[float],
                      f: list[float]) -> list[float]:
    r"""``F`` with each user force ``Element.F0`` in place of the computed one.

    Each user force must satisfy its law at the initial elongation or rate,
    ``|R(q_e, F0_e)| <= 1e-9 (|dR/dq q_e| + |dR/dF F0_e|) + 1e-12``, and every junction
    must balance with them, ``|f_i + sum_{a_e = i} F_e - sum_{b_e = i} F_e| <= 1e-9 S_i +
    1e-12`` (``S_i``: the sum of the magnitudes of those terms).

    Parameters
    ----------
    scene : Scene
        The scene.
    x0, v : list of float
        The nodes' initial positions and velocities.
    F : list of float
        The computed initial forces (not changed).
    f : list of float
        The external forces at ``t = 0``.

    Returns
    -------
    list of float
        The forces, the user's in place.

    Raises
    ------
    InconsistentInitialForce
        If a user force breaks its element's law or a junction's force balance.
    """
    elements = scene.elements
    user = [e for e, el in enumerate(elements) if el.F0 is not None]
    if not user:
        return F
    F = list(F)
    ea, eb = scene.elem_a, scene.elem_b
    q_init = scene.elongations(x0, v)
    for e in user:
        el = elements[e]
        R, Rq, RF = el.law.kernel(q_init[e], el.F0)
        tol = 1e-9 * (abs(Rq * q_init[e]) + abs(RF * el.F0)) + 1e-12
        if not abs(R) <= tol:
            raise InconsistentInitialForce(
                f"initial force F0 = {el.F0!r} of element {el.name!r} breaks its law "
                f"{el.law_name!r}: R(q={q_init[e]!r}, F={el.F0!r}) = {R!r} != 0"
            )
        F[e] = el.F0
    net = scene.net_forces(0.0, F)
    for i, node in enumerate(scene.nodes):
        if isinstance(node, Junction):
            scale = abs(f[i]) + sum(abs(F[e]) for e in range(len(elements))
                                    if i in (ea[e], eb[e]))
            if not abs(net[i]) <= 1e-9 * scale + 1e-12:
                raise InconsistentInitialForce(
                    f"initial forces break the force balance of junction {node.name!r}: "
                    f"net force {net[i]!r} != 0"
                )
    return F
