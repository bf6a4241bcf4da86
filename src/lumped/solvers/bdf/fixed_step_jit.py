r"""``jit-bdf1`` / ``jit-bdf2``: the generic fixed-step BDF of
:mod:`lumped.solvers.bdf.fixed_step`, compiled with numba.

:func:`run_bdf_jit` runs, by default, the scene's generated fast loop
(:mod:`lumped.solvers.bdf.fast_codegen`, driven by :mod:`lumped.solvers.bdf.fast_jit`): the step
system unrolled up to a few unknowns (a loop solve above), the laws' kernels called (LLVM
inlines them), a Newton specialised to the scene's size, agreeing
with the reference to the Newton tolerance (round-off on piecewise-linear laws). The
steps it cannot take go to the faithful port, the step loop of
:mod:`lumped.solvers.bdf.core_jit` on the structure-generic step system of
:mod:`lumped.codegen.step_dispatch` (:func:`port_parts`): the step system, the
semismooth Newton with its convergence tests and law-row scales, the singleton-first LU
and the fold check, all compiled once per machine and cached on disk (and each law's
kernel once per law), so the port of a new structure compiles nothing. That port
(alone with ``fast=False``) follows :func:`lumped.solvers.bdf.fixed_step.run_bdf` (the
readable reference) operation for operation: on systems of at most 8 unknowns the two
give the same numbers bit for bit, and the same counters; above that the reference
hands the LU to LAPACK and they agree to round-off.

Scope: every scene :func:`~lumped.solvers.bdf.fixed_step.run_bdf` runs, with laws given as
sympy residuals (a hand-written kernel cannot be compiled: ``ValueError``), except
scenes with a position lock (a spring law with a branch on which the force is free,
such as a taut string), refused with a ``ValueError``: the event model of impacts is
not part of this compiled port. (Through :func:`lumped.simulate`, ``method="jit-bdf1"`` or
``"jit-bdf2"`` runs such a scene's plain steps on this loop and its impacts and
indeterminate forces on the reference, :mod:`lumped.solvers.bdf.lock_handover`; a run of
another scene whose compiled Newton fails runs whole on the reference solver,
``stats["fallback"]`` says so.)

The consistent initial state is computed by the reference in Python (once per run).
Forcing: ``None``, constants and :class:`~lumped.scene.forcing.SineBurst` are evaluated
in the compiled loop; any other callable (a sympy expression, a Python function) is
tabulated on the grid in Python before the loop (a Python call per step).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from ...scene import Scene
from ..implicit.branch_check import known_monotone
from ..implicit.initial_state import consistent_initial_state
from ..implicit.step_system import newton_failure
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..status import BranchError, RawRun, Status

__all__ = ["JIT_METHODS", "FAST_MIN_STEPS", "run_bdf_jit", "loop_arguments", "Port", "port_parts",
           "position_lock", "refuse_position_locks", "takes_fast_path"]

#: Compiled method name -> step formula.
JIT_METHODS = {"jit-bdf1": "bdf1", "jit-bdf2": "bdf2"}
#: The steps a process runs a structure on the faithful port before ``fast=None``
#: compiles its fast loop (:func:`takes_fast_path`).
FAST_MIN_STEPS = 1_000_000


def position_lock(scene: Scene, method: str) -> str | None:
    """Why ``method`` cannot run ``scene`` compiled (a spring element's law has a branch
    that locks its elongation: a taut string), or ``None``."""
    try:
        from ...codegen.branches import law_branches
    except ImportError:  # pragma: no cover - before the branch machinery exists
        return None
    for el in scene.elements:
        if el.kind != "spring":
            continue
        lb = law_branches(el.law)
        for i in range(lb.count):
            if lb.info[i].locks:
                return (f"method {method!r} does not take position locks: branch {i} of "
                        f"law {el.law_name!r} of element {el.name!r} fixes its elongation "
                        f"(use {JIT_METHODS[method]!r})")
    return None


def refuse_position_locks(scene: Scene, method: str) -> None:
    """``ValueError`` if a spring element's law has a branch that locks its elongation
    (:func:`position_lock`)."""
    why = position_lock(scene, method)
    if why is not None:
        raise ValueError(why)


class Port:
    """The faithful port's callbacks, ``evaluate(u, p, G, J, S, roundoff)`` and
    ``element_law(e, q, F, c)`` (:meth:`callbacks`), and the constants ``c`` they read
    (:attr:`consts`, an array of its final size from the start: the loop's workspace is
    sized by it). The callbacks are made, and the constants completed, at the first call
    of :meth:`callbacks`: a run the fast loop takes whole compiles none of them."""

    def __init__(self, consts: np.ndarray, make: Callable[[], tuple],
                 tally: list[int] | None = None) -> None:
        self.consts = consts
        self._make = make
        self._callbacks: tuple | None = None
        #: the steps this process ran the scene's structure on the port (one element,
        #: shared by the structure's scenes; ``None``: not counted)
        self.tally = tally

    def callbacks(self) -> tuple:
        """``(evaluate, element_law)``, made (compiled or loaded) the first time."""
        if self._callbacks is None:
            self._callbacks = self._make()
        return self._callbacks


def port_parts(scene: Scene) -> tuple:
    """``(jit_scene, port)``: the scene's arrays and numbers
    (:class:`~lumped.codegen.scene_numbers.JitScene`) and the faithful port's
    :class:`Port`.

    With numba, the port's callbacks are the structure-generic step system of
    :mod:`lumped.codegen.step_dispatch` (compiled once per machine; its laws' law modules
    once per law), and the scene has no generated module (``module=None``): a new
    structure compiles nothing. Without numba (or with ``NUMBA_DISABLE_JIT=1``) they are
    the scene's generated module's (:func:`lumped.codegen.jit.jit_scene`), run as plain
    Python. Both give the same numbers bit for bit."""
    from ...codegen.jit import jit_scene, numba_enabled

    if numba_enabled():
        from ...codegen.step_dispatch import step_callbacks, step_layout

        js, consts, with_header, tally = step_layout(scene)

        def make() -> tuple:
            with_header()
            return step_callbacks()

        return js, Port(consts, make, tally)
    js = jit_scene(scene)
    return js, Port(js.consts, lambda: (js.module.evaluate, js.module.element_law))


def loop_arguments(scene: Scene, formula: str, dt: float, n_steps: int,
                   options: NewtonOptions):
    """``(jit_scene, port, args, ic_stats)``: the scene's arrays and numbers, the faithful
    port's :class:`Port` (:func:`port_parts`); the arguments of
    :func:`lumped.solvers.bdf.core_jit.run_bdf_core` after its two callbacks, for one
    run (consistent initial state, forcing, outputs, workspaces, the port's constants
    last; ``args[19:25]`` are ``xs, vs, Fs, info, finfo`` and Newton's vector
    workspace); the initial state's Newton counters."""
    from ..newton.semismooth_jit import workspace
    from .core_jit import loop_workspace

    js, port = port_parts(scene)
    v, F, ic_stats = consistent_initial_state(scene, time_scale=dt, options=options)
    N, E = len(scene.nodes), len(scene.elements)
    from ...scene.forcing_jit import forcing_arrays

    fkind, fpar, ftab = forcing_arrays(scene, dt, n_steps)
    checked = np.array([e for e, el in enumerate(scene.elements)
                        if not known_monotone(el.law)], dtype=np.int64)
    args = (js.masses, js.ea, js.eb, js.spring, checked,
            np.array([nd.x0 for nd in scene.nodes], dtype=float), np.array(v, dtype=float),
            np.array(F, dtype=float), float(dt), int(n_steps), formula == "bdf2",
            options.rtol, options.atol, options.max_iters, options.max_backtracks,
            options.free_steps, fkind, fpar, ftab,
            np.empty((n_steps + 1, N)), np.empty((n_steps + 1, N)), np.empty((n_steps + 1, E)),
            np.zeros(9, dtype=np.int64), np.zeros(6), *workspace(N + E),
            *loop_workspace(N, E, port.consts.shape[0]), port.consts)
    return js, port, args, ic_stats


