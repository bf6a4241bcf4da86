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

**Branches of non-monotone laws.** After each step, every element whose law is not a
known monotone built-in is checked for a jump between branches: if ``dR/dq`` or
``dR/dF`` takes strictly opposite signs at the old and new point (or, when the step
leaves the tangent of the law, at points sampled on the segment between them), the
step has crossed or skipped a fold. The run stops with :class:`BranchError` (time,
element, the two points) instead of jumping silently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from ...scene import Scene
from ...scene.supports import solver_view
from ..implicit.branch_check import known_monotone, left_branch
from ..implicit.globalize import laws_hold, solve_globalized
from ..implicit.initial_state import consistent_initial_state
from ..implicit.step_system import EPS, generate_evaluate, newton_failure
from ..newton.criteria import residual_ok, update_ok
from ..newton.linalg import FactorCache
from ..newton.options import NewtonCode, NewtonOptions
from ..newton.semismooth import newton_solve
from ..nonsmooth.impacts import lockable_elements, locking_elements
from ..nonsmooth.locks import IntervalLog, cyclic_elements, indeterminate_elements
from ..status import BranchError, Event, Status
from .impact_step import halved_steps, impact_step, impulse_is_negligible

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
    forcing = [(i, fn) for i, fn in enumerate(scene.forcing) if fn is not None]
    isfinite = math.isfinite

    x_hat, uref, f = [0.0] * N, [0.0] * N, [0.0] * N
    h1 = dt
    h2 = 2.0 * dt / 3.0
    # the fast path tests with the linearised row scales; Newton proper (from the same
    # start, when the fast path declines) with the round-off scales of _law_scale
    ev1 = generate_evaluate(scene, h1, uref, x_hat, f)
    full1 = generate_evaluate(scene, h1, uref, x_hat, f, roundoff=True)
    ev2 = full2 = None
    if method == "bdf2":
        ev2 = generate_evaluate(scene, h2, uref, x_hat, f)
        full2 = generate_evaluate(scene, h2, uref, x_hat, f, roundoff=True)

    # branch bookkeeping: q, dR/dq, dR/dF at the last accepted point of checked elements
    checked = [e for e, el in enumerate(scene.elements) if not known_monotone(el.law)]
    prev_q = law_q(x, v)  # each law's own argument, q_e + o_e(t)
    prev_d = [el.law.kernel(prev_q[e], F[e]) for e, el in enumerate(source.elements)]

    cache1, cache2 = FactorCache(), FactorCache()
    rtol, atol = options.rtol, options.atol
    fast = options.free_steps >= 1
    xs, vs, Fs = list(x), list(v), list(F)
    total_it = res_ev = jac_ev = facts = 0
    max_it = 0
    status, message = Status.SUCCESS, ""
    x_prev, v_prev = x, v
    # impacts and locks: springs that can lock, those locked now, the events
    lockable = lockable_elements(scene)
    locked = set(locking_elements(scene, x, v, F, lockable)) if lockable else set()
    restart = False
    events: list[Event] = []
    knots: list = []
    n_impacts = 0
    log = IntervalLog()
    cyclic = cyclic_elements(scene)
    for step in range(1, n_steps + 1):
        t = t0 + step * dt
        clock(t)  # support offsets at t_{n+1}
        for i, fn in forcing:
            val = fn(t)
            if not isfinite(val):
                raise ValueError(
                    f"force on node {scene.nodes[i].name!r} returned {val!r} at t = {t!r}"
                )
            f[i] = val
        if ev2 is None or step == 1 or restart:
            h = h1
            evaluate, full = ev1, full1
            for i in range(N):
                x_hat[i] = x[i]
                uref[i] = v[i]
        else:
            h = h2
            evaluate, full = ev2, full2
            for i in range(N):
                # (4 y_n - y_{n-1}) / 3 as an increment: exact for a stuck state
                # (y_n == y_{n-1}), where the textbook form is one ulp off for about one
                # value in seven; the closed form (bingham.bdf2_step) uses the same formula
                xi, vi = x[i], v[i]
                x_hat[i] = xi + (xi - x_prev[i]) / 3.0
                uref[i] = vi + (vi - v_prev[i]) / 3.0
        cache = cache1 if h == h1 else cache2
        u = _fast_step(evaluate, v + F, cache, rtol, atol) if fast else None
        halved = None
        if u is not None:  # the common case, counted as newton_solve would count it
            J_acc = cache.J  # the Jacobian at the solution (same pieces)
            it = u.pop()
            total_it += it
            res_ev += 1 + it
            jac_ev += 1
            if it > max_it:
                max_it = it
        else:
            res = newton_solve(full, v + F, options, cache, min_norm=True)
            if res.code is NewtonCode.SUCCESS and not laws_hold(scene, h, x_hat, res.u,
                                                                 rtol, atol):
                res.code = NewtonCode.DIVERGED  # the last correction left a law
            if res.code is not NewtonCode.SUCCESS:
                total_it += res.iterations
                res_ev += res.residual_evals
                res = solve_globalized(scene, full, h, x_hat, v, F, options, sweeps=True)
            total_it += res.iterations
            res_ev += res.residual_evals
            jac_ev += res.jacobian_evals
            facts += res.factorizations
            if res.iterations > max_it:
                max_it = res.iterations
            if res.code is not NewtonCode.SUCCESS:  # last resort: backward-Euler substeps
                halved = halved_steps(scene, t - dt, dt, x, v, F, options)
            if res.code is not NewtonCode.SUCCESS and halved is None:
                err = newton_failure(scene, res, t, step)
                if throw:
                    raise err
                status, message = err.status, str(err)
                break
            if halved is not None:
                total_it += halved[3]
                u = halved[1] + halved[2]
                J_acc = None
            else:
                u = res.u
                J_acc = res.jacobian
        v_new = u[:N]
        x_new = [x_hat[i] + h * v_new[i] for i in range(N)] if halved is None else halved[0]
        F_new = u[N:]
        restart = halved is not None  # history through substeps: BDF2 restarts
        if lockable:
            now = set(locking_elements(scene, x_new, v_new, F_new, lockable))
            new = [e for e in sorted(now) if e not in locked]
            # an impulse below the round-off of the step's momentum change is none
            if new and not impulse_is_negligible(
                    scene, v, new, 4.0 * EPS * dt * max(map(abs, F_new + f), default=0.0)):
                done = impact_step(scene, t - dt, dt, x, v, F, locked, options, restitution)
                total_it += done.newton_iterations
                res_ev += done.solves
                if done.failure is not None:
                    err = newton_failure(scene, done.failure, done.failure_t, step)
                    if throw:
                        raise err
                    status, message = err.status, str(err)
                    break
                x_new, v_new, F_new = done.x, done.v, done.F
                events += done.events
                knots += done.knots
                n_impacts += 1
                restart = True
                J_acc = None
                now = set(locking_elements(scene, x_new, v_new, F_new, lockable))
            locked = now
        clock(t)  # (substeps move them)
        F_prev, F = F, F_new
        q_new = law_q(x_new, v_new) if checked else ()
        for e in checked:
            q0, d0 = prev_q[e], prev_d[e]
            kernel = source.elements[e].law.kernel
            d1 = kernel(q_new[e], F[e])  # at the accepted point
            if left_branch(kernel, q0, F_prev[e], d0[1], d0[2], q_new[e], F[e], d1[1], d1[2]):
                el = scene.elements[e]
                msg = (
                    f"element {el.name!r} (law {el.law_name!r}) left its branch at t = {t!r} "
                    f"(step {step}): from (q, F) = ({q0!r}, {F_prev[e]!r}) to "
                    f"({q_new[e]!r}, {F[e]!r}) the law's dR/dq or dR/dF changes sign -- a fold; "
                    "there is no solution continuous with the past at this step"
                )
                err = BranchError(msg, status=Status.BRANCH_LOST, t=t,
                                  where=f"law {el.law_name!r} of element {el.name!r}",
                                  residual=d1[0])
                if throw:
                    raise err
                status, message = Status.BRANCH_LOST, msg
                break
            prev_q[e] = q_new[e]
            prev_d[e] = d1
        if status is not Status.SUCCESS:
            break
        if cyclic:
            # force-free elements: dR/dF = 0 on the diagonal of the step's Jacobian
            if J_acc is not None and sum(J_acc[N + e][N + e] == 0.0 for e in cyclic) < 2:
                if log.open:
                    log.mark(t0 + (step - 1) * dt, t, ())
            else:
                q_acc = scene.elongations(x_new, v_new)
                log.mark(t0 + (step - 1) * dt, t, [scene.elements[e].name for e in
                                              indeterminate_elements(scene, q_acc, F, cyclic)])
        x_prev, v_prev, x, v = x, v, x_new, v_new
        xs += x
        vs += v
        Fs += F
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
    if lockable:  # a scene that can lock counts its impacts
        stats["impacts"] = n_impacts
    return RunResult(dt, N, E, xs, vs, Fs, stats, status, message, events, log.result(),
                     knots)


