r"""Generic BDF1 / BDF2 time stepping of a :class:`~lumped.scene.Scene`.

One step is one discrete system in all unknowns at ``t_{n+1}``. BDF with fixed step
``dt`` reads, for every node, ``x_{n+1} = x_hat + h v_{n+1}`` and (masses)
``m (v_{n+1} - v_hat) / h = net force at t_{n+1}``, with

* BDF1 (backward Euler): ``h = dt``, ``x_hat = x_n``, ``v_hat = v_n``;
* BDF2: ``h = 2 dt / 3``, ``x_hat = (4 x_n - x_{n-1}) / 3``, ``v_hat = (4 v_n - v_{n-1}) / 3``,
  computed as ``y_n + (y_n - y_{n-1}) / 3`` (the same value, but exact when
  ``y_n == y_{n-1}``, so a stuck state stays put bit for bit; as
  :func:`lumped.solvers.closed.closed_form.bdf2_step`); its first step is a BDF1 step.

The positions are eliminated (``x_{n+1} = x_hat + h v_{n+1}``), which leaves the unknowns
``u = (v_1 .. v_N, F_1 .. F_E)`` -- every node's velocity and every element's force --
and the equations (rows in that order)::

    mass i:      (m_i / h)(v_i - v_hat_i) - f_i(t) - sum_{a_e = i} F_e + sum_{b_e = i} F_e = 0
    junction i:                         - f_i(t) - sum_{a_e = i} F_e + sum_{b_e = i} F_e = 0
    element e:   R_e(q_e, F_e) = 0,   q_e = x_b - x_a (spring) or v_b - v_a (dashpot)

solved by :func:`lumped.solvers.newton.semismooth.newton_solve` from the previous step's solution.
The Jacobian is assembled from the kernels' ``dR/dq, dR/dF`` (``dq/dv = +-h`` for springs,
``+-1`` for dashpots). Everything runs on Python floats.

**Consistent initial state.** The same system with a vanishing step ``h = eps`` and the
masses' accelerations as unknowns (``v_i = v_i(0) + eps a_i``) selects the initial
forces that the limit ``dt -> 0`` of the implicit steps selects: a stuck dashpot takes
the force that keeps its mass at rest if its law admits it, else the nearest admissible
one (for the paper's scene ``clip(F(0) - k x0, -tau, tau)``, as
:func:`lumped.solvers.closed.closed_form.initial_dashpot_force`), and junction velocities follow
from the laws.

**Steep branches.** A step whose plain Newton fails is solved next with every law's
steep branches in their inverse form (:mod:`lumped.solvers.implicit.conditioned`):
Herschel-Bulkley ``n < 1`` as ``F = sgn(q) (tau + (|q|/gamma)^(1/n))``, which fixes the
force of a rate too small to have one in ``q = gamma (F - tau)^n`` (``|q| < gamma
ulp(tau)^n``, a break-away from rest at small steps); then by the globalised solve
(:func:`lumped.solvers.implicit.globalize.solve_globalized`), then by substeps.

**Branches of non-monotone laws.** After each step, every element whose law is not a
known monotone built-in is checked for a jump between branches: if ``dR/dq`` or
``dR/dF`` takes strictly opposite signs at the old and new point (or, when the step
leaves the tangent of the law, at points sampled on the segment between them), the
step has crossed or skipped a fold. The run stops with :class:`BranchError` (time,
element, the two points) instead of jumping silently.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ...scene import Scene
from ...scene.supports import solver_view
from ..implicit.initial_state import consistent_initial_state
from ..newton.options import NewtonOptions
from ..status import Event, Status
from .step_loop import StepLoop

__all__ = ["GENERIC_METHODS", "RunResult", "run_bdf"]

#: Generic step formulas by name.
GENERIC_METHODS = ("bdf1", "bdf2")


@dataclass
class RunResult:
    """Raw output of :func:`run_bdf`: the node displacements ``xs``, velocities ``vs`` and
    element forces ``Fs`` of all samples (``t_n = n dt``), each flat (sample-major, so the
    step loop creates no lasting containers for the garbage collector), and the counters."""

    dt: float
    n_nodes: int
    n_elements: int
    xs: list[float]
    vs: list[float]
    Fs: list[float]
    stats: dict = field(default_factory=dict)
    status: Status = Status.SUCCESS
    message: str = ""
    events: list[Event] = field(default_factory=list)
    indeterminate: dict[str, list[tuple[float, float]]] = field(default_factory=dict)
    #: States just before and just after each impact, ``(t, x, v, F)``
    #: (:attr:`lumped.solvers.bdf.impact_step.ImpactStep.knots`).
    knots: list[tuple[float, list[float], list[float], list[float]]] = \
        field(default_factory=list)

    def dense(self, scene: Scene):
        """The dense output with the impacts as knots, or ``None`` without impacts.

        Between samples the cubic Hermite interpolant of :mod:`lumped.post.dense`; a step
        that holds impacts is split at them, each impact a pair of rows at its time (the
        state just before, then just after), so the velocities jump at the impact instead
        of being spread over the step."""
        if not self.knots:
            return None
        import numpy as np

        from ...post.dense import HermiteDense

        data = self.as_array()
        N = self.n_nodes
        rows = np.empty((len(self.knots), data.shape[1]))
        for r, (t, x, v, F) in enumerate(self.knots):
            rows[r, 0] = t
            rows[r, 1:1 + 2 * N:2] = x
            rows[r, 2:2 + 2 * N:2] = v
            rows[r, 1 + 2 * N:] = F
        at = np.searchsorted(data[:, 0], rows[:, 0], side="right")
        return HermiteDense(scene, np.insert(data, at, rows, axis=0))

    def as_array(self):
        """``(n, 1 + 2 N + E)`` array: ``t``, then ``x_i, v_i`` per node, then ``F_e``."""
        import numpy as np

        N, E = self.n_nodes, self.n_elements
        n = len(self.xs) // N
        out = np.empty((n, 1 + 2 * N + E))
        out[:, 0] = np.arange(n, dtype=float) * self.dt
        out[:, 1:1 + 2 * N:2] = np.array(self.xs, dtype=float).reshape(n, N)
        out[:, 2:2 + 2 * N:2] = np.array(self.vs, dtype=float).reshape(n, N)
        out[:, 1 + 2 * N:] = np.array(self.Fs, dtype=float).reshape(n, E)
        return out


# ---------------------------------------------------------------------------------------
# the step loop


def run_bdf(
    scene: Scene,
    *,
    method: str,
    dt: float,
    n_steps: int,
    options: NewtonOptions | None = None,
    throw: bool = True,
    restitution: float = 0.0,
    start: tuple[float, list[float], list[float], list[float]] | None = None,
    max_residual_evals: int | None = None,
) -> RunResult:
    """Advance ``scene`` by ``n_steps`` fixed steps of BDF1 or BDF2 (first step BDF1).

    From the consistent initial state at ``t = 0``, or from ``start = (t0, x, v, F)``, a
    state of the scene at ``t0`` (the samples are then at ``t0 + n dt``; ``radau5``
    bridges a stop with it, :mod:`lumped.solvers.eventdriven.bridge`).

    Returns the samples (see :class:`RunResult`; ``as_array()`` gives the columns ``t``,
    ``x_i, v_i`` per node, ``F_e`` per element), the counters, the impacts (``events``)
    and the intervals of indeterminate forces. On a failed step: raise
    :class:`SolverError` (``throw=True``) or return the samples so far with ``status`` and
    ``message`` set.

    **Impacts** (a spring-like element reaches a locking branch while its ends approach):
    the step is redone by :func:`lumped.solvers.bdf.impact_step.impact_step` (locate, impulse
    with restitution ``restitution``, finish), and BDF2 restarts with a BDF1 step.
    **Indeterminate forces** (locked elements in parallel): a singular step matrix is
    solved by minimum-norm Newton corrections (the forces change as little as possible
    from the previous step), and the elements and intervals are reported
    (:mod:`lumped.solvers.nonsmooth.locks`).

    **Work budget** (``max_residual_evals``, optional): the run stops, with ``status``
    ``MAX_ITERS`` and a message, once its residual evaluations pass that number (checked
    every :data:`BUDGET_CHUNK` steps; ``radau5``'s bridges use it, so that a span whose
    steps all need the globalised solve ends in seconds, not hours).
    """
    if method not in GENERIC_METHODS:
        raise ValueError(f"`method` must be one of {GENERIC_METHODS}, got {method!r}")
    if not (isinstance(restitution, (int, float)) and 0.0 <= restitution <= 1.0):
        raise ValueError(f"`restitution` must be in [0, 1], got {restitution!r}")
    options = options or NewtonOptions()
    source = scene  # with supports: a view whose laws read the offsets clock(t) sets
    scene, clock, law_q = solver_view(source, method, 0.0 if start is None else start[0])
    N, E = len(scene.nodes), len(scene.elements)
    if start is None:
        t0 = 0.0
        v, F, ic_stats = consistent_initial_state(scene, time_scale=dt, options=options)
        x = [n.x0 for n in scene.nodes]
    else:
        t0, x, v, F = start[0], list(start[1]), list(start[2]), list(start[3])
        ic_stats = {"newton_iterations": 0}
    loop = StepLoop(source, scene, clock, law_q, method=method, dt=dt, options=options,
                    throw=throw, restitution=restitution, t0=t0, x=x, v=v, F=F)
    if max_residual_evals is None:
        loop.advance(n_steps)
    else:
        _advance_within(loop, n_steps, max_residual_evals, t0, dt)
    xs, vs, Fs = loop.xs, loop.vs, loop.Fs
    total_it, res_ev, jac_ev, facts, max_it = loop.counts
    steps = len(xs) // N - 1
    stats = {
        "steps": steps,
        "newton_iterations": total_it,
        "residual_evals": res_ev,
        "jacobian_evals": jac_ev,
        "factorizations": facts,
        "max_newton_iterations": max_it,
        "initial_newton_iterations": ic_stats["newton_iterations"],
    }
    if loop.lockable:  # a scene that can lock counts its impacts
        stats["impacts"] = loop.n_impacts
    return RunResult(dt, N, E, xs, vs, Fs, stats, loop.status, loop.message, loop.events,
                     loop.log.result(), loop.knots)


#: Steps between two checks of a run's work budget (:func:`run_bdf`).
BUDGET_CHUNK = 16


def _advance_within(loop: StepLoop, n_steps: int, budget: int, t0: float, dt: float) -> None:
    """``loop.advance`` to ``n_steps`` in chunks of :data:`BUDGET_CHUNK` steps, stopped
    with ``MAX_ITERS`` once its residual evaluations (``loop.counts[1]``) pass
    ``budget``."""
    for last in range(BUDGET_CHUNK, n_steps + BUDGET_CHUNK, BUDGET_CHUNK):
        loop.advance(min(last, n_steps))
        if loop.message or last >= n_steps:
            return
        if loop.counts[1] > budget:
            loop.status = Status.MAX_ITERS
            loop.message = (f"work budget: {loop.counts[1]} residual evaluations in "
                            f"{loop.step} steps (at most {budget}) at t = {t0 + loop.step * dt!r}")
            return
