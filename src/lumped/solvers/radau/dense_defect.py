r"""The defect of ``radau5``'s dense output against the held laws, in the first step after
an event.

Radau IIA's error estimate (:meth:`lumped.solvers.radau.error.ErrorEstimate.error_norm`)
measures ``x`` of every node and ``v`` of every mass at the end of a step. Right after an event the
motion can start with a singularity in time that the estimate does not see: a massless
junction whose Herschel-Bulkley ``n < 1`` dashpot breaks out has the rate
``q = gamma (F - tau)^n`` with ``F - tau ~ (t - t_*)``, so ``q ~ (t - t_*)^n`` and the
junction's position goes as ``(t - t_*)^(1 + n)``. The filtered estimate divides by the
stiff junction direction and accepted one step of 0.35 s across such a break-out at
``rtol = 6e-4``: the dense output inside it had the junction's rate at 0.09 where the
law gives 0.51 for the force beside it (issue 11).

The stage values hold every law exactly at the collocation nodes; between them the dense
output of ``q`` and ``F`` is interpolated, and how far the interpolated pair lies from the
law's curve is the defect of the output. For a law linear in ``(q, F)`` (a linear spring,
a Newtonian or Bingham dashpot slipping, a lock) the interpolation stays on the curve and
the defect is round-off; for a curved law it is the interpolation error. The start point
``s = 0`` is the event's state, which holds the law only to the event's own tolerance (a
string snapped taut within the position tolerance): its residual ``R_0``, carried by the
interpolation with the weight ``l_0(s)`` of the node ``0``, is not the step's defect and
is taken out. The distance is measured in the tolerances' units,

.. math::

    d_e(s) = \frac{|R_e(q(s), F(s)) - l_0(s) R_0|}{\sqrt{(R_q \sigma_q)^2
             + (R_F \sigma_F)^2}},

``sigma_q = atol + rtol max |y|`` (velocities for a dashpot, positions for a spring) and
``sigma_F = min(1e-3, 100 rtol) max(|F|, F_ref)`` (``F_ref`` the largest force or load
met so far), the tolerance the forces of the dense output are held to. ``d <= 1`` at
the sample points accepts the step. The sign convention is the laws': ``q`` the
elongation (or its rate) from end ``a`` to end ``b``, ``F`` the tension.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from .error import FORCE_TOL_FACTOR
from .tableau import dense_weights

__all__ = ["SAMPLES", "WEIGHTS", "dense_defect", "norm2"]

#: Where the defect is sampled (fractions of the step): the two lobes of the
#: interpolation error of a ``(t - t_*)^n`` start (for ``n = 0.5`` the cubic through the
#: nodes is off by 0.076 and 0.069 of the step's change there; 0.082 at most, at 0.03).
SAMPLES = (0.03, 0.4)
#: The dense output's weights ``l_1, l_2, l_3`` at :data:`SAMPLES`.
WEIGHTS = tuple(dense_weights(s) for s in SAMPLES)


def norm2(a: float, b: float) -> float:
    """``sqrt(a^2 + b^2)`` without overflow, as ``m sqrt((a/m)^2 + (b/m)^2)``, ``m =
    max(|a|, |b|)`` (``m`` itself when it is 0, infinite or NaN): IEEE operations and a
    square root alone, so the compiled twin (:mod:`lumped.solvers.eventdriven.first_step_jit`)
    gives the same bits; ``math.hypot`` is CPython's own algorithm, numba's the C
    library's."""
    a, b = abs(a), abs(b)
    m = a if a > b else b
    if not m > 0.0 or m == math.inf:
        return m
    a, b = a / m, b / m
    return m * math.sqrt(a * a + b * b)


def dense_defect(nodes: Sequence[tuple[tuple[float, ...], tuple[float, ...]]],
                 kernels: Sequence[Callable], spring: Sequence[bool], rtol: float,
                 atol: float, v_scale: float, x_scale: float, F_ref: float
                 ) -> tuple[float, int]:
    """The largest scaled defect ``d`` of the dense output on a step and its element.

    Parameters
    ----------
    nodes : sequence of ((q_0, q_1, q_2, q_3), (F_0, F_1, F_2, F_3))
        Per element, its ``q`` and ``F`` at ``s = 0, c_1, c_2, 1``
        (:meth:`~lumped.solvers.radau.stage.StageSystem.element_nodes`).
    kernels : sequence of callables
        Per element, its held branch's kernel ``(q, F) -> (R, dR/dq, dR/dF)``.
    spring : sequence of bool
        Which elements are springs (``q`` a position) rather than dashpots (a rate).
    rtol, atol : float
        The run's tolerances.
    v_scale, x_scale : float
        The largest ``|v|`` and ``|x|`` at the step's start and end.
    F_ref : float
        The force scale of the run: the largest force or load met so far.

    Returns
    -------
    (float, int)
        ``max_e max_s d_e(s)`` and the element where it is largest (``-1`` without
        elements).
    """
    sigma_v = atol + rtol * v_scale
    sigma_x = atol + rtol * x_scale
    rtol_F = min(1e-3, FORCE_TOL_FACTOR * rtol)
    worst, where = 0.0, -1
    for e, (q, F) in enumerate(nodes):
        sigma_q = sigma_x if spring[e] else sigma_v
        sigma_F = rtol_F * max(abs(F[0]), abs(F[3]), F_ref)
        kernel = kernels[e]
        R0 = kernel(q[0], F[0])[0]
        for w1, w2, w3 in WEIGHTS:
            qs = q[0] + w1 * (q[1] - q[0]) + w2 * (q[2] - q[0]) + w3 * (q[3] - q[0])
            Fs = F[0] + w1 * (F[1] - F[0]) + w2 * (F[2] - F[0]) + w3 * (F[3] - F[0])
            R, Rq, RF = kernel(qs, Fs)
            norm = norm2(Rq * sigma_q, RF * sigma_F)
            if not norm > 0.0:
                continue
            d = abs(R - (1.0 - w1 - w2 - w3) * R0) / norm
            if not d <= worst:  # (a NaN defect is the worst)
                worst, where = (d if math.isfinite(d) else math.inf), e
    return worst, where
