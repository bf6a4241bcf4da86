r"""Kinks of the force split among locks in parallel, located inside a ``radau5`` step.

Where locked elements act in parallel (a stuck Coulomb element on a cycle of stuck
dashpots, a taut string beside a stuck dashpot), the motion is determinate and their
forces are not; the stage solve picks the split of least weighted norm and holds a force
that would leave the interval ``[lo, hi]`` its lock admits at that interval's end
(:meth:`lumped.solvers.radau.stage.StageSystem.solve`). The split is then continuous but not
smooth in time: it has a kink where the free (unheld) split reaches a bound, and another
where it comes back inside. The motion does not see these kinks (the held forces do not
act on a mass), the error estimate does not either, but the force's dense output does:
the cubic through a step's held and unheld stage values overshoots the bound between its
nodes (a Coulomb element's share read 1.2e-4 above its yield force, 8e-4 of it, at
``rtol`` 3.9e-5, where the split sat at the bound from a kink 14 ms before the step's
end).

:func:`split_kink` finds such a step and where to end it instead: the first ``s`` at
which the free split's cubic, through the step's start and its stage values before any
was held, crosses the bound (``hi`` or ``lo``) the other way from the start (leaving the
interval from inside; coming back from a held start). The driver then retries the step
to end there, so that no step's polynomial spans a kink.
"""

from __future__ import annotations

from collections.abc import Mapping

from .crossing_root import collocation_at_py, illinois

__all__ = ["split_kink"]

#: Points in ``(0, 1]`` where a step's force cubic is read against its interval.
_READ = tuple(k / 32.0 for k in range(1, 33))

#: A force within this fraction of its interval's half-width from an end is held there
#: (the stage solve holds it ``1e-6`` of the half-width inside).
_AT_END = 2e-6


def split_kink(held: Mapping[int, tuple[tuple[float, ...], tuple[float, ...]]],
               cones: Mapping[int, tuple[float, float, float, float]], tol: float
               ) -> float | None:
    r"""Where a step whose held split overshoots its interval should end, or None.

    Parameters
    ----------
    held : mapping
        ``e -> (F_held, F_free)``: element ``e``'s force at the nodes ``s = 0, c_1, c_2,
        1`` of the step as solved (some stage values held at a bound), and with the stage
        values of the free split (the first pass, nothing held); ``F_held[0] ==
        F_free[0]``, the force at the step's start.
    cones : mapping
        ``e -> (centre, half-width, lo, hi)``, :func:`lumped.solvers.modes.lock_events.lock_cones`.
    tol : float
        Overshoot allowed (force units): the method's tolerance on forces.

    Returns
    -------
    float or None
        ``s`` in ``(0, 1)``: the earliest kink of the free split among the elements whose
        held cubic leaves ``[lo - tol, hi + tol]`` somewhere in the step; ``0.5`` for such
        an element whose free cubic shows no kink (its share moved by another's hold);
        None when no cubic overshoots, or when a stage value is itself beyond its
        interval (no split held the locks: one breaks, an event that the guards locate).
    """
    s_best: float | None = None
    for e, (F_held, _) in held.items():
        _, _, lo, hi = cones[e]
        if any(f > hi + tol or f < lo - tol for f in F_held[1:]):
            return None  # a stage beyond its interval: the locks break (a guard's event)
    for e, (F_held, F_free) in held.items():
        _, w, lo, hi = cones[e]
        if not any(collocation_at_py(s, *F_held) > hi + tol
                   or collocation_at_py(s, *F_held) < lo - tol for s in _READ):
            continue
        s = _kink_of(F_free, lo, hi, _AT_END * w)
        s = 0.5 if s is None or not 0.0 < s < 1.0 else s
        s_best = s if s_best is None else min(s_best, s)
    return s_best


def _kink_of(F_free: tuple[float, ...], lo: float, hi: float, margin: float
             ) -> float | None:
    """The kink of one free share along the step (see :func:`split_kink`); ``margin``:
    a start this close to a bound is held there."""
    start = F_free[0]
    if start >= hi - margin:  # held at hi: the kink where it comes back below
        return _first_sign_change(lambda s: collocation_at_py(s, *F_free) - (hi - margin))
    if start <= lo + margin:
        return _first_sign_change(lambda s: (lo + margin) - collocation_at_py(s, *F_free))
    # inside: the kink where the free split reaches either end
    return _first_sign_change(lambda s: min(hi - collocation_at_py(s, *F_free),
                                            collocation_at_py(s, *F_free) - lo))


def _first_sign_change(g) -> float | None:
    """The first root of ``g`` on ``(0, 1]`` where it turns from ``>= 0`` to ``< 0``,
    bracketed on :data:`_READ` (from ``s = 0``) and refined by Illinois; None if ``g``
    stays ``>= 0`` or starts ``< 0`` and never turns."""
    a, ga = 0.0, g(0.0)
    for s in _READ:
        gs = g(s)
        if ga >= 0.0 > gs:
            return illinois(g, a, s, ga, gs) if ga > 0.0 else a
        a, ga = s, gs
    return None