def takes_fast_path(scene: Scene, n_steps: int, fast: bool | None,
                    port: Port | None = None) -> bool:
    """Whether a run of ``n_steps`` steps takes the generated fast loop (see
    :func:`run_bdf_jit` for ``fast``; ``port`` the run's :class:`Port`, whose tally
    counts the steps the structure ran on the port); ``TypeError`` for a ``fast`` not a
    bool or None."""
    if fast is not None and not isinstance(fast, bool):
        raise TypeError(f"`fast` must be True, False or None, got {fast!r}")
    from .fast_codegen import MAX_FAST_UNKNOWNS, fast_module_cached

    small = len(scene.nodes) + len(scene.elements) <= MAX_FAST_UNKNOWNS
    if fast is None:
        from .core_jit import port_cached

        tally = None if port is None else port.tally
        fast = n_steps + (tally[0] if tally else 0) >= FAST_MIN_STEPS or (
            small and (fast_module_cached(scene) or not port_cached()))
        if not fast and tally is not None:
            tally[0] += n_steps
    return fast and small


def run_bdf_jit(scene: Scene, *, method: str, dt: float, n_steps: int,
                options: NewtonOptions | None = None, throw: bool = True,
                fast: bool | None = None) -> RawRun:
    """Advance ``scene`` by ``n_steps`` compiled BDF steps (``method`` ``jit-bdf1`` or
    ``jit-bdf2``); the same output and errors as :func:`~lumped.solvers.bdf.fixed_step.run_bdf`.

    With ``fast=True`` the scene's generated fast loop takes every step it can and hands
    the others to the faithful port (:mod:`lumped.solvers.bdf.fast_jit`:
    the reference's numbers to round-off on piecewise-linear laws, its solution to the
    Newton tolerance otherwise; ``stats`` adds ``fast_steps`` and ``handovers``). With
    ``fast=False``, or a step system of more than
    :data:`~lumped.solvers.bdf.fast_codegen.MAX_FAST_UNKNOWNS` unknowns, the faithful port alone
    runs: the reference's numbers and counters bit for bit. ``fast=None`` (the default)
    is ``True`` for every run of a structure whose fast loop exists (loaded, or in the
    disk cache), for every run on a machine where the faithful port was never compiled
    (:func:`~lumped.solvers.bdf.core_jit.port_cached`: about 30 s of CPU, once per
    machine, against a few seconds for a structure's fast loop), and once this process
    has run the structure for :data:`FAST_MIN_STEPS` steps in all, this run's included
    (the port's tally); else ``False``. The fast loop is compiled once per structure
    (the laws' expressions and the topology: 3-5 s of CPU for the 3-mass chain), and the
    port, compiled once for every scene, runs a new structure of laws met before
    without compiling anything at about 1.5 us a step on that chain against 0.3 us for
    the fast loop: a million steps on the port cost about a third of the compile, so a
    one-off run of a new structure takes the port (50 000 steps of the chain: 0.5 s
    against 4.9 s), and runs repeated past a million steps compile the fast loop once.
    The laws' numbers are run-time data, so new numbers compile nothing.

    Raises
    ------
    ValueError
        Unknown ``method``; a law without a sympy residual; a position lock; a forcing
        that returns a non-finite value.
    SolverError, BranchError
        A failed step, with ``throw=True`` (else the run so far with its status).
    """
    if method not in JIT_METHODS:
        raise ValueError(f"`method` must be one of {tuple(JIT_METHODS)}, got {method!r}")
    refuse_position_locks(scene, method)
    options = options or NewtonOptions()
    from .core_jit import compiled_run_bdf_core

    js, port, args, ic_stats = loop_arguments(scene, JIT_METHODS[method], dt, n_steps,
                                              options)
    fast = takes_fast_path(scene, n_steps, fast, port)
    if fast:
        from .fast_jit import run_fast_path

        rows, stats = run_fast_path(scene, js, port, args)
    else:
        rows = compiled_run_bdf_core()(*port.callbacks(), *args, 0, -1)
    N, E = len(scene.nodes), len(scene.elements)
    xs, vs, Fs, info, finfo, wv = args[19:25]
    status, message = Status.SUCCESS, ""
    outcome, step = int(info[0]), int(info[1])
    t = float(finfo[1])
    if outcome == 3:
        node = scene.nodes[int(info[3])]
        raise ValueError(f"force on node {node.name!r} returned {float(finfo[0])!r} at "
                         f"t = {t!r}")
    if outcome == 1:
        from ..newton.semismooth_jit import CODE_NAMES

        res = NewtonResult([], NewtonCode(CODE_NAMES[int(info[2])]), int(finfo[5]), 0, 0, 0,
                           wv[0].tolist(), int(info[3]), [])
        err = newton_failure(scene, res, t, step)
        if throw:
            raise err
        status, message = err.status, str(err)
    elif outcome == 2:
        el = scene.elements[int(info[3])]
        q0, F0, q1, F1 = (float(x) for x in finfo[2:6])
        message = (
            f"element {el.name!r} (law {el.law_name!r}) left its branch at t = {t!r} "
            f"(step {step}): from (q, F) = ({q0!r}, {F0!r}) to "
            f"({q1!r}, {F1!r}) the law's dR/dq or dR/dF changes sign -- a fold; "
            "there is no solution continuous with the past at this step")
        err = BranchError(message, status=Status.BRANCH_LOST, t=t,
                          where=f"law {el.law_name!r} of element {el.name!r}",
                          residual=float(finfo[0]))
        if throw:
            raise err
        status = Status.BRANCH_LOST
    data = np.empty((rows, 1 + 2 * N + E))
    data[:, 0] = np.arange(rows, dtype=float) * dt
    data[:, 1:1 + 2 * N:2] = xs[:rows]
    data[:, 2:2 + 2 * N:2] = vs[:rows]
    data[:, 1 + 2 * N:] = Fs[:rows]
    if not fast:
        stats = {
            "steps": rows - 1,
            "newton_iterations": int(info[4]),
            "residual_evals": int(info[5]),
            "jacobian_evals": int(info[6]),
            "factorizations": int(info[7]),
            "max_newton_iterations": int(info[8]),
        }
    stats["initial_newton_iterations"] = ic_stats["newton_iterations"]
    return RawRun(data, stats, status, message)
