r"""The static balance of a network at rest: the forces of the elements that hold every
node still, from the others' forces and the load.

With every node at rest, ``free`` elements whose forces are left to the balance (a stuck
dashpot, a taut string) and the other elements' forces known, the balance of every node
(eq. 4a, ``net_i = f_i + sum_{a_e = i} F_e - sum_{b_e = i} F_e = 0``) is

.. math::

    K_\text{free} F_\text{free} = -(f + K_\text{fixed} F_\text{fixed}),

with ``K`` the incidence matrix (``+1`` at an element's first node ``a``, ``-1`` at its
second node ``b``). When ``free`` has one element per node and ``K_free`` is regular it
has one solution; ``K_free`` is then unimodular (an incidence matrix with ground as the
reference vertex), so ``-K_free^{-1}`` is an integer matrix, made once per structure
(:func:`rest_inverse`). :func:`rest_forces` evaluates the balance with the same operations
as :meth:`lumped.solvers.modes.stuck.StaticHold.forces`, so that the consistent initial state
of a scene at rest and its held interval agree bit for bit.
"""

from __future__ import annotations

from collections.abc import Sequence
from functools import lru_cache

import numpy as np

__all__ = ["rest_inverse", "rest_forces"]


@lru_cache(maxsize=256)
def rest_inverse(n_nodes: int, ends: tuple[tuple[int, int], ...], free: tuple[int, ...]
                 ) -> tuple[list[list[float]], list[list[float]], list[int]] | None:
    """``(-K_free^-1, K, fixed)`` for the elements with ``ends`` ``(a, b)`` (ground
    ``-1``; ``K`` as lists of floats, ``n_nodes`` rows), or ``None`` when ``free`` has not
    one element per node or ``K_free`` is singular (cached per structure; the caller must
    not change the lists)."""
    if len(free) != n_nodes:
        return None
    K = np.zeros((n_nodes, len(ends)))
    for e, (a, b) in enumerate(ends):
        if a >= 0:
            K[a, e] += 1.0
        if b >= 0:
            K[b, e] -= 1.0
    Kf = K[:, list(free)]
    if abs(np.linalg.det(Kf)) < 0.5:  # an incidence matrix: det is an integer
        return None
    # a regular incidence matrix is unimodular: its inverse is integral
    minv = (-np.round(np.linalg.inv(Kf))).tolist()
    fixed = [e for e in range(len(ends)) if e not in free]
    return minv, K.tolist(), fixed


def rest_forces(minv: Sequence[Sequence[float]], K: Sequence[Sequence[float]],
                fixed: Sequence[int], free: Sequence[int], f: Sequence[float],
                F: Sequence[float]) -> tuple[list[float], list[float]]:
    """``(F', c)``: ``F`` with the ``free`` forces set by the balance under the load ``f``,
    and ``c = K_fixed F_fixed`` (floats)."""
    c = [sum(K[i][e] * F[e] for e in fixed) for i in range(len(f))]
    g = [fi + ci for fi, ci in zip(f, c, strict=True)]
    out = list(F)
    for r, e in enumerate(free):
        row = minv[r]
        s = 0.0
        for i, gi in enumerate(g):
            s += row[i] * gi
        out[e] = s
    return out, c