def _fast_step(evaluate, u0: list[float], cache: FactorCache, rtol: float,
               atol: float) -> list[float] | None:
    """The common step of :func:`~lumped.solvers.newton.semismooth.newton_solve`, without its
    bookkeeping.

    When the Jacobian at ``u0`` equals the cached one (the laws stay on the same pieces),
    Newton's path is: accept ``u0`` (0 iterations) or take the full step and accept it
    after the simplified-Newton check with the same factors (1 iteration). This function
    follows exactly that path -- same operations, same result -- and returns the solution
    with the iteration count appended, or ``None`` when anything else would happen
    (then the caller runs ``newton_solve`` from ``u0``).
    """
    G, J, S = evaluate(u0)
    if J != cache.J or not math.isfinite(sum(G)):
        return None
    solve = cache.hit()
    du = solve(G)
    if not math.isfinite(sum(du)):
        return None
    if residual_ok(G, S, rtol, atol):
        if update_ok(du, u0, rtol, atol):
            out = [ui - di for ui, di in zip(u0, du, strict=True)]
            out.append(0)
            return out
        return None  # newton_solve would try a directional Jacobian here
    u1 = [ui - di for ui, di in zip(u0, du, strict=True)]
    G1, J1, S1 = evaluate(u1)
    if J1 != J or not math.isfinite(sum(G1)) or not residual_ok(G1, S1, rtol, atol):
        return None
    d = solve(G1)
    if not (math.isfinite(sum(d)) and update_ok(d, u1, rtol, atol)):
        return None
    out = [ui - di for ui, di in zip(u1, d, strict=True)]
    out.append(1)
    return out


