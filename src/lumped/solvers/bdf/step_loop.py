r"""The step loop of the Python reference ``bdf1``/``bdf2``, resumable over a range of steps.

:func:`lumped.solvers.bdf.fixed_step.run_bdf` (read it for the maths: the step system,
impacts, locks, indeterminate forces, the fold check) runs one :class:`StepLoop` over
all its steps. The loop keeps everything a step needs between calls of
:meth:`StepLoop.advance`:

* the state ``(x_n, v_n, F_n)`` and the BDF2 history ``(x_{n-1}, v_{n-1})``, and
  ``restart`` (the next step is a BDF1 step: the first step, or the one after an impact
  or after backward-Euler substeps);
* the position locks held at ``t_n`` (``locked``: the spring-like elements whose law is on
  a locking branch; an element that enters one during a step is an impact);
* the fold check's last accepted ``(q, dR/dq, dR/dF)`` per checked element, the Newton
  factor caches, the counters, the events, the knots and the log of indeterminate forces.

So a run can be split into ranges of steps with other code in between:
:meth:`StepLoop.resume` sets the state at a step ``n`` from samples computed elsewhere
(the compiled loop of :mod:`lumped.solvers.bdf.lock_handover`), exactly as the
reference would hold it there when it computed the same samples itself -- the locks
at ``t_n`` are a function of the state, and the BDF2 history is the two samples -- and
:meth:`StepLoop.advance` then takes steps ``n + 1 ..``, optionally stopping as soon as
``handback`` consecutive steps were plain steps (no impact or restart, no indeterminate
forces possible), so that the BDF2 history is plain too.
"""

from __future__ import annotations

import math

from ..implicit.branch_check import known_monotone, left_branch
from ..implicit.conditioned import conditioned_kernels
from ..implicit.globalize import laws_hold, solve_globalized
from ..implicit.step_system import EPS, generate_evaluate, newton_failure
from ..newton.criteria import residual_ok, update_ok
from ..newton.linalg import FactorCache
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.semismooth import newton_solve
from ..nonsmooth.impacts import lockable_elements, locking_elements
from ..nonsmooth.locks import IntervalLog, cyclic_elements, indeterminate_elements
from ..status import BranchError, Event, Status
from .impact_step import halved_steps, impact_step, impulse_is_negligible

__all__ = ["StepLoop", "fast_step"]


