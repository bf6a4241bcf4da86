r"""One entry point: ``simulate(scene, method=..., dt=..., t_end=...) -> Solution``.

Methods (the same names on the command line):

``bdf1``, ``bdf2``
    The generic semismooth-Newton BDF steps of :mod:`lumped.integrators`, for any scene.
``closed-bdf1``, ``closed-bdf2``
    The closed-form steps of :mod:`lumped.bingham` (``closed-bdf1`` is the paper's
    Algorithm 1). Only for a scene that is exactly one mass with one ``linear_spring``
    and one ``bingham`` dashpot, both to ground; any other scene is refused.
``auto`` (default)
    ``closed-bdf2`` for exactly that scene, ``bdf2`` otherwise.

Further methods can be registered in :data:`METHOD_REGISTRY` (name -> runner).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ._validate import as_positive
from .bingham import BinghamOscillator, integrate, steps_for
from .integrators import (
    BranchError,
    InconsistentInitialForce,
    SolverError,
    Status,
    consistent_initial_state,
    run_bdf,
)
from .newton import NewtonOptions
from .scene import GROUND, Mass, Scene

__all__ = [
    "simulate",
    "Solution",
    "Status",
    "SolverError",
    "BranchError",
    "InconsistentInitialForce",
    "METHODS",
    "METHOD_REGISTRY",
    "closed_form_oscillator",
    "resolve_method",
]


@dataclass(frozen=True)
class Solution:
    """The result of :func:`simulate`.

    Attributes
    ----------
    columns : tuple of str
        ``t``, then ``x_<node>``, ``v_<node>`` per node, then ``F_<element>`` per element.
    data : numpy.ndarray
        ``(n_samples, len(columns))`` array; row 0 is the consistent initial state.
    node_names, element_names : tuple of str
    method : str
        The method that ran (``auto`` resolved).
    stats : dict
        ``steps``, ``newton_iterations``, ``residual_evals``, ``jacobian_evals``,
        ``factorizations`` (zero for the closed form), ``max_newton_iterations``.
    status : Status
    message : str
        Empty on success; otherwise what failed, when and where.
    """

    columns: tuple[str, ...]
    data: np.ndarray
    node_names: tuple[str, ...]
    element_names: tuple[str, ...]
    method: str
    stats: dict = field(default_factory=dict)
    status: Status = Status.SUCCESS
    message: str = ""

    def __post_init__(self) -> None:
        if self.data.ndim != 2 or self.data.shape[1] != len(self.columns):
            raise ValueError(
                f"`data` has shape {self.data.shape}, expected (n, {len(self.columns)})"
            )
        if not np.all(np.isfinite(self.data)):
            r, c = np.argwhere(~np.isfinite(self.data))[0]
            raise FloatingPointError(
                f"non-finite {self.columns[c]} = {self.data[r, c]!r} at row {r}"
            )

    def column(self, name: str) -> np.ndarray:
        """One column by name, e.g. ``"x_mass"``."""
        try:
            return self.data[:, self.columns.index(name)]
        except ValueError:
            raise KeyError(f"no column {name!r}; columns are {self.columns}") from None

    @property
    def t(self) -> np.ndarray:
        return self.data[:, 0]

    @property
    def x(self) -> dict[str, np.ndarray]:
        """Displacement per node."""
        return {n: self.column(f"x_{n}") for n in self.node_names}

    @property
    def v(self) -> dict[str, np.ndarray]:
        """Velocity per node."""
        return {n: self.column(f"v_{n}") for n in self.node_names}

    @property
    def F(self) -> dict[str, np.ndarray]:
        """Force per element (positive in tension)."""
        return {e: self.column(f"F_{e}") for e in self.element_names}

    @property
    def forces(self) -> np.ndarray:
        """``(n_samples, n_elements)`` array of the element forces."""
        return self.data[:, 1 + 2 * len(self.node_names):]

    @property
    def ok(self) -> bool:
        return self.status is Status.SUCCESS

    def to_csv(self, path: str | Path) -> Path:
        """Write the columns with a header line, ``%.17g`` (round-trip precision)."""
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        np.savetxt(path, self.data, fmt="%.17g", delimiter=",",
                   header=",".join(self.columns), comments="")
        return path


# ---------------------------------------------------------------------------------------


def closed_form_oscillator(scene: Scene) -> tuple[BinghamOscillator, float, float] | str:
    """If ``scene`` is exactly the paper's oscillator, return ``(osc, sign_s, sign_d)``.

    ``sign`` is ``+1`` for an element drawn from ground to the mass (its force is the
    closed form's ``F_s`` / ``F_d``) and ``-1`` for the other orientation. Otherwise
    return a string saying why not.
    """
    try:
        from .laws import BUILTIN_LAWS
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


def _run_closed(scene: Scene, formula: str, dt: float, n_steps: int, throw: bool,
                options: NewtonOptions | None):
    found = closed_form_oscillator(scene)
    if isinstance(found, str):
        raise ValueError(f"method 'closed-{formula}' covers only one mass with a linear spring "
                         f"and a Bingham dashpot to ground: {found}")
    osc, s_sign, d_sign = found
    mass = scene.nodes[0]
    fn = scene.forcing[0]
    forcing = fn if fn is not None else (lambda t: 0.0)
    traj = integrate(osc, x0=mass.x0, v0=mass.v0, forcing=forcing, dt=dt, n_steps=n_steps,
                     method=formula)
    cols = {"x": traj.x, "v": traj.v}
    F = np.empty((len(traj.t), 2))
    for e, el in enumerate(scene.elements):
        if el.law_name == "linear_spring":
            F[:, e] = s_sign * traj.F_s
        else:
            F[:, e] = d_sign * traj.F_d
    if any(el.F0 is not None for el in scene.elements):
        _, F0, _ = consistent_initial_state(scene, time_scale=dt)
        F[0, :] = F0
    data = np.column_stack([traj.t, cols["x"], cols["v"], F])
    stats = {"steps": n_steps, "newton_iterations": 0, "residual_evals": 0,
             "jacobian_evals": 0, "factorizations": 0, "max_newton_iterations": 0}
    return data, stats, Status.SUCCESS, ""


def _run_generic(formula: str):
    def runner(scene: Scene, dt: float, n_steps: int, throw: bool,
               options: NewtonOptions | None):
        out = run_bdf(scene, method=formula, dt=dt, n_steps=n_steps, options=options,
                      throw=throw)
        return out.as_array(), out.stats, out.status, out.message

    return runner


def _closed(formula: str):
    def runner(scene, dt, n_steps, throw, options):
        return _run_closed(scene, formula, dt, n_steps, throw, options)

    return runner


Runner = Callable[[Scene, float, int, bool, "NewtonOptions | None"], tuple]

#: Method name -> runner ``(scene, dt, n_steps, throw, options) -> (data, stats, status, msg)``.
METHOD_REGISTRY: dict[str, Runner] = {
    "bdf1": _run_generic("bdf1"),
    "bdf2": _run_generic("bdf2"),
    "closed-bdf1": _closed("bdf1"),
    "closed-bdf2": _closed("bdf2"),
}

#: Every method name :func:`simulate` accepts (shared with ``lumped run --method``).
METHODS: tuple[str, ...] = ("auto", *METHOD_REGISTRY)


def resolve_method(scene: Scene, method: str) -> str:
    """The concrete method ``auto`` stands for on ``scene`` (others unchanged)."""
    if method == "auto":
        return "closed-bdf2" if not isinstance(closed_form_oscillator(scene), str) else "bdf2"
    return method


def simulate(
    scene: Scene,
    *,
    method: str = "auto",
    dt: float,
    t_end: float,
    throw: bool = True,
    options: NewtonOptions | None = None,
) -> Solution:
    """Simulate ``scene`` on the grid ``t_n = n dt`` up to ``t_end``.

    Parameters
    ----------
    scene : Scene
    method : str
        One of :data:`METHODS` (see the module notes); default ``"auto"``.
    dt, t_end : float
        Step size and final time (``> 0``); the number of steps is
        :func:`lumped.bingham.steps_for` ``(dt, t_end)``.
    throw : bool
        On a failed step raise :class:`SolverError` (default) -- naming the time, the
        element or node, and the residual -- or, if ``False``, return the solution up to
        the last good step with ``status`` and ``message`` set.
    options : NewtonOptions, optional
        Newton tolerances and budgets for the generic methods.

    Returns
    -------
    Solution
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"`scene` must be a Scene, got {type(scene).__name__}")
    if not isinstance(method, str) or method not in METHODS:
        raise ValueError(f"`method` must be one of {METHODS}, got {method!r}")
    dt = as_positive("dt", dt)
    t_end = as_positive("t_end", t_end)
    n_steps = steps_for(dt, t_end)
    concrete = resolve_method(scene, method)
    data, stats, status, message = METHOD_REGISTRY[concrete](scene, dt, n_steps, throw, options)
    if data.ndim == 1:  # pragma: no cover - defensive
        data = data.reshape(1, -1)
    return Solution(
        columns=scene.columns(), data=data, node_names=scene.node_names,
        element_names=scene.element_names, method=concrete, stats=dict(stats),
        status=status, message=message,
    )

