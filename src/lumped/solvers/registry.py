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
    What the user gave decides (:func:`resolve_method`): ``rtol``/``atol`` or nothing,
    ``radau5``; ``dt`` alone, ``closed-bdf2`` on the paper's scene, else ``bdf2``; a law
    ``radau5`` does not take, ``bdf2``. Scenes with moving supports
    (:mod:`lumped.scene.supports`) follow the same rule (``radau5`` runs them in its
    Python loop, ``closed-bdf2`` refuses them).

All but ``radau5`` are fixed-step methods (they need ``dt``; the grid is ``t_n = n dt``).
Each family hands its runners over (``RUNNERS`` of :mod:`lumped.solvers.bdf.runners`
and :mod:`lumped.solvers.closed.runners`, ``run_radau5`` of
:mod:`lumped.solvers.eventdriven.runner`); the runner contract
(:class:`~lumped.solvers.status.RunSettings` in, :class:`~lumped.solvers.status.RawRun`
out) lives in :mod:`lumped.solvers.status`. A new method is one call to
:func:`register_method`.
"""

from __future__ import annotations

from ..scene import Scene
from .bdf.runners import RUNNERS as BDF_RUNNERS
from .closed.runners import RUNNERS as CLOSED_RUNNERS
from .closed.runners import closed_form_oscillator
from .eventdriven.runner import run_radau5
from .eventdriven.setup import scene_plan
from .status import Runner, RunSettings

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


#: Method name -> runner ``(scene, settings) -> RawRun``.
METHOD_REGISTRY: dict[str, Runner] = {**BDF_RUNNERS, **CLOSED_RUNNERS}

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


def resolve_method(scene: Scene, method: str, *, dt: float | None = None,
                   rtol: float | None = None, atol: float | None = None) -> str:
    """The concrete method ``auto`` stands for on ``scene`` (others unchanged): what the
    user gave decides.

    ``rtol`` and/or ``atol`` (with or without ``dt``)
        ``radau5``; with ``dt``, its dense output sampled on ``t_n = n dt``.
    ``dt`` alone
        A fixed-step method at that step: ``closed-bdf2`` on the paper's oscillator (one
        mass, a ``linear_spring`` and a ``bingham`` dashpot to ground), else ``bdf2``.
    neither
        ``radau5`` at its default tolerances.

    A scene with a law ``radau5`` does not take
    (:func:`lumped.solvers.eventdriven.setup.scope_error`), runs ``bdf2`` whatever was
    given, and needs ``dt``. A scene with moving supports follows the rules above
    (``dt`` alone: ``bdf2``, as ``closed-bdf2`` refuses supports)."""
    if method != "auto":
        return method
    if scene_plan(scene).refused:  # (scope_error, kept per scene object)
        return "bdf2"
    if dt is not None and rtol is None and atol is None:
        return "closed-bdf2" if not isinstance(closed_form_oscillator(scene), str) else "bdf2"
    return "radau5"


register_method("radau5", run_radau5)
