"""Whether the state at a guard stays as it is when the mode choice keeps the mode there
(:meth:`lumped.solvers.eventdriven.mode_state.ModeState.change_mode`)."""

from __future__ import annotations

from .mode_parts import laws_hold

__all__ = ["state_stays"]

#: A kept choice at a guard at most this many accepted steps after the last one keeps the
#: state at ``t`` (:func:`state_stays`).
_AGAIN = 1


def state_stays(ms, t: float, cause: str, new: list[int], impact: bool, x: list[float],
                v: list[float], F: list[float]) -> bool:
    """Whether the junction velocities and forces at ``t`` stay as they are after the
    mode ``new`` is chosen, rather than the deciding probe's (``ms``: the run's
    :class:`~lumped.solvers.eventdriven.mode_state.ModeState`, whose ``kept_at_step`` it
    sets): when the full laws keep the mode at a guard (a tangency; ``impact``: an
    impact was applied) *again*, within :data:`_AGAIN` accepted steps of the last such
    choice (the run landed on the guard at once after taking the probe's state), and
    every law of that mode holds at ``(x, v, F)`` (the end of the step on it: a
    consistent state at ``t``). A first kept choice takes the probe's state, which
    carries a split held at its bound on (a held share of a stuck cycle: its break-out
    time to 1e-10 at rtol 4e-5, against 5e-6 from the state at ``t``).

    A junction hung on a mass by a stuck Coulomb element took the state of a probe
    ``1e-3`` s long (a rate ``0.04`` to ``0.23`` off the mass's), crossed its guard at
    ``t`` again, and crept on by ``3e-14`` s a step until bridged (issue 29)."""
    kept = cause == "guard" and new == ms.modes and not impact
    steps = ms.stats["steps"]
    again = kept and steps - ms.kept_at_step <= _AGAIN
    if kept:
        ms.kept_at_step = steps
    return again and laws_hold(ms.kernels, ms.scene.elongations(x, v), F)
