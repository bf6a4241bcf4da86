r"""``radau5``'s work budget: ``max_steps`` bounds the work of a run (not its wall time), so
that a run that cannot make progress ends with a clear stop.

The work is every step the run tries: accepted, rejected (error test, Newton failure, a
kink of the force split, the defect after an event), redone to land on an event, and the
backward-Euler steps of its bridges (:mod:`lumped.solvers.eventdriven.bridge`). Two tests
on it, at every pass of the driver's loop (:class:`lumped.solvers.eventdriven.run.
Radau5Run`), which is where the compiled loop returns to:

* the budget is spent: ``work >= max_steps``;
* the pace: over the last :func:`window` tries of ``radau5`` itself (at least
  :data:`PACE_WINDOW`, or ``max_steps / 100``; the steps of bridges, which a bridge sizes
  and bounds, not counted) ``t`` moved by ``dt_w``; when the time left at that pace needs
  more tries than the budget has left, ``(t_end - t) / dt_w * window > max_steps - work``, the
  run stops at once rather than spend the rest of it (a loaded network whose Newton
  failed at every step longer than 1e-9 s moved 3.2e-6 s in 10 000 tries with 0.7 s to
  go, 2.2e9 tries; a budget of 1e6 tries would take 2 hours of its Python loop).

* stuck: over the last :data:`STUCK_WINDOW` tries of ``radau5`` itself, at least half
  of them rejected, the time left at that pace needs more than :data:`STUCK_MARGIN`
  times the tries left: a run whose stage solves fail at every step size (a junction's
  velocity that the stage Newton could not converge below its round-off crept from
  ``t = 0.35387`` with 15 000 rejected tries of its 20 000, at up to tens of ms each,
  before the pace test's window of 10 000 ended twice, issue 29) stops within two such
  windows (the compiled loop's: when it returns). A slow phase of accepted steps (an
  accumulation of events) is left to the pace test.

All three stop the run with :attr:`~lumped.solvers.status.Status.MAX_ITERS` (SciML's return
code for a step budget; a ``SolverError`` with ``throw=True``), never bridged, with the
time reached, the tries of each kind and how to raise the budget.

A pass that chooses the mode again at a guard and keeps it may cost far more than a try
(a full mode choice, thousands of residual evaluations): :meth:`WorkBudget.kept` counts
such choices at (nearly) one time, at the stuck test's pace, and the driver stops the run
after a few (``STEP_TOO_SMALL``, bridged; ``_KEPT_AT_T`` in
:mod:`lumped.solvers.eventdriven.run`).

The compiled loop (:mod:`lumped.solvers.eventdriven.loop_jit`) counts its tries, accepted
and rejected, and returns at a cap: :meth:`WorkBudget.compiled_cap` hands it the tries it
may take before it returns, the budget left, at most a window of the stuck test
(:data:`STUCK_WINDOW`) or of the pace test, so that the tests above see every try and
run at least once a window (a run whose stage solves kept failing inside the compiled
loop, which capped accepted steps only, spent 14 773 tries of ``max_steps = 5000``, and
the stuck test waited for it to return, issue 29).
"""

from __future__ import annotations

import math

from ..status import Status

__all__ = ["KEPT_CHOICES", "PACE_WINDOW", "WorkBudget", "window"]

#: Tries in the shortest window of the pace test.
PACE_WINDOW = 10_000

#: Tries in a window of the stuck test (mostly rejected tries at a hopeless pace).
STUCK_WINDOW = 1_000

#: How far beyond the tries left the stuck test's pace must need to stop the run.
STUCK_MARGIN = 100

#: The most kept choices a series of them may need at its pace to reach the end before
#: it is a stall, whatever the budget (:meth:`WorkBudget.kept`).
KEPT_CHOICES = 100_000


