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
    The method that ran, the steps completed, ``steps * dt``.
``x_end.<node>``, ``v_end.<node>``
    The state at the last good step.
``at_rest``, ``rest_position.<node>``
    The system is at rest at the end when the run succeeded and every node velocity is
    exactly zero (the closed form and the generic solver give ``v = 0`` exactly while
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


def _record(status: str, message: str, method: str, steps: int, dt: float,
            nodes: Sequence[str], x: Sequence[float], v: Sequence[float],
            stick_steps: int, cycles: int, events: int, work: float) -> dict[str, Any]:
    rec: dict[str, Any] = {"status": status, "message": message, "method": method,
                           "steps": int(steps), "t_reached": steps * dt}
    at_rest = status == "success" and all(vi == 0.0 for vi in v)
    for name, xi, vi in zip(nodes, x, v, strict=True):
        rec[f"x_end.{name}"] = float(xi)
        rec[f"v_end.{name}"] = float(vi)
    rec["at_rest"] = bool(at_rest)
    for name, xi in zip(nodes, x, strict=True):
        rec[f"rest_position.{name}"] = float(xi) if at_rest else None
    rec["stick_time"] = stick_steps * dt
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
    return _record(status, message, method, done_i, dt, (node,), (x,), (v,),
                   int(stick), int(cycles), int(events), work)


def solution_record(sol: Any, scene: Any, dt: float) -> dict[str, Any]:
    """A row from a :class:`~lumped.Solution` of ``scene`` on steps of ``dt``."""
    from lumped.post.columns import F_col, v_col, velocities, x_col

    nodes = scene.node_names
    data = sol.data
    V = data[:, [v_col(i) for i in range(len(nodes))]]
    X = data[:, [x_col(i) for i in range(len(nodes))]]
    rest = np.all(V == 0.0, axis=1)
    pattern = np.sign(V)
    changed = np.any(pattern[1:] != pattern[:-1], axis=1)
    work = 0.0
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot":
            continue
        rate = velocities(scene, data, e)
        work += float(np.sum(dt * data[1:, F_col(scene, e)] * rate[1:]))
    status = sol.status.value if hasattr(sol.status, "value") else str(sol.status)
    return _record(status, sol.message, sol.method, len(data) - 1, dt, nodes, X[-1], V[-1],
                   int(np.count_nonzero(rest[1:])),
                   int(np.count_nonzero(rest[1:] & ~rest[:-1])),
                   int(np.count_nonzero(changed)), work)


def failed_record(scene: Any, method: str, dt: float, status: str, message: str
                  ) -> dict[str, Any]:
    """A row for a scene whose run produced no step: the initial state, and why."""
    nodes = scene.node_names
    x = [node.x0 for node in scene.nodes]
    v = [getattr(node, "v0", 0.0) for node in scene.nodes]
    return _record(status, message, method, 0, dt, nodes, x, v, 0, 0, 0, 0.0)
