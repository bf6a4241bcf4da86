r"""The 3-stage Radau IIA method (order 5): its nodes, Butcher matrix, error weights and
the collocation polynomial's weights (the dense output), and the points of a step where
the branch guards are sampled.

The stage values ``Y_k`` at ``t_n + c_k h`` with ``y_n`` are the nodes ``0, c_1, c_2,
c_3 = 1`` of the collocation polynomial of a step (Hairer & Wanner, *Solving Ordinary
Differential Equations II*, sec. IV.5 and IV.8). The stage equations themselves are in
:mod:`lumped.solvers.radau.stage`.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

__all__ = ["A", "C", "E_ERR", "END_SLOPES", "MU_REAL", "SAMPLES", "START_WEIGHTS", "W",
           "dense_slopes", "dense_weights"]

_S6 = math.sqrt(6.0)
#: Collocation nodes of Radau IIA (3 stages).
C = ((4.0 - _S6) / 10.0, (4.0 + _S6) / 10.0, 1.0)
#: The Butcher matrix ``A``.
A = (
    ((88.0 - 7.0 * _S6) / 360.0, (296.0 - 169.0 * _S6) / 1800.0, (-2.0 + 3.0 * _S6) / 225.0),
    ((296.0 + 169.0 * _S6) / 1800.0, (88.0 + 7.0 * _S6) / 360.0, (-2.0 - 3.0 * _S6) / 225.0),
    ((16.0 - _S6) / 36.0, (16.0 + _S6) / 36.0, 1.0 / 9.0),
)
#: ``L_k(0)``: the value at the step's start of the quadratic through the three stage values
#: (Lagrange weights on the nodes ``C``).  An algebraic variable (a force) that satisfies a
#: linear relation at every stage satisfies it on that quadratic too.
START_WEIGHTS = tuple(
    math.prod(-C[j] for j in range(3) if j != k)
    / math.prod(C[k] - C[j] for j in range(3) if j != k)
    for k in range(3)
)
#: Weights of the embedded error estimate (Hairer & Wanner, RADAU5).
E_ERR = ((-13.0 - 7.0 * _S6) / 3.0, (-13.0 + 7.0 * _S6) / 3.0, -1.0 / 3.0)
#: The real eigenvalue of ``A^{-1}``: ``3 + 3^(2/3) - 3^(1/3)``.
MU_REAL = 3.0 + 3.0 ** (2.0 / 3.0) - 3.0 ** (1.0 / 3.0)


def _inverse3(M: Sequence[Sequence[float]]) -> tuple[tuple[float, ...], ...]:
    (a, b, c), (d, e, f), (g, h, i) = M
    det = a * (e * i - f * h) - b * (d * i - f * g) + c * (d * h - e * g)
    return (
        ((e * i - f * h) / det, (c * h - b * i) / det, (b * f - c * e) / det),
        ((f * g - d * i) / det, (a * i - c * g) / det, (c * d - a * f) / det),
        ((d * h - e * g) / det, (b * g - a * h) / det, (a * e - b * d) / det),
    )


#: ``W = A^{-1}``: the collocation derivative at the stages.
W = _inverse3(A)


def dense_weights(s: float) -> tuple[float, float, float]:
    r"""Lagrange weights ``l_k(s)``, ``k = 1..3``, of the collocation polynomial.

    ``y(t_n + s h) = y_n + sum_k l_k(s) (Y_k - y_n)``, ``l_k`` the Lagrange polynomial of
    the nodes ``0, c_1, c_2, c_3`` that is 1 at ``c_k`` (the weight of the node ``0``
    multiplies ``y_n - y_n = 0``; this form keeps a held value exactly).
    """
    c1, c2, c3 = C
    return (
        s * (s - c2) * (s - c3) / (c1 * (c1 - c2) * (c1 - c3)),
        s * (s - c1) * (s - c3) / (c2 * (c2 - c1) * (c2 - c3)),
        s * (s - c1) * (s - c2) / (c3 * (c3 - c1) * (c3 - c2)),
    )


def dense_slopes(s: float) -> tuple[float, float, float]:
    """Derivatives ``l_k'(s)`` of the weights of :func:`dense_weights` (per unit ``s``)."""
    nodes = (0.0, *C)
    out = []
    for k in (1, 2, 3):
        ck = nodes[k]
        others = [nodes[j] for j in range(4) if j != k]
        denom = 1.0
        for cj in others:
            denom *= ck - cj
        total = 0.0
        for skip in range(3):
            prod = 1.0
            for j, cj in enumerate(others):
                if j != skip:
                    prod *= s - cj
            total += prod
        out.append(total / denom)
    return out[0], out[1], out[2]


#: ``l_k'(1)``: the slope of the collocation polynomial at the end of a step.
END_SLOPES = dense_slopes(1.0)

#: Points ``s`` in ``(0, 1]`` of a step where the guards are sampled on its collocation
#: polynomial (in order; :mod:`lumped.solvers.modes.crossing_root`).
SAMPLES = tuple(k / 8.0 for k in range(1, 9))
