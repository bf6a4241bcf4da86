r"""The registry of methods: name -> runner ``runner(scene, settings) -> RawRun``.

Built-in methods (the same names on the command line):

``bdf1``, ``bdf2``
    The generic semismooth-Newton BDF steps of :mod:`lumped.solvers.bdf.fixed_step`, for any
    scene.
``jit-bdf1``, ``jit-bdf2``
    The same steps compiled with numba (:mod:`lumped.solvers.bdf.fixed_step_jit`): the same
    numbers to the Newton tolerance (``fast=False``: bit for bit), much faster per step,
    after a one-off compile cached on disk. Not for hand-written kernels. A scene with a
    position lock (a taut string: impacts, indeterminate forces) and a run whose compiled
    Newton fails run whole on the reference solver, and ``stats["fallback"]`` says why.
``closed-bdf1``, ``closed-bdf2``
    The closed-form steps of :mod:`lumped.solvers.closed.closed_form` (``closed-bdf1`` is the
    paper's Algorithm 1). Only for a scene that is exactly one mass with one
    ``linear_spring`` and one ``bingham`` dashpot, both to ground; any other scene is
    refused.
``exact``
    The event-driven exact reference of :mod:`lumped.reference`, on the same grid; for
    that same scene with no forcing or a sine burst (``{ kind = "sine", ... }``).
``radau5``
    The adaptive Radau IIA (order 5) method of :mod:`lumped.solvers.eventdriven.runner`, with
    events located inside the step (``rtol``/``atol``; no ``dt``).
``auto``
    ``closed-bdf2`` for exactly that scene, else ``radau5``, else (a law ``radau5`` does
    not take) ``bdf2`` (:func:`resolve_method`).

All but ``radau5`` are fixed-step methods (they need ``dt``; the grid is ``t_n = n dt``).
A new method is one call to :func:`register_method`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from ..scene import GROUND, Mass, Scene
from ..scene.forcing import zero_forcing
from ..trajectory import Trajectory
from .bdf.fixed_step import run_bdf
from .closed.closed_form import BinghamOscillator, integrate, steps_for
from .implicit.initial_state import consistent_initial_state
from .newton.options import NewtonOptions
from .status import RawRun, Status

__all__ = [
    "FIXED_STEP_METHODS",
    "METHODS",
    "METHOD_REGISTRY",
    "RunSettings",
    "Runner",
    "closed_form_oscillator",
    "register_method",
    "resolve_method",
]


@dataclass(frozen=True)
class RunSettings:
    """What :func:`lumped.simulate` passes to a runner (validated there).

    Attributes
    ----------
    t_end : float
        Final time.
    dt : float, optional
        Step size of the fixed-step methods (required there).
    rtol, atol : float, optional
        Tolerances of the adaptive methods.
    throw : bool
        Raise :class:`~lumped.solvers.status.SolverError` on a failed step, or return the
        run up to the last good step with its status and message.
    options : NewtonOptions, optional
        Newton tolerances and budgets.
    extra : Mapping
        Method-specific keywords.
    """

    t_end: float
    dt: float | None = None
    rtol: float | None = None
    atol: float | None = None
    throw: bool = True
    options: NewtonOptions | None = None
    extra: Mapping[str, Any] = field(default_factory=lambda: MappingProxyType({}))


#: ``runner(scene, settings) -> RawRun``.
Runner = Callable[[Scene, RunSettings], RawRun]


def closed_form_oscillator(scene: Scene) -> tuple[BinghamOscillator, float, float] | str:
    """If ``scene`` is exactly the paper's oscillator, return ``(osc, sign_s, sign_d)``.

    ``sign`` is ``+1`` for an element drawn from ground to the mass (its force is the
    closed form's ``F_s`` / ``F_d``) and ``-1`` for the other orientation. Otherwise
    return a string saying why not.
    """
    try:
        from ..laws import BUILTIN_LAWS
    except ImportError:  # pragma: no cover - before the law library exists
        BUILTIN_LAWS = None

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
    from ..reference import reference_for_grid

    return reference_for_grid(osc, x0=x0, v0=v0, forcing=forcing, dt=dt, t_end=n_steps * dt)


def _fixed_step_grid(method: str, settings: RunSettings,
                     allowed: tuple[str, ...] = ()) -> tuple[float, int]:
    """``(dt, n_steps)`` of a fixed-step method; refuses what it does not take (extra
    keywords other than ``allowed``)."""
    if settings.dt is None:
        raise ValueError(f"`dt` is required for the fixed-step method {method!r}, got None")
    for name in ("rtol", "atol"):
        if getattr(settings, name) is not None:
            raise ValueError(f"`{name}` applies to adaptive methods only; {method!r} is a "
                             f"fixed-step method (give `dt`), got {name}="
                             f"{getattr(settings, name)!r}")
    unknown = sorted(k for k in settings.extra if k not in allowed)
    if unknown:
        raise TypeError(f"method {method!r} takes no keyword argument(s) "
                        f"{', '.join(map(repr, unknown))}")
    return settings.dt, steps_for(settings.dt, settings.t_end)


def _run_generic(formula: str) -> Runner:
    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        dt, n_steps = _fixed_step_grid(formula, settings, ("restitution",))
        out = run_bdf(scene, method=formula, dt=dt, n_steps=n_steps, options=settings.options,
                      throw=settings.throw,
                      restitution=settings.extra.get("restitution", 0.0))
        return RawRun(out.as_array(), out.stats, out.status, out.message,
                      events=out.events, dense=out.dense(scene),
                      indeterminate=out.indeterminate)

    return runner


#: Statuses of a compiled run that send it to the reference solver.
_NEWTON_FAILURES = frozenset({Status.SINGULAR, Status.DIVERGED, Status.MAX_ITERS,
                              Status.NON_FINITE})


def _on_reference(scene: Scene, method: str, dt: float, n_steps: int,
                  settings: RunSettings, why: str) -> RawRun:
    """The run of ``method`` (``jit-bdf1``/``jit-bdf2``) on the reference solver, with
    ``stats["fallback"] = why``."""
    out = run_bdf(scene, method=method.removeprefix("jit-"), dt=dt, n_steps=n_steps,
                  options=settings.options, throw=settings.throw)
    stats = dict(out.stats, fallback=why)
    return RawRun(out.as_array(), stats, out.status, out.message,
                  events=out.events, dense=out.dense(scene), indeterminate=out.indeterminate)


def _run_jit(method: str) -> Runner:
    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        from .bdf.fixed_step_jit import position_lock, run_bdf_jit

        dt, n_steps = _fixed_step_grid(method, settings, ("fast",))
        fast = settings.extra.get("fast")
        locked = position_lock(scene, method)
        if locked is not None:
            # impacts and locks are not compiled: the whole run on the reference solver,
            # which locates the impact in the step and splits indeterminate forces
            return _on_reference(scene, method, dt, n_steps, settings,
                                 "reference solver: " + locked)
        raw = run_bdf_jit(scene, method=method, dt=dt, n_steps=n_steps,
                          options=settings.options, throw=False, fast=fast)
        if raw.status in _NEWTON_FAILURES:
            # a step the compiled Newton cannot take (indeterminate forces: a singular
            # step matrix; a hard point of a law): the whole run on the reference solver,
            # with its globalised Newton and minimum-norm force split (issue 11)
            return _on_reference(scene, method, dt, n_steps, settings,
                                 f"reference solver after: {raw.message}")
        if raw.status is not Status.SUCCESS and settings.throw:
            return run_bdf_jit(scene, method=method, dt=dt, n_steps=n_steps,
                               options=settings.options, throw=True, fast=fast)
        return raw

    return runner


def _single(method: str, make: Callable[..., Trajectory]) -> Runner:
    def runner(scene: Scene, settings: RunSettings) -> RawRun:
        dt, n_steps = _fixed_step_grid(method, settings)
        return _run_single_mass(scene, method, make, dt, n_steps)

    return runner


#: Method name -> runner ``(scene, settings) -> RawRun``.
METHOD_REGISTRY: dict[str, Runner] = {
    "bdf1": _run_generic("bdf1"),
    "bdf2": _run_generic("bdf2"),
    "jit-bdf1": _run_jit("jit-bdf1"),
    "jit-bdf2": _run_jit("jit-bdf2"),
    "closed-bdf1": _single("closed-bdf1", _closed_trajectory("bdf1")),
    "closed-bdf2": _single("closed-bdf2", _closed_trajectory("bdf2")),
    "exact": _single("exact", _exact_trajectory),
}

#: The registered methods that need ``dt`` (``auto`` resolves to one of them).
FIXED_STEP_METHODS: set[str] = set(METHOD_REGISTRY)

#: Every method name :func:`lumped.simulate` accepts (shared with ``lumped run --method``);
#: rebuilt by :func:`register_method`.
METHODS: tuple[str, ...] = ("auto", *METHOD_REGISTRY)


def register_method(name: str, runner: Runner, *, fixed_step: bool = False) -> None:
    """Add (or replace) the method ``name``; ``fixed_step=True`` if it needs ``dt``.

    Raises
    ------
    ValueError
        If ``name`` is not a non-empty string or is ``"auto"``.
    TypeError
        If ``runner`` is not callable.
    """
    global METHODS
    if not isinstance(name, str) or not name or name == "auto":
        raise ValueError(f"`name` must be a non-empty string other than 'auto', got {name!r}")
    if not callable(runner):
        raise TypeError(f"`runner` must be callable, got {type(runner).__name__}")
    METHOD_REGISTRY[name] = runner
    if fixed_step:
        FIXED_STEP_METHODS.add(name)
    else:
        FIXED_STEP_METHODS.discard(name)
    METHODS = ("auto", *METHOD_REGISTRY)


def resolve_method(scene: Scene, method: str) -> str:
    """The concrete method ``auto`` stands for on ``scene`` (others unchanged):
    ``closed-bdf2`` on the paper's scene, else ``radau5``, else (a law ``radau5`` does not
    take, :func:`lumped.solvers.eventdriven.setup.scope_error`) ``bdf2``."""
    if method == "auto":
        if not isinstance(closed_form_oscillator(scene), str):
            return "closed-bdf2"
        from .eventdriven.setup import scope_error

        return "bdf2" if scope_error(scene) else "radau5"
    return method


def _register_adaptive() -> None:
    from .eventdriven.runner import run_radau5

    register_method("radau5", run_radau5)


_register_adaptive()