def window(max_steps: int) -> int:
    """Tries per window of the pace test: :data:`PACE_WINDOW`, or ``max_steps / 100`` if
    more (a budget below :data:`PACE_WINDOW` is spent before a window ends: then the
    pace test never stops the run)."""
    return max(PACE_WINDOW, max_steps // 100)


class WorkBudget:
    """The work budget of one run: ``max_steps`` tries over ``[0, t_final]``."""

    def __init__(self, max_steps: int, t_final: float) -> None:
        self.max_steps, self.t_final = max_steps, t_final
        self.window = window(max_steps)
        #: passes of the Python loop that neither accepted nor rejected a step (a step
        #: redone shorter to land on an event, a mode chosen again at ``t``)
        self.redone = 0
        self.mark = (0, 0.0)  # (tries but bridges', t) at the start of the current window
        self.stuck = (0, 0, 0.0)  # (tries but bridges', rejected, t): the stuck window's
        self.kept_at, self.kept_count = math.nan, 0  # a series of kept choices (kept())

    def kept(self, t: float, stats: dict) -> int:
        """Count a choice of the mode at ``t`` that kept it; the choices in its series.

        A series of kept choices starts at ``t_k`` and goes on while the ``c`` choices
        after its first moved ``t`` so little that the time left at their pace needs more
        than :data:`STUCK_MARGIN` times the tries left, or more than
        :data:`KEPT_CHOICES` choices, ``(t - t_k) * min(STUCK_MARGIN * left,
        KEPT_CHOICES) < c * (t_final - t)`` (every kept choice costs a pass of the loop
        and a full mode choice): at one ``t``, or crept on by an accepted step as short as
        ``5e-12 s`` after each (a junction's Herschel-Bulkley n = 0.3 dashpot whose guard
        read crossed at ``t = 0.13772`` after every step, a full mode choice of 18 000
        residual evaluations each, 2 s, that the stuck test saw once per 250 of them,
        issue 29). The cap holds whatever ``max_steps`` is: two Coulomb dashpots in
        parallel kept slipping at rate 0 where they reverse, a choice of 0.3 s every
        ``1.5e-8`` s with 0.17 s to go (1.2e7 choices, which the default budget's
        ``1e8`` admitted: 40 days; seed 25171 of the property of both loops)."""
        left = max(1, self.max_steps - self.tries(stats))
        need = min(STUCK_MARGIN * left, KEPT_CHOICES)
        if (t - self.kept_at) * need < self.kept_count * (self.t_final - t):
            self.kept_count += 1
        else:
            self.kept_at, self.kept_count = t, 1
        return self.kept_count

    def tries(self, stats: dict) -> int:
        """The steps tried so far (see the module notes)."""
        return (stats["steps"] + stats["rejected"] + stats.get("bridged_steps", 0)
                + self.redone)

    def compiled_cap(self, stats: dict) -> int:
        """The ``max_steps`` of the compiled loop: the count of accepted plus rejected
        steps it may reach before it returns (the budget left, at most a window of the
        stuck test or the pace test, at least one try)."""
        left = self.max_steps - self.tries(stats)
        return (stats["steps"] + stats["rejected"]
                + max(1, min(left, self.window, STUCK_WINDOW)))

    def check(self, t: float, stats: dict) -> tuple[Status, str] | None:
        """``(Status.MAX_ITERS, message)`` when the budget is spent, or when the run's pace
        over the last window cannot reach ``t_final`` within what is left of it."""
        tries = self.tries(stats)
        if tries >= self.max_steps:
            return Status.MAX_ITERS, (
                f"radau5 stopped at t = {t!r} of t_end = {self.t_final!r}: its work budget "
                f"max_steps = {self.max_steps} is spent ({self._count(stats)}); give a "
                "larger max_steps to go on")
        # the pace of radau5's own tries (a bridge's steps are sized by the bridge,
        # :mod:`lumped.solvers.eventdriven.bridge`, and its count bounded there)
        own = tries - stats.get("bridged_steps", 0)
        left = self.max_steps - tries
        got = self._stuck(t, own, stats["rejected"], left, stats)
        own0, t0 = self.mark
        if got is not None or own - own0 < self.window:
            return got
        moved, n = t - t0, own - own0
        if moved * left < n * (self.t_final - t):
            need = (f"about {n * (self.t_final - t) / moved:.2g} tries" if moved > 0
                    else "tries without end")
            return Status.MAX_ITERS, (
                f"radau5 stopped at t = {t!r} of t_end = {self.t_final!r}: its work budget "
                f"cannot reach t_end: its last {n} tries moved t by {moved!r} "
                f"s, at which pace the {self.t_final - t!r} s left need {need}, more than "
                f"the {left} left of max_steps = {self.max_steps} ({self._count(stats)}); "
                "give a larger max_steps to go on")
        self.mark = (own, t)
        return None

    def _stuck(self, t: float, own: int, rejected: int, left: int, stats: dict
               ) -> tuple[Status, str] | None:
        """The stuck test (see the module notes) at the end of a window of
        :data:`STUCK_WINDOW` tries: at least half of ``n`` tries rejected and ``t`` moved
        by ``dt_w`` with ``(t_final - t) / dt_w * n > STUCK_MARGIN * left``."""
        own0, rej0, t0 = self.stuck
        n = own - own0
        if n < STUCK_WINDOW:
            return None
        self.stuck = (own, rejected, t)
        moved, r = t - t0, rejected - rej0
        if 2 * r < n or moved * STUCK_MARGIN * left >= n * (self.t_final - t):
            return None
        return Status.MAX_ITERS, (
            f"radau5 stopped at t = {t!r} of t_end = {self.t_final!r}: it is stuck: its "
            f"last {n} tries, {r} of them rejected, moved t by {moved!r} s, at which pace "
            f"the {self.t_final - t!r} s left need more than {STUCK_MARGIN} times the "
            f"{left} tries left of max_steps = {self.max_steps} ({self._count(stats)})")

    def _count(self, stats: dict) -> str:
        bridged = stats.get("bridged_steps", 0)
        return (f"{stats['steps']} accepted steps, {stats['rejected']} rejected, "
                f"{self.redone} other passes (landings on events, modes chosen again)"
                + (f", {bridged} backward-Euler steps of bridges" if bridged else ""))
