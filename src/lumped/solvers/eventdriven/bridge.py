r"""``radau5``'s bridge over a stop: backward Euler from the state where the adaptive
method could not go on.

The event-driven driver of ``radau5`` (:mod:`lumped.solvers.eventdriven.run`) stops when it
finds no way on: its step falls below the floor, events accumulate at one time (numerical
chatter, a Zeno-like point), or no mode of the full laws continues the motion. Backward
Euler across the same laws (``bdf1``, :func:`lumped.solvers.bdf.fixed_step.run_bdf`) is
Moreau's time-stepping with restitution 0: it needs no events, takes impacts, locks and
indeterminate forces in its stride, never creates energy, and converges as its step
shrinks. This is the classical pairing of event-driven and time-stepping schemes for
nonsmooth dynamics (Acary and Brogliato 2008, ch. 8): the event-driven scheme where it
goes, the time-stepping scheme over the points where it does not.

A bridge starts at the last accepted state ``(t, x, v, F)`` of the driver, takes ``n``
backward-Euler steps of size ``delta``,

.. math::

    \delta = \sqrt{\mathrm{rtol}}\; h_{\max}, \qquad n = 32 \cdot 2^k

(``h_max`` the longest step the run accepted, ``k`` the bridges already taken; at most
:data:`MAX_STEPS` steps, ending at the run's end at the latest), and the driver goes on
from its end state with the mode the full laws choose there. Backward Euler is first
order, so the error a bridge adds is ``O(delta)`` and falls with the tolerance (as
``sqrt(rtol)``). Inside a bridge the dense output is linear between its steps, impacts
are recorded as events, switches are not located (the driver records the change of mode
across the bridge at its end), and the intervals of forces that are not unique are
kept. A bridge whose backward Euler fails is tried again over the same span with other
step sizes (:data:`RETRY_SCALES`). A run bridges at most :data:`MAX_BRIDGES` stops; the
run's message names each bridge, its interval and the stop it bridged.
"""

from __future__ import annotations

import math

from ..bdf.fixed_step import RunResult, run_bdf
from ..radau.rows import row_of
from ..radau.tableau import C
from ..status import SolverError

__all__ = ["BRIDGE_STEPS", "BRIDGE_WORK", "BRIDGE_WORK_FLOOR", "MAX_BRIDGES", "MAX_STEPS",
           "RETRY_SCALES", "RUN_BRIDGE_WORK", "bridge_steps", "run_bridge", "linear_stages",
           "take_bridge"]

#: Backward-Euler steps of the first bridge of a run (doubled for each further one).
BRIDGE_STEPS = 32
#: Steps of one bridge at the most.
MAX_STEPS = 20_000
#: Bridges of one run at the most.
MAX_BRIDGES = 12
#: A bridge's work budget in residual evaluations: ``BRIDGE_WORK`` per step of its first
#: try, at least ``BRIDGE_WORK_FLOOR``, for each of its tries (:func:`take_bridge`).
#: Backward Euler's plain Newton takes 2-20 a step; the bridges of the test suite took at
#: most 12 221 in all (191 a step, a shear-thinning break-away); a loaded 4-node network
#: took 626 025 over 2048 steps of one bridge (77 s), its Newton up to 617 iterations a
#: step, and its bridges doubling in length after it.
BRIDGE_WORK, BRIDGE_WORK_FLOOR = 100, 50_000
#: The bridges of one run together, in residual evaluations at the most (a minute or two
#: of Python at the worst cost seen, ~120 µs an evaluation on 4 nodes; the tries a
#: budget ended count in full): a run that crawls from bridge to bridge ends.
RUN_BRIDGE_WORK = 1_000_000
#: Step sizes a bridge tries in turn, as multiples of its own (the same span), when
#: backward Euler fails at the one before.
RETRY_SCALES = (1.0, 0.1, 4.0)


def bridge_steps(rtol: float, h_max: float, room: float, k: int
                 ) -> tuple[float, int, bool]:
    """``(delta, n, to_end)``: the step and the number of steps of the ``k``-th bridge of
    a run (``k = 0`` first) at the tolerance ``rtol``, ``h_max`` the longest accepted step
    and ``room`` the time left to the run's end; ``to_end`` when the bridge ends the run
    (it ends there at the latest)."""
    delta = math.sqrt(rtol) * h_max
    n = min(BRIDGE_STEPS << min(k, 20), MAX_STEPS)
    if n * delta < room:
        return delta, n, False
    n = max(1, math.ceil(room / delta))
    return room / n, n, True