class StepLoop:
    """The reference BDF1/BDF2 step loop of ``scene`` from ``(x, v, F)`` at ``t0``.

    ``source`` is the user's scene, ``scene, clock, law_q`` its solver view
    (:func:`lumped.scene.supports.solver_view`); ``method`` ``"bdf1"`` or ``"bdf2"``. Step
    ``n`` ends at ``t0 + n dt``. The samples taken are appended to the flat lists ``xs,
    vs, Fs`` (the state at ``t0`` first); ``status``, ``message``, the counters, the
    events and knots as :class:`lumped.solvers.bdf.fixed_step.RunResult` has them.
    """

    def __init__(self, source, scene, clock, law_q, *, method: str, dt: float,
                 options: NewtonOptions, throw: bool, restitution: float, t0: float,
                 x: list[float], v: list[float], F: list[float]) -> None:
        self.source, self.scene, self.clock, self.law_q = source, scene, clock, law_q
        self.dt, self.options, self.throw, self.restitution = dt, options, throw, restitution
        self.t0 = t0
        N = len(scene.nodes)
        self.x_hat, self.uref, self.f = [0.0] * N, [0.0] * N, [0.0] * N
        h1, h2 = dt, 2.0 * dt / 3.0
        # the fast path tests with the linearised row scales; Newton proper (from the
        # same start, when the fast path declines) with the round-off scales of _law_scale
        self.ev1 = generate_evaluate(scene, h1, self.uref, self.x_hat, self.f)
        self.full1 = generate_evaluate(scene, h1, self.uref, self.x_hat, self.f,
                                       roundoff=True)
        self.ev2 = self.full2 = None
        if method == "bdf2":
            self.ev2 = generate_evaluate(scene, h2, self.uref, self.x_hat, self.f)
            self.full2 = generate_evaluate(scene, h2, self.uref, self.x_hat, self.f,
                                           roundoff=True)
        #: the laws' conditioned kernels (``None``: no steep branch) and their step
        #: systems per step size, built when a step first needs them
        #: (:meth:`conditioned_solve`)
        self.steep: list | None | bool = False
        self.cond: dict[float, object] = {}
        self.checked = [e for e, el in enumerate(scene.elements)
                        if not known_monotone(el.law)]
        self.cache1, self.cache2 = FactorCache(), FactorCache()
        self.lockable = lockable_elements(scene)
        self.cyclic = cyclic_elements(scene)
        self.forcing = [(i, fn) for i, fn in enumerate(scene.forcing) if fn is not None]
        self.counts = [0, 0, 0, 0, 0]  # Newton iterations, residual and Jacobian evals,
        #                                factorisations, the most iterations of one step
        self.status, self.message = Status.SUCCESS, ""
        self.events: list[Event] = []
        self.knots: list = []
        self.n_impacts = 0
        self.log = IntervalLog()
        self.xs, self.vs, self.Fs = list(x), list(v), list(F)
        self.resume(0, x, v, x, v, F)
        self.restart = True  # the first step is a BDF1 step

    def resume(self, step: int, x_prev: list[float], v_prev: list[float], x: list[float],
               v: list[float], F: list[float]) -> None:
        """Hold the state ``(x, v, F)`` at step ``step`` (samples not appended), with the
        BDF2 history ``(x_prev, v_prev)`` at ``step - 1``: the next step is a BDF2 step,
        the locks and the fold check's last point are those of the state."""
        self.step = step
        self.x_prev, self.v_prev = list(x_prev), list(v_prev)
        self.x, self.v, self.F = list(x), list(v), list(F)
        self.restart = False
        scene = self.scene
        self.locked = (set(locking_elements(scene, x, v, F, self.lockable))
                       if self.lockable else set())
        self.prev_q = self.law_q(x, v)  # each law's own argument, q_e + o_e(t)
        self.prev_d = [el.law.kernel(self.prev_q[e], F[e])
                       for e, el in enumerate(self.source.elements)]
        if self.log.open:  # the steps since were computed elsewhere, determinate
            t = self.t0 + step * self.dt
            self.log.mark(t, t, ())

    def advance(self, last: int, handback: int = 0) -> int:
        """Take steps ``self.step + 1 .. last``; with ``handback > 0`` stop after the
        first step that ends ``handback`` consecutive *plain* steps: no restart pending
        (no impact, no substeps) and fewer than two force-free elements on cycles (no
        indeterminate forces possible). Return the last step taken (``self.step``); on a
        failed step raise (``throw``) or set ``status``, ``message`` and stop before it."""
        scene, source, clock, law_q = self.scene, self.source, self.clock, self.law_q
        dt, t0, options, throw = self.dt, self.t0, self.options, self.throw
        restitution = self.restitution
        N = len(scene.nodes)
        x_hat, uref, f = self.x_hat, self.uref, self.f
        h1 = dt
        h2 = 2.0 * dt / 3.0
        ev1, full1, ev2, full2 = self.ev1, self.full1, self.ev2, self.full2
        checked, prev_q, prev_d = self.checked, self.prev_q, self.prev_d
        cache1, cache2 = self.cache1, self.cache2
        rtol, atol = options.rtol, options.atol
        fast = options.free_steps >= 1
        xs, vs, Fs = self.xs, self.vs, self.Fs
        total_it, res_ev, jac_ev, facts, max_it = self.counts
        status, message = self.status, self.message
        x_prev, v_prev, x, v, F = self.x_prev, self.v_prev, self.x, self.v, self.F
        lockable, locked, restart = self.lockable, self.locked, self.restart
        events, knots, n_impacts = self.events, self.knots, self.n_impacts
        log, cyclic, forcing = self.log, self.cyclic, self.forcing
        isfinite = math.isfinite
        slack = 0
        done_step = self.step
        for step in range(self.step + 1, last + 1):
            t = t0 + step * dt
            clock(t)  # support offsets at t_{n+1}
            for i, fn in forcing:
                val = fn(t)
                if not isfinite(val):
                    raise ValueError(
                        f"force on node {scene.nodes[i].name!r} returned {val!r} at t = {t!r}"
                    )
                f[i] = val
            if ev2 is None or restart:
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
                    # (y_n == y_{n-1}), where the textbook form is one ulp off for about
                    # one value in seven; the closed form (bingham.bdf2_step) uses the same
                    xi, vi = x[i], v[i]
                    x_hat[i] = xi + (xi - x_prev[i]) / 3.0
                    uref[i] = vi + (vi - v_prev[i]) / 3.0
            cache = cache1 if h == h1 else cache2
            u = fast_step(evaluate, v + F, cache, rtol, atol) if fast else None
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
                    res = self.conditioned_solve(h, v + F)
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
            x_new = ([x_hat[i] + h * v_new[i] for i in range(N)] if halved is None
                     else halved[0])
            F_new = u[N:]
            restart = halved is not None  # history through substeps: BDF2 restarts
            if lockable:
                now = set(locking_elements(scene, x_new, v_new, F_new, lockable))
                new = [e for e in sorted(now) if e not in locked]
                # an impulse below the round-off of the step's momentum change is none
                if new and not impulse_is_negligible(
                        scene, v, new, 4.0 * EPS * dt * max(map(abs, F_new + f), default=0.0)):
                    done = impact_step(scene, t - dt, dt, x, v, F, locked, options,
                                       restitution)
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
                if left_branch(kernel, q0, F_prev[e], d0[1], d0[2], q_new[e], F[e], d1[1],
                               d1[2]):
                    el = scene.elements[e]
                    msg = (
                        f"element {el.name!r} (law {el.law_name!r}) left its branch at "
                        f"t = {t!r} (step {step}): from (q, F) = ({q0!r}, {F_prev[e]!r}) to "
                        f"({q_new[e]!r}, {F[e]!r}) the law's dR/dq or dR/dF changes sign "
                        "-- a fold; there is no solution continuous with the past at this "
                        "step"
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
                F = F_prev  # (the sample at the last step taken)
                break
            free = False  # two force-free elements on cycles: forces may be indeterminate
            if cyclic:
                # force-free elements: dR/dF = 0 on the diagonal of the step's Jacobian
                if J_acc is not None and sum(J_acc[N + e][N + e] == 0.0 for e in cyclic) < 2:
                    if log.open:
                        log.mark(t0 + (step - 1) * dt, t, ())
                else:
                    free = True
                    q_acc = scene.elongations(x_new, v_new)
                    log.mark(t0 + (step - 1) * dt, t,
                             [scene.elements[e].name for e in
                              indeterminate_elements(scene, q_acc, F, cyclic)])
            x_prev, v_prev, x, v = x, v, x_new, v_new
            xs += x
            vs += v
            Fs += F
            done_step = step
            if handback:
                slack = 0 if (free or restart) else slack + 1
                if slack >= handback:
                    break
        self.counts = [total_it, res_ev, jac_ev, facts, max_it]
        self.status, self.message = status, message
        self.x_prev, self.v_prev, self.x, self.v, self.F = x_prev, v_prev, x, v, F
        self.locked, self.restart, self.n_impacts = locked, restart, n_impacts
        self.step = done_step
        return done_step

    def conditioned_solve(self, h: float, u0: list[float]) -> NewtonResult:
        """The step of size ``h`` from ``u0`` (the step's ``x_hat, uref, f`` set) solved
        with every law's steep branches in their inverse form
        (:func:`~lumped.solvers.implicit.conditioned.conditioned_kernels`, the same
        zeros), by the minimum-norm Newton; a success only where those forms hold at the
        solution (:func:`~lumped.solvers.implicit.globalize.laws_hold`).

        Taken where the plain Newton of the laws' own forms fails, before the globalised
        solve: a Herschel-Bulkley ``n < 1`` dashpot breaking away from rest at a rate
        below ``gamma ulp(tau)^n`` has no floating-point force in ``q = gamma (F -
        tau)^n``, and the plain Newton cycles between ``F = tau`` and its neighbour. A
        step the plain Newton takes is not touched (its numbers are as before). Returns
        a failed, empty result for a scene with no such branch."""
        if self.steep is False:
            self.steep = conditioned_kernels(self.scene)
        if self.steep is None:
            return NewtonResult(list(u0), NewtonCode.DIVERGED, 0, 0, 0, 0, [], 0, [])
        evaluate = self.cond.get(h)
        if evaluate is None:
            evaluate = self.cond[h] = generate_evaluate(
                self.scene, h, self.uref, self.x_hat, self.f, roundoff=True,
                kernels=self.steep)
        res = newton_solve(evaluate, u0, self.options, None, min_norm=True)
        if res.code is NewtonCode.SUCCESS and not laws_hold(
                self.scene, h, self.x_hat, res.u, self.options.rtol, self.options.atol,
                self.steep):
            res.code = NewtonCode.DIVERGED
        return res


def fast_step(evaluate, u0: list[float], cache: FactorCache, rtol: float,
              atol: float) -> list[float] | None:
    """The common step of :func:`~lumped.solvers.newton.semismooth.newton_solve`, without
    its bookkeeping.

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
