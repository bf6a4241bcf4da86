r"""The per-scene quantities of a sweep, one table row per scene.

Every row has the same columns, whichever path computed it (the compiled batched closed
form or :func:`lumped.simulate` per scene); they agree to round-off on the scenes both
cover (tested).

``status``, ``message``
    ``"success"`` and ``""``, or the :class:`~lumped.Status` value of a run that
    stopped early and what stopped it. ``"inconsistent"``: no consistent initial state
    (an initial force breaks its law); ``"error"``: any other exception of the run, its
    type and text in ``message``. (A method that raises ``FloatingPointError`` instead of
    returning its steps so far gives ``"non_finite"`` with the initial state.) The
    numbers of such a row are those up to the last good step (the initial state if there
    was none) -- never NaN.
``method``, ``steps``, ``t_reached``
    The method that ran, the steps completed, ``steps * dt`` (an adaptive method: its
    accepted steps, ``stats["steps"]``, and the time of its last sample).
``x_end.<node>``, ``v_end.<node>``
    The state at the last good step.
``at_rest``, ``rest_position.<node>``
    The system is at rest at the end when the run succeeded and every node velocity is
    exactly zero (the closed form and the generic solvers give ``v = 0`` exactly while
    stuck). Then
    ``rest_position.<node>`` is the final displacement; otherwise it is missing
    (``<NA>`` in the DataFrame, an empty CSV cell).
``stick_time``
    ``dt`` times the number of steps ``n >= 1`` at rest (all ``v_n == 0``).
``stick_slip_cycles``
    The number of slip-to-stick transitions (at rest at ``n``, not at ``n - 1``).
``events``
    The number of steps at which the branch changes: the pattern of
    ``sgn(v_node)`` (stick 0, slip +1 or -1) differs from the previous sample's.
``dissipated_energy``
    The work done on the dashpot-like elements, ``sum_n dt F_e,n qdot_e,n`` over the
    steps (right-endpoint rule, the quadrature that matches a BDF1 step), where
    ``qdot_e = v_b - v_a`` is the elongation rate and ``F_e`` the tension. For a Bingham
    dashpot ``F_e qdot_e >= 0``.

**An adaptive method** (``radau5``) has no steps of one size: its rows are summarised on
the intervals between consecutive samples (its step points, which land on every located
event, or its output grid ``t_n = n dt`` when a ``dt`` is given), read off the method's
own dense output at the 5 Gauss-Legendre points of each interval. An interval is at
rest when every node velocity is exactly zero at all five (the method holds ``v = 0``
exactly on a stuck step); ``stick_time`` is the total length of such intervals,
``stick_slip_cycles`` counts the intervals at rest after one in motion, ``events`` the
intervals whose ``sgn(v_node)`` pattern at the midpoint differs from the previous
interval's, and ``dissipated_energy`` is ``int F_e qdot_e dt`` by the 5-point
Gauss-Legendre rule on each interval (exact on the collocation polynomials between the
events; on the 3-mass chain at ``rtol = 1e-6`` within 1e-8 of the converged value,
where the right-endpoint rule on the same step points is off by 3e-3). There is no
``dt`` column, for either kind of method.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

__all__ = ["QUANTITIES", "RESULT_COLUMNS", "closed_record", "solution_record",
           "failed_record"]

#: Scalar columns every row has (besides the per-node ones).
QUANTITIES = ("stick_time", "stick_slip_cycles", "events", "dissipated_energy")

#: Names of result columns (per-node ones as ``<name>.<node>``): no parameter may take them.
RESULT_COLUMNS = frozenset({"status", "message", "method", "steps", "t_reached", "at_rest",
                            "x_end", "v_end", "rest_position", *QUANTITIES,
                            "steady_omega", "steady_amplitude", "steady_cycles",
                            "energy_per_cycle", "zeta_eq"})


def _record(status: str, message: str, method: str, steps: int, t_reached: float,
            nodes: Sequence[str], x: Sequence[float], v: Sequence[float],
            stick_time: float, cycles: int, events: int, work: float) -> dict[str, Any]:
    rec: dict[str, Any] = {"status": status, "message": message, "method": method,
                           "steps": int(steps), "t_reached": float(t_reached)}
    at_rest = status == "success" and all(vi == 0.0 for vi in v)
    for name, xi, vi in zip(nodes, x, v, strict=True):
        rec[f"x_end.{name}"] = float(xi)
        rec[f"v_end.{name}"] = float(vi)
    rec["at_rest"] = bool(at_rest)
    for name, xi in zip(nodes, x, strict=True):
        rec[f"rest_position.{name}"] = float(xi) if at_rest else None
    rec["stick_time"] = float(stick_time)
    rec["stick_slip_cycles"] = int(cycles)
    rec["events"] = int(events)
    rec["dissipated_energy"] = float(work)
    return rec


def closed_record(out: np.ndarray, n: int, dt: float, method: str, node: str) -> dict[str, Any]:
    """A row from one line of the compiled summary (``closed_form_jit.SUMMARY_FIELDS``)."""
    x, v, done, stick, cycles, events, work, _ = (float(u) for u in out)
    done_i = int(done)
    status, message = "success", ""
    if done_i < n:
        status = "non_finite"
        message = (f"non-finite force or state at step {done_i + 1} "
                   f"(t = {(done_i + 1) * dt!r}); values are those of step {done_i}")
    return _record(status, message, method, done_i, done_i * dt, (node,), (x,), (v,),
                   int(stick) * dt, int(cycles), int(events), work)


def solution_record(sol: Any, scene: Any, dt: float | None) -> dict[str, Any]:
    """A row from a :class:`~lumped.Solution` of ``scene``.

    A fixed-step method's run (``sol.method`` in
    :data:`lumped.solvers.registry.FIXED_STEP_METHODS`) is summarised on its steps of
    ``dt``; an adaptive method's run (``radau5``, with or without an output grid ``dt``)
    on the intervals between its samples, from its dense output (see the module notes).
    """
    from lumped.post.columns import x_col
    from lumped.solvers.registry import FIXED_STEP_METHODS

    nodes = scene.node_names
    data = sol.data
    x_end = data[-1, [x_col(i) for i in range(len(nodes))]]
    status = sol.status.value if hasattr(sol.status, "value") else str(sol.status)
    if sol.method in FIXED_STEP_METHODS:
        if dt is None:
            raise ValueError(f"`dt` is required for a run of the fixed-step method "
                             f"{sol.method!r}, got None")
        steps, t_reached, v_end, (stick, cycles, events, work) = (
            len(data) - 1, (len(data) - 1) * dt, *_on_steps(sol, scene, dt))
    else:
        steps = int(sol.stats.get("steps", len(data) - 1))
        t_reached = float(data[-1, 0])
        v_end, (stick, cycles, events, work) = _on_intervals(sol, scene)
    return _record(status, sol.message, sol.method, steps, t_reached, nodes, x_end, v_end,
                   stick, cycles, events, work)


def _on_steps(sol: Any, scene: Any, dt: float) -> tuple[np.ndarray, tuple]:
    """``v_end`` and ``(stick_time, cycles, events, work)`` of a fixed-step run."""
    from lumped.post.columns import F_col, v_col, velocities

    data = sol.data
    V = data[:, [v_col(i) for i in range(len(scene.nodes))]]
    rest = np.all(V == 0.0, axis=1)
    pattern = np.sign(V)
    changed = np.any(pattern[1:] != pattern[:-1], axis=1)
    work = 0.0
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot":
            continue
        rate = velocities(scene, data, e)
        work += float(np.sum(dt * data[1:, F_col(scene, e)] * rate[1:]))
    return V[-1], (int(np.count_nonzero(rest[1:])) * dt,
                   int(np.count_nonzero(rest[1:] & ~rest[:-1])),
                   int(np.count_nonzero(changed)), work)


#: Gauss-Legendre nodes and weights on ``[-1, 1]`` for an adaptive run's intervals (odd:
#: the middle node is the interval's midpoint; exact for polynomials of degree 9).
_GAUSS = np.polynomial.legendre.leggauss(5)


def _on_intervals(sol: Any, scene: Any) -> tuple[np.ndarray, tuple]:
    """``v_end`` and ``(stick_time, cycles, events, work)`` of an adaptive run, from the
    method's dense output on the intervals between its samples (those of positive
    length: an impact's two samples at one time are no interval)."""
    from lumped.post.columns import F_col, v_col, velocities

    data = sol.data
    cols = [v_col(i) for i in range(len(scene.nodes))]
    t = data[:, 0]
    h = np.diff(t)
    keep = h > 0.0
    h, t0 = h[keep], t[:-1][keep]
    if not len(h):
        return data[-1, cols], (0.0, 0, 0, 0.0)
    nodes, weights = _GAUSS
    k = len(nodes)
    rows = sol.sol((t0[:, None] + 0.5 * h[:, None] * (nodes[None, :] + 1.0)).ravel())
    V = rows[:, cols].reshape(len(h), k, len(cols))
    rest = np.all(V == 0.0, axis=(1, 2))  # the motion is held on the whole interval
    pattern = np.sign(V[:, k // 2, :])  # the branch pattern at the interval's midpoint
    changed = np.any(pattern[1:] != pattern[:-1], axis=1)
    work = 0.0
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot":
            continue
        power = (rows[:, F_col(scene, e)] * velocities(scene, rows, e)).reshape(len(h), k)
        work += float(np.sum(0.5 * h * (power @ weights)))
    return data[-1, cols], (float(np.sum(h[rest])),
                            int(np.count_nonzero(rest[1:] & ~rest[:-1])),
                            int(np.count_nonzero(changed)), work)


def failed_record(scene: Any, method: str, dt: float | None, status: str, message: str
                  ) -> dict[str, Any]:
    """A row for a scene whose run produced no step: the initial state, and why (``dt``
    is unused: no step was taken; ``None`` for an adaptive method)."""
    nodes = scene.node_names
    x = [node.x0 for node in scene.nodes]
    v = [getattr(node, "v0", 0.0) for node in scene.nodes]
    return _record(status, message, method, 0, 0.0, nodes, x, v, 0.0, 0, 0, 0.0)
