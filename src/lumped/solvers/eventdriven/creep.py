"""The creep test of ``radau5``'s loops: a run whose accepted steps stay below a floor, step
after step (landing on a guard again and again, ``t`` moving by ulps), stops there (and
is bridged by backward Euler, :mod:`lumped.solvers.eventdriven.bridge`). The Python loop
(:meth:`lumped.solvers.eventdriven.step.StepPass._accept`) and the compiled loop
(:mod:`lumped.solvers.eventdriven.loop_jit`) make the same test."""

from __future__ import annotations

from ..status import Status
from .setup import step_floor

__all__ = ["CREEP_STEPS", "creep_floor", "creep_stop"]

#: Accepted steps in a row below the step floor after which a run that creeps (landing on a
#: guard again and again, ``t`` moving by ulps) stops (and is bridged). At most 1 in a row
#: in 5400 runs of random networks that did not creep (1800 draws, 3 levels); 200 before.
CREEP_STEPS = 20
#: ... steps shorter than the step floor or than this fraction of the run.
_CREEP_FRACTION = 1e-12


def creep_floor(t: float, t_final: float) -> float:
    """The creep floor of a step from ``t`` in a run to ``t_final``: the step floor
    (:func:`~lumped.solvers.eventdriven.setup.step_floor`), or :data:`_CREEP_FRACTION` of
    the run if more. ``creep_floor(0.0, t_final)`` is its part that does not depend on
    ``t`` (the step floor grows with ``|t|``), which the compiled loop takes
    (:mod:`lumped.solvers.eventdriven.loop_jit`, ``fst[CREEP_FLOOR]``)."""
    return max(step_floor(t, t_final), _CREEP_FRACTION * t_final)


def creep_stop(t: float, creeping: int, floor: float, el) -> tuple[Status, str]:
    """The stop of a run that creeps: ``creeping`` accepted steps in a row, the last
    ending at ``t``, below the creep ``floor``; ``el`` the element whose guard the steps
    landed on (``None``: not landings)."""
    return Status.STEP_TOO_SMALL, (
        f"radau5 stopped at t = {t!r}: {creeping} accepted steps in a row below "
        f"the creep floor {floor!r} (the run creeps"
        + (f", landing again and again on a guard of element {el.name!r} (law "
           f"{el.law_name!r})" if el is not None else "") + ")")
