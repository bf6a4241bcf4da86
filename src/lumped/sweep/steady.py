r"""The steady amplitude of one scene of a sweep under periodic forcing (amplitude against
frequency curves, ``simulate_many(..., steady_amplitude=NAME)``).

The forcing frequency ``omega`` is the one sine of the scene: a
:class:`~lumped.scene.SineBurst` force on a node or a sine ground motion; a scene with
none, or with two different frequencies, is refused (its row says why). Cycles of period
``T = 2 pi / omega`` start at ``t = 0``.

* For an **element** (or several in parallel, ``"spring+slider"``),
  :func:`lumped.post.loops.cycles` reports its steady cycles: ``steady_amplitude`` is
  the mean ``u_0 = (q_max - q_min) / 2`` of its elongation, ``energy_per_cycle`` the
  mean ``oint F dq`` (J) and ``zeta_eq`` the equivalent damping ratio.
* For a **node**, ``u_0`` is half the peak-to-peak relative displacement ``x_i`` over a
  cycle (the samples inside it and its ends from the dense output); the steady cycles
  are those from which on consecutive amplitudes agree to ``rtol`` (the rule of
  :mod:`lumped.post.loops` without its energy test); ``energy_per_cycle`` and
  ``zeta_eq`` are empty.

``steady_cycles`` counts the steady cycles; with none (still in the transient at
``t_end``) the amplitude is empty (``<NA>``) rather than a transient value.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["STEADY_COLUMNS", "steady_record", "forcing_omega", "empty_steady"]

#: The columns a sweep with ``steady_amplitude`` adds.
STEADY_COLUMNS = ("steady_omega", "steady_amplitude", "steady_cycles", "energy_per_cycle",
                  "zeta_eq")


def forcing_omega(scene: Any) -> float:
    """The one circular frequency of the scene's sine forcing and ground motion."""
    from lumped.scene import SineBurst

    found = {float(f.omega) for f in getattr(scene, "applied_forcing", scene.forcing)
             if isinstance(f, SineBurst) and f.omega != 0.0}
    gm = getattr(scene, "ground_motion", None)
    if gm is not None and gm.omega is not None:
        found.add(float(gm.omega))
    if len(found) != 1:
        raise ValueError("`steady_amplitude` needs exactly one sine frequency in the scene "
                         f"(a sine force or a sine ground motion), found {sorted(found)}")
    return found.pop()


def empty_steady(omega: float | None = None) -> dict[str, Any]:
    """The columns of a row without a steady state."""
    return {"steady_omega": omega, "steady_amplitude": None, "steady_cycles": 0,
            "energy_per_cycle": None, "zeta_eq": None}


def steady_record(sol: Any, scene: Any, target: str, rtol: float = 1e-2) -> dict[str, Any]:
    """The :data:`STEADY_COLUMNS` of one solution (see the module notes)."""
    omega = forcing_omega(scene)
    names = target.split("+")
    if all(n in scene.element_index for n in names):
        from lumped.post.loops import cycles

        rep = cycles(sol, names if len(names) > 1 else target, omega=omega, rtol=rtol)
        if rep.steady_from is None:
            return empty_steady(omega)
        return {"steady_omega": omega, "steady_amplitude": rep.amplitude,
                "steady_cycles": len(rep.steady), "energy_per_cycle": rep.energy,
                "zeta_eq": rep.zeta_eq}
    if target not in scene.node_index:
        raise ValueError(f"`steady_amplitude` must name an element or a node of the scene "
                         f"(elements: {', '.join(scene.element_names)}; nodes: "
                         f"{', '.join(scene.node_names)}), got {target!r}")
    col = 1 + 2 * scene.node_index[target]
    T = 2.0 * math.pi / omega
    t = sol.t
    last = float(t[-1])
    n = math.floor(last / T * (1.0 + 1e-12))
    amps = []
    for k in range(n):
        a, b = k * T, min((k + 1) * T, last)
        inside = sol.data[np.searchsorted(t, a, side="right"):np.searchsorted(t, b), col]
        ends = sol.sol(np.array([a, b]))[:, col]
        x = np.concatenate([inside, ends])
        amps.append(0.5 * float(x.max() - x.min()))
    j = len(amps)
    while j > 1 and abs(amps[j - 1] - amps[j - 2]) <= rtol * max(amps[j - 1], amps[j - 2]):
        j -= 1
    if j >= len(amps):
        return empty_steady(omega)
    steady = amps[j - 1:]
    return {"steady_omega": omega, "steady_amplitude": float(np.mean(steady)),
            "steady_cycles": len(steady), "energy_per_cycle": None, "zeta_eq": None}