def run_bridge(scene, t: float, x: list[float], v: list[float], F: list[float],
               delta: float, n: int, options, restitution: float,
               budget: int | None = None) -> RunResult | str:
    """``n`` backward-Euler steps of size ``delta`` from ``(t, x, v, F)``: the run, or why
    it failed (a Newton failure, a fold of a law, a value that is not finite, or more
    residual evaluations than ``budget``, by default ``max(BRIDGE_WORK n,
    BRIDGE_WORK_FLOOR)``)."""
    if budget is None:
        budget = max(BRIDGE_WORK * n, BRIDGE_WORK_FLOOR)
    try:
        run = run_bdf(scene, method="bdf1", dt=delta, n_steps=n, options=options,
                      throw=False, restitution=restitution, start=(t, x, v, F),
                      max_residual_evals=budget)
    except (ArithmeticError, ValueError, SolverError) as err:
        return f"backward Euler failed too: {err}"
    if run.message:
        return f"backward Euler failed too: {run.message}"
    if not all(map(math.isfinite, run.xs + run.vs + run.Fs)):
        return "backward Euler failed too: a value is not finite"
    return run


def linear_stages(y0: list[float], y1: list[float], nodes: tuple[float, ...]
                  ) -> list[list[float]]:
    """The values at the nodes ``c_k`` of the straight line from ``y0`` (``s = 0``) to
    ``y1`` (``s = 1``): stage values whose collocation polynomial is that line, the dense
    output of a backward-Euler step."""
    return [[a + c * (b - a) for a, b in zip(y0, y1, strict=True)] for c in nodes]


def take_bridge(scene, start: tuple, k: int, rtol: float, h_max: float, t_final: float,
                options, restitution: float, dense, rows, events: list, log, stats: dict
                ) -> tuple[float, list[float], list[float], list[float], bool, float] | str:
    """The ``k``-th bridge of a ``radau5`` run (``k = 0`` first) from ``start = (t, x, v,
    F)``: its steps written to the dense output ``dense`` and the rows ``rows``, its
    impacts to ``events``, its intervals of forces that are not unique to ``log``
    (:class:`~lumped.solvers.nonsmooth.locks.IntervalLog`), its steps counted in
    ``stats["bridged_steps"]``, its residual evaluations in ``stats["bridge_work"]``
    (within :data:`RUN_BRIDGE_WORK` for the run). Returns ``(t, x, v, F, to_end,
    delta)`` at its end (``to_end`` when that is ``t_final``; ``delta`` its step), or
    why backward Euler failed too."""
    t0, x, v, F = start
    delta, n, to_end = bridge_steps(rtol, h_max, t_final - t0, k)
    span = n * delta
    used = stats.get("bridge_work", 0)
    run = (f"backward Euler not tried: the run's bridges used their work budget ({used} "
           f"residual evaluations)")
    for scale in RETRY_SCALES:
        budget = min(max(BRIDGE_WORK * n, BRIDGE_WORK_FLOOR), RUN_BRIDGE_WORK - used)
        if budget <= 0:
            break
        # the same span, with steps ``scale`` times as long: backward Euler's Newton can
        # miss a step at one size and not at others, where several dashpots sit at their
        # yield forces at once (a junction's Herschel-Bulkley n = 0.3 dashpot and a
        # Bingham one beside a taut string: steps of 0.1 and 27 times the size went
        # through, 1 and 10 times did not)
        n_s = min(MAX_STEPS, max(1, round(n / scale)))
        run = run_bridge(scene, t0, x, v, F, span / n_s, n_s, options, restitution, budget)
        if not isinstance(run, str):  # (run_bdf copies the start lists)
            delta, n = span / n_s, n_s
            stats["bridge_work"] = used + run.stats["residual_evals"]
            break
        if "work budget" in run:
            used = stats["bridge_work"] = used + budget
    else:
        return run
    if isinstance(run, str):
        return run
    N, E = len(x), len(F)
    y = list(x) + list(v) + list(F)
    for i in range(1, n + 1):
        x = run.xs[i * N:(i + 1) * N]
        v = run.vs[i * N:(i + 1) * N]
        F = run.Fs[i * E:(i + 1) * E]
        t = t_final if (to_end and i == n) else t0 + i * delta
        y_next = x + v + F
        dense.add(t0 + (i - 1) * delta, delta, y, linear_stages(y, y_next, C))
        rows.append(row_of(t, x, v, F))
        y = y_next
    events.extend(run.events)
    log.add_closed(run.indeterminate)
    stats["bridged_steps"] = stats.get("bridged_steps", 0) + n
    return t, x, v, F, to_end, delta
