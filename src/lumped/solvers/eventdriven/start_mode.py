r"""The mode of a ``radau5`` run at ``t = 0``, chosen again when the start stops a mass.

The start's mode probe (:meth:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode`,
cause ``"start"``) is an implicit step of ``h_p = 1e-9`` of the run from the consistent
initial state. A mass released at a velocity so small that the load stops it within the
probe (``|v_0| < h_p |a|``) is read stopped: the probe of a lock on it ends at rate 0, and
its force is the lock's average over the probe, which carries the momentum the lock
takes away, ``m v_0 / h_p``, beside the load. That force can lie within the lock's
interval where the load alone does not: one mass (``m = 1``) on a spring (``k x_0 =
1.5``) and a Bingham dashpot (``tau = 1``), released at ``v_0 = 1e-9`` against the
spring, read ``F = 1.5 - m v_0 / h_p = 0.5`` on the stuck branch over a probe of
``5e-10`` s. The start then put the mass at rest in row 0 (``v = 0``, the force on the
edge of the set at rest, :func:`~lumped.solvers.implicit.initial_slip.start_at_known_rates`)
on the stuck branch, a state the load does not hold (the balance's force is ``-1.5``),
and the held interval from it (:func:`~lumped.solvers.modes.stuck.hold_interval`) kept the
mass at ``x_0`` for the whole run: a draw of the tight-tolerance property (seed 25037 of
the ``long`` profile, shrunk) stayed at ``x = 0.5`` where the exact mass slips to
``0.4942``.

The exact mass stops after ``|v_0 / a| < h_p`` (``4e-10`` s there) and goes on from rest,
so the mode after it is the one the full laws choose from that state: :func:`start_mode`
chooses again, once, from row 0 when the first choice stopped a mass that moved. A mass
that sticks (the load within the lock's interval) is chosen stuck again; one the load
breaks out slips from rest, as a mass released at ``v_0 = 0``.
"""

from __future__ import annotations

__all__ = ["start_mode"]


def start_mode(ms, h_probe: float, x: list[float], v: list[float], F: list[float]) -> str:
    """The mode at ``t = 0`` from the consistent initial state ``(x, v, F)`` (changed in
    place to row 0) by ``ms`` (a :class:`~lumped.solvers.eventdriven.mode_state.ModeState`)
    with probes of ``h_probe``: chosen again from row 0 when the first choice stopped a
    mass (see the module notes). ``""``, or why no mode is consistent."""
    moving = [i for i, vi in enumerate(v) if vi != 0.0 and ms.is_mass[i]]
    msg = ms.change_mode(0.0, h_probe, "start", x, v, F)
    if not msg and any(v[i] == 0.0 for i in moving):
        msg = ms.change_mode(0.0, h_probe, "start", x, v, F)
    return msg
