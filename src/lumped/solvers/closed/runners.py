r"""The runners of the methods for the paper's one scene: ``closed-bdf1`` (Algorithm 1),
``closed-bdf2`` (its BDF2 twin) and ``exact`` (the event-driven reference), each
``runner(scene, settings) -> RawRun`` (see :mod:`lumped.solvers.registry`).

They run only a scene that is exactly one mass with one ``linear_spring`` and one
``bingham`` dashpot, both to ground (:func:`closed_form_oscillator`); the closed form's
``F_s, F_d`` act against ``+x``, so an element drawn from the mass to ground takes the
opposite sign.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...scene import GROUND, Mass, Scene
from ...scene.forcing import zero_forcing
from ...trajectory import Trajectory
from ..implicit.initial_state import consistent_initial_state
from ..status import RawRun, Runner, RunSettings, Status, fixed_step_grid
from .closed_form import BinghamOscillator
from .integrate import integrate

__all__ = ["RUNNERS", "closed_form_oscillator"]


def closed_form_oscillator(scene: Scene) -> tuple[BinghamOscillator, float, float] | str:
    """If ``scene`` is exactly the paper's oscillator, return ``(osc, sign_s, sign_d)``.

    ``sign`` is ``+1`` for an element drawn from ground to the mass (its force is the
    closed form's ``F_s`` / ``F_d``) and ``-1`` for the other orientation. Otherwise
    return a string saying why not.
    """
    try:
        from ...laws import BUILTIN_LAWS
    except ImportError:  # pragma: no cover - before the law library exists
        BUILTIN_LAWS = None

    if getattr(scene, "support_ends", ()):
        return (f"the scene has moving supports ({', '.join(sorted(scene.supports))}), "
                "which the closed form does not take (use 'bdf1' or 'bdf2')")
    if len(scene.nodes) != 1 or not isinstance(scene.nodes[0], Mass):
        return "the scene must have exactly one node, a Mass"
    if len(scene.elements) != 2:
        return f"the scene must have exactly two elements, it has {len(scene.elements)}"
    mass = scene.nodes[0]
    found: dict[str, tuple] = {}
    for el in scene.elements:
        name = el.law_name
        if name not in ("linear_spring", "bingham") or name in found:
            return ("the elements must be one 'linear_spring' and one 'bingham', got "
                    f"{[e.law_name for e in scene.elements]}")
        builtin = BUILTIN_LAWS.get(name) if BUILTIN_LAWS is not None else el.law.law
        if not (el.law.law is builtin or el.law.law == builtin):
            return f"element {el.name!r} uses a law named {name!r} that is not the built-in one"
        if {el.a, el.b} != {GROUND, mass.name}:
            return f"element {el.name!r} must join {mass.name!r} to ground"
        found[name] = (el, 1.0 if el.a == GROUND else -1.0)
    spring, s_sign = found["linear_spring"]
    dashpot, d_sign = found["bingham"]
    p_s, p_d = dict(spring.law.params), dict(dashpot.law.params)
    osc = BinghamOscillator(m=mass.m, k=p_s["k"], gamma=p_d["gamma"], tau=p_d["tau"])
    return osc, s_sign, d_sign


def _run_single_mass(scene: Scene, method: str, make: Callable[..., Trajectory],
                     dt: float, n_steps: int) -> RawRun:
    """Run a single-mass path (closed form or exact reference) and lay it out as the
    scene's columns; ``make(osc, x0, v0, forcing, dt, n_steps) -> Trajectory``."""
    found = closed_form_oscillator(scene)
    if isinstance(found, str):
        raise ValueError(f"method {method!r} covers only one mass with a linear spring "
                         f"and a Bingham dashpot to ground: {found}")
    osc, s_sign, d_sign = found
    mass = scene.nodes[0]
    fn = scene.forcing[0]
    traj = make(osc, mass.x0, mass.v0, fn, dt, n_steps)
    F = np.empty((len(traj.t), 2))
    for e, el in enumerate(scene.elements):
        if el.law_name == "linear_spring":
            F[:, e] = s_sign * traj.F_s
        else:
            F[:, e] = d_sign * traj.F_d
    if any(el.F0 is not None for el in scene.elements):
        _, F0, _ = consistent_initial_state(scene, time_scale=dt)
        F[0, :] = F0
    data = np.column_stack([traj.t, traj.x, traj.v, F])
    stats = {"steps": n_steps, "newton_iterations": 0, "residual_evals": 0,
             "jacobian_evals": 0, "factorizations": 0, "max_newton_iterations": 0}
    return RawRun(data, stats, Status.SUCCESS, "")


def _closed_trajectory(formula: str) -> Callable[..., Trajectory]:
    def make(osc, x0, v0, forcing, dt, n_steps):
        return integrate(osc, x0=x0, v0=v0, forcing=forcing if forcing is not None else
                         zero_forcing, dt=dt, n_steps=n_steps, method=formula)

    return make


def _exact_trajectory(osc, x0, v0, forcing, dt, n_steps):
    from ...reference import reference_for_grid

    return reference_for_grid(osc, x0=x0, v0=v0, forcing=forcing, dt=dt, t_end=n_steps * dt)


def _single(method: str, make: Callable[..., Trajectory]) -> Runner:
    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        dt, n_steps = fixed_step_grid(method, settings)
        return _run_single_mass(scene, method, make, dt, n_steps)

    return runner


#: The methods of the paper's one scene, name -> runner.
RUNNERS: dict[str, Runner] = {
    "closed-bdf1": _single("closed-bdf1", _closed_trajectory("bdf1")),
    "closed-bdf2": _single("closed-bdf2", _closed_trajectory("bdf2")),
    "exact": _single("exact", _exact_trajectory),
}
