r"""The impact and lock scenes of issue 11 (the seed paper's Figure 2 element), with the
exact impact motion, for tests, examples and the benchmark.

*Impact.* A mass ``m = 1`` hangs on a spring with an inextensible string in parallel
(``string_spring``, ``k = 1``, ``L = 0.5``), from ``x0 = 0`` with ``v0 = 1``. It moves as
``x = sin t`` until ``x = L`` at ``t = pi/6`` (speed ``sqrt(3)/2``); the string stops it at
once (perfectly inelastic: kinetic energy ``3/8`` lost, ``1/8`` left in the spring); then
``x = 0.5 cos(t - pi/6)``. File: ``examples/impact.toml``.

*Lock.* The same mass and element with a Coulomb element (``tau = 0.2``) in parallel,
pushed from rest by a constant load ``1.0``: it slides until the string is taut (an
impact), then stays at ``x = L``; the string and the friction element share the load in a
way the laws do not fix (indeterminate forces). File: ``examples/lock.toml``.
"""

from __future__ import annotations

import math

import numpy as np

from ..laws import get_law
from ..scene import Element, Mass, Scene
from .methods import steady_loop

__all__ = ["IMPACT_TIME", "IMPACT_SCENES", "impact_scene", "lock_scene", "exact_impact",
           "impact_errors", "impact_markdown"]

#: Time at which the string of :func:`impact_scene` becomes taut.
IMPACT_TIME = math.pi / 6


def impact_scene() -> Scene:
    """The impact scene (see the module notes)."""
    return Scene([Mass("mass", m=1.0, x0=0.0, v0=1.0)],
                 [Element("string", get_law("string_spring").bind(k=1.0, L=0.5),
                          "ground", "mass")])


def lock_scene() -> Scene:
    """The lock scene (see the module notes)."""
    return Scene([Mass("mass", m=1.0, x0=0.0, v0=0.0)],
                 [Element("string", get_law("string_spring").bind(k=1.0, L=0.5),
                          "ground", "mass"),
                  Element("friction", get_law("coulomb").bind(tau=0.2, r=10.0),
                          "ground", "mass")],
                 forces={"mass": 1.0})


def exact_impact(t) -> np.ndarray:
    """Exact displacement of :func:`impact_scene`: ``sin t`` before ``pi/6``, then
    ``0.5 cos(t - pi/6)`` (the string never goes taut again: ``|x| <= 0.5``)."""
    t = np.asarray(t, dtype=float)
    return np.where(t < IMPACT_TIME, np.sin(t), 0.5 * np.cos(t - IMPACT_TIME))


#: name -> (scene factory, exact x(t) or None, final time): for ``lumped bench``.
IMPACT_SCENES = {
    "impact": (impact_scene, exact_impact, 3.0),
    "lock": (lock_scene, None, 3.0),
}


def impact_errors(methods=("bdf1", "bdf2", "auto"), dts=(1e-2, 1e-3, 1e-4),
                  t_end: float = 3.0, timed: bool = False) -> list[dict]:
    """Max error against :func:`exact_impact` per method and step (rows for a table),
    with the largest energy after the impact (``0.125`` exact), the impacts recorded and
    the Newton iterations; with ``timed``, the CPU time in yardstick units
    (:func:`lumped.bench.runner.yardstick`, measured in the same process)."""
    from ..simulate import simulate

    unit = None
    if timed:
        from .timing import measure_unit, time_call

        unit = measure_unit()
    rows = []
    for method in methods:
        for dt in dts:
            fast = steady_loop(method)

            def go(method=method, dt=dt, fast=fast):
                return simulate(impact_scene(), method=method, dt=dt, t_end=t_end,
                                throw=False, **fast)

            if unit is not None:
                sol, cpu, _ = time_call(go)
            else:
                sol, cpu = go(), math.nan
            x, v = sol.x["mass"], sol.v["mass"]
            E = 0.5 * v**2 + 0.5 * x**2
            after = sol.t > IMPACT_TIME + dt
            rows.append({
                "method": sol.method, "dt": dt, "status": sol.status.value,
                "max_error": float(np.abs(x - exact_impact(sol.t)).max()),
                "max_energy_after": float(E[after].max()) if after.any() else math.nan,
                "impacts": len(sol.events),
                "newton_iterations": sol.stats.get("newton_iterations", 0),
                "ratio": cpu / unit if unit is not None else math.nan,
            })
    return rows


def impact_markdown(rows: list[dict]) -> str:
    """The rows of :func:`impact_errors` as a markdown table."""
    out = ["| method | dt | status | max error | error / dt | max E after impact | impacts "
           "| Newton its | time (yardsticks) |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        out.append(f"| {r['method']} | {r['dt']:g} | {r['status']} | {r['max_error']:.2e} | "
                   f"{r['max_error'] / r['dt']:.3g} | {r['max_energy_after']:.6f} | "
                   f"{r['impacts']} | {r['newton_iterations']} | {r['ratio']:.3g} |")
    return "\n".join(out) + "\n"
