r"""``radau5``: adaptive Radau IIA (order 5) with located switching and time events.

The driver of the adaptive method (the step is :mod:`lumped.solvers.radau`, the event
logic :mod:`lumped.solvers.events`; the reasons are in ``docs/theory.md``):

1. the consistent initial state, and the initial mode by a vanishing implicit step;
2. steps of Radau IIA with every law held on its mode's branch (a smooth DAE), the step
   size from RADAU5's filtered error estimate on the differential components (``x`` of
   every node, ``v`` of every mass) with Gustafsson's predictive controller;
3. after an accepted step, the branch guards along the collocation polynomial: at the
   first crossing the step is redone to end on it, the next mode is chosen, and the
   event is recorded; a break of the forcing in time (``breakpoints(t0, t1)`` of a
   forcing object) is stepped to exactly and is a time event;
4. more than ``max_events`` events, or ``zeno_events`` events within ``zeno_window``
   seconds, stop the run with :attr:`Status.TOO_MANY_EVENTS`; a step below its floor stops
   it with :attr:`Status.STEP_TOO_SMALL`.

The output holds the accepted step points, or (with ``dt``) the dense output on
``t_n = n dt``; ``RawRun.dense(t)`` evaluates the collocation polynomials anywhere.

The loop below is the readable reference. By default the steps between events run in
its compiled port (:mod:`lumped.solvers.radau_loop_jit`, through
:mod:`lumped.solvers.adaptive_fast`), which returns here for every pass that needs more
than a held-mode step (an event, a stop, a singular matrix) and gives the same numbers.
"""

from __future__ import annotations

import math

from ..scene import Mass, Scene
from . import adaptive_fast
from .adaptive_fast import compiled_loop
from .adaptive_modes import ModeState
from .adaptive_output import DenseOutput, Rows, initial_step, output_data, row_of
from .adaptive_setup import (
    EXTRA_OPTIONS,
    breakpoints,
    compiled_stage_solver,
    read_options,
    scene_plan,
)
from .bridge import MAX_BRIDGES, take_bridge
from .crossing_root import first_root_py
from .dense_defect import dense_defect
from .events import fold_crossed, guard_tolerance
from .initial_state import consistent_initial_state
from .landing import Landing
from .radau import DAMPED_AFTER, STALL_PASSES, START_WEIGHTS, C, StageSystem
from .radau import A as _A
from .split_kink import split_kink
from .status import BranchError, RawRun, SolverError, Status
from .stuck import hold_interval

__all__ = ["run_radau5", "DEFAULT_RTOL", "DEFAULT_ATOL", "EXTRA_OPTIONS"]

DEFAULT_RTOL = 1e-6
DEFAULT_ATOL = 1e-9
_EPS = 2.220446049250313e-16
#: Accepted steps in a row shorter than the step floor after which a run that creeps
#: (landing again and again on a guard, ``t`` moving by ulps) stops.
_CREEP_STEPS = 200
#: ... steps shorter than the step floor or than this fraction of the run.
_CREEP_FRACTION = 1e-12
#: Cuts of one step at kinks of the force split (:mod:`lumped.solvers.split_kink`) before
#: the step is taken as it is.
_KINK_CUTS = 8
#: The stops that backward Euler bridges (:mod:`lumped.solvers.bridge`, the keyword
#: ``bridge``); a fold of a law (``BRANCH_LOST``), ``max_steps`` and ``max_events`` end
#: the run.
_BRIDGED = frozenset({Status.STEP_TOO_SMALL, Status.TOO_MANY_EVENTS, Status.INCONSISTENT})


def _admitted(guard, q0: float, F0: float, q1: float, F1: float) -> float:
    """``F0`` if ``guard(q0, F0)`` holds (every value ``>= 0``), else the force on the
    segment from ``(q0, F0)`` to ``(q1, F1)`` nearest ``F0`` that it admits (bisection;
    ``F0`` when ``(q1, F1)`` is not admitted either)."""
    if min(guard(q0, F0), default=0.0) >= 0.0 or not min(guard(q1, F1), default=0.0) >= 0.0:
        return F0
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if min(guard(q0 + mid * (q1 - q0), F0 + mid * (F1 - F0))) >= 0.0:
            hi = mid
        else:
            lo = mid
    return F0 + hi * (F1 - F0)


def _skipping(guard, skip: tuple[int, ...]):
    """``guard`` with its guards ``skip`` read as held (``+inf``): a tangency at ``t``
    that the full laws kept (see :func:`run_radau5`)."""
    def held(q: float, F: float) -> list[float]:
        return [math.inf if j in skip else g for j, g in enumerate(guard(q, F))]
    return held


def _structure(scene: Scene, plan) -> tuple[list[bool], tuple[float, ...], list[bool],
                                             list[bool], float]:
    """``(is_mass, masses, spring, massless, m_min)`` of the scene's nodes and elements,
    made once per plan (the scene's structure; the lists are only read): which nodes are
    masses, ``m_i`` (``0.0`` at a junction), which elements are springs, which are
    dashpots between junctions and ground only (a lock there has its force from a
    junction's balance), and the lightest mass."""
    got = plan.__dict__.get("radau5_structure")
    if got is None:
        is_mass = [isinstance(nd, Mass) for nd in scene.nodes]
        masses = scene.masses
        massless = [not any(p >= 0 and is_mass[p] for p in (scene.elem_a[e], scene.elem_b[e]))
                    and el.kind == "dashpot" for e, el in enumerate(scene.elements)]
        got = plan.__dict__["radau5_structure"] = (
            is_mass, masses, [el.kind == "spring" for el in scene.elements], massless,
            min(mi for mi in masses if mi > 0.0))
    return got


def run_radau5(scene: Scene, settings) -> RawRun:
    """The ``radau5`` runner: ``(scene, RunSettings) -> RawRun`` (see the module notes).

    ``settings.rtol`` / ``atol`` default to :data:`DEFAULT_RTOL` / :data:`DEFAULT_ATOL`;
    ``settings.dt`` (optional) samples the dense output on ``t_n = n dt``; the keywords of
    :data:`EXTRA_OPTIONS` come in ``settings.extra``.
    """
    from .closed_form import steps_for

    plan = scene_plan(scene)
    if plan.refused:
        raise ValueError(plan.refused)
    rtol = DEFAULT_RTOL if settings.rtol is None else settings.rtol
    atol = DEFAULT_ATOL if settings.atol is None else settings.atol
    opts = read_options(settings)
    dt = settings.dt
    t_final = settings.t_end if dt is None else max(settings.t_end,
                                                    steps_for(dt, settings.t_end) * dt)
    N, E = len(scene.nodes), len(scene.elements)
    n = N + E
    is_mass, masses, spring, massless, m_min = _structure(scene, plan)
    system = StageSystem(masses, scene.elem_a, scene.elem_b, spring)
    checked = plan.checked
    x = [float(nd.x0) for nd in scene.nodes]
    v, F, ic = consistent_initial_state(scene, time_scale=t_final, options=settings.options)
    breaks = breakpoints(scene, t_final)
    zeno_window = opts["zeno_window"] or 1e-6 * t_final
    dense = DenseOutput(N, E)
    rows = Rows()
    rows.append(row_of(0.0, x, v, F))
    stats = {"steps": 0, "rejected": 0, "newton_iterations": 0, "factorizations": 0,
             "nfev": 0, "njev": 0, "events": 0, "max_newton_iterations": 0,
             "initial_newton_iterations": ic["newton_iterations"], "held_intervals": 0}
    status, message = Status.SUCCESS, ""
    fast, stats["loop"] = compiled_loop(scene, plan, opts["compiled"])

    ms = ModeState(scene, plan, settings, opts, rtol, atol, stats, zeno_window)
    ms.fast = fast
    modes, kernels, guards, watched, cones = ms.modes, ms.kernels, ms.guards, ms.watched, \
        ms.cones
    events, recent = ms.events, ms.recent
    lbs = plan.branches

    # the compiled stage Newton (compiled=True), built on first need: with the compiled
    # loop the attempts need it only after a singular Jacobian (building it costs ~0.7 ms)
    stage_solve = None

    msg = ms.change_mode(0.0, 1e-9 * t_final, "start", x, v, F)
    events.clear()
    recent.clear()
    if msg:
        raise SolverError(f"radau5: no consistent initial mode: {msg}",
                          status=Status.INCONSISTENT, t=0.0, where="", residual=math.nan)
    rows.set_first(row_of(0.0, x, v, F))
    # the last state a step (or a held interval) ended on, before any event there changed
    # it: a bridge starts from it (an event probe's forces on a position lock are
    # m ulp(x) / h_probe^2, 1e11, no start for a Newton iteration)
    committed = (0.0, list(x), list(v), list(F))

    def net_at(t: float) -> list[float]:
        return scene.net_forces(t, F)

    acc0 = [net_at(0.0)[i] / masses[i] if is_mass[i] else 0.0 for i in range(N)]
    h = opts["first_step"] or initial_step(x, v, acc0, is_mass, rtol, atol, t_final)
    h_good = h_big = h  # (the longest accepted step: the scale of a bridge's steps)
    h_acc = err_acc = None
    F_seen = 0.0
    if fast is not None:
        fast.setup(t_final, rtol, atol, m_min)
    dF_n: list[float] | None = None  # force slopes at t (None at the start, after events)
    target: Landing | None = None  # the guard being landed on and its bracket
    floor_tried = False  # a mode change was tried at the step floor since the last step
    infeasible_at = math.nan  # the last t where an infeasible stage had the mode chosen
    U: list[float] = []  # the Python attempt's stage values, force scale (``attempt``)
    Fref = 0.0
    infeasible_modes: list[int] = []  # ... and the mode the full laws kept there
    kept = False  # an event at t kept the mode (since the last step)
    tangent: set[tuple[int, int]] = set()  # ... and the guards read crossed at t then
    t = 0.0
    bi = 0
    max_newton = 10

    def at_event(t: float, h: float, cause: str) -> tuple[Status, str] | None:
        nonlocal hold_check
        hold_check = True  # a stuck interval may start here (lumped.solvers.stuck)
        return ms.at_event(t, h, cause, x, v, F)

    def choose_again(h_p: float) -> bool | None:
        """The full laws choose the mode at ``t`` (probes on the scale ``h_p``): whether
        it changed, or ``None`` when the run must stop (``status``, ``message`` set)."""
        nonlocal dF_n, status, message
        old = list(modes)
        dF_n = None
        stop = at_event(t, h_p, "guard")
        if stop:
            status, message = stop
            return None
        return modes != old

    def start_forces(U: list[float]) -> list[float]:
        """The forces at ``t`` the step's polynomial starts from: after an event the
        stage forces' quadratic at ``s = 0`` rather than the probe's forces, whose
        round-off (magnified by ``m / h_probe``) would put a false guard crossing into
        the first step (a dashpot breaking out tangentially chattered: issue 11)."""
        if not ms.forces_from_probe:
            return F
        return [sum(w * U[k * n + N + e] for k, w in enumerate(START_WEIGHTS))
                for e in range(E)]

    def dense_start_forces(U: list[float], h: float) -> list[float]:
        """The forces at ``t`` the dense output's polynomials start from, after an event.

        The probe's force, the right limit at ``t`` to ``O(h_probe)``, for an element
        that is not locked, or locked between junctions and ground only (its force is
        then set by a junction's balance, an algebraic relation the probe holds). A lock
        that a mass enters, a position lock (a taut string) and locks in parallel
        (``cones``) start from the stage forces' quadratic at ``s = 0``: the probe fixes
        the force of a lock on a mass only to ``m / h_probe`` times the velocity it
        snapped (0.7 for ``4e-9``), a position lock's to ``m ulp(x) / h_probe^2``, and the
        split of locks in parallel is the stage solve's (the quadratic is exact for a
        load shared by locks). The quadratic is off by ``O(h^3)`` times the force's third
        derivative where the step after the event is long and the force curved: a
        junction's dashpot just broken out and relaxing faster than the step (20 % of the
        force at the first output point), a Coulomb element just stuck at a junction (its
        force read beyond its yield force)."""
        if not ms.forces_from_probe:
            return F
        F_q = start_forces(U)
        out = []
        for e in range(E):
            if not (e in cones or (lbs[e].info[modes[e]].locks and not massless[e])):
                out.append(F[e])
                continue
            # a lock admits the force at the event: a quadratic start beyond its guards
            # (a Coulomb element just stuck beside a string gone taut, 2e-4 tau above it)
            # is moved back along the way to the first stage, which the guards admit
            q, Fe = system.element_nodes(U, h, x, v, F_q, e)
            out.append(_admitted(guards[e], q[0], Fe[0], q[1], Fe[1]))
        return out

    def crossing(U: list[float], h: float):
        if not watched:
            return None
        fns = [guards[e] for e in watched]
        if tangent:
            fns = [_skipping(fn, tuple(j for w2, j in tangent if w2 == w))
                   if any(w2 == w for w2, _ in tangent) else fn for w, fn in enumerate(fns)]
        hit = first_root_py([system.element_nodes(U, h, x, v, F, e) for e in watched], fns)
        if hit is None or not ms.forces_from_probe or hit[0] == 0.0:
            return hit  # (a guard already off at t: an event at t itself, as before)
        F_0 = start_forces(U)  # a crossing inside the step: tested without the offset
        return first_root_py([system.element_nodes(U, h, x, v, F_0, e) for e in watched],
                             fns)

    def attempt(h: float, iters: int, damped: bool = False
                ) -> tuple[list[float] | None, int, int]:
        """The stage solve of a step of size ``h`` from ``(t, x, v, F)`` in Python (the
        compiled stage Newton when ``compiled=True``; with ``damped``, the line-search
        fallback :meth:`~lumped.solvers.radau.StageSystem.solve_damped`): ``(U or None,
        iterations, factorisations)``; sets ``U``, ``Fref`` and ``F_seen`` for the error
        estimate."""
        nonlocal U, Fref, F_seen, stage_solve
        fk = [scene.external_forces(t + C[k] * h) for k in range(3)]
        U = (list(v) + list(F)) * 3
        # the force scale: the largest force or load met so far (never shrinks to 0)
        F_seen = max([F_seen] + [abs(Fe) for Fe in F] + [abs(fi) for fi in fk[2]])
        # ... and at least the force that changes the lightest mass's velocity by its
        # tolerance over the step (a force error below it does not show in x, v)
        Fref = max(F_seen, m_min * (max(abs(vi) for vi in v) + atol / rtol) / h)
        scale = ([atol + rtol * abs(vi) for vi in v]
                 + [rtol * max(abs(Fe), Fref) for Fe in F]) * 3
        if damped:
            return system.solve_damped(U, h, x, v, fk, kernels, scale, max_iters=iters)
        if stage_solve is None and opts["compiled"] is True:
            stage_solve = compiled_stage_solver(scene, modes)  # modes: the live list
        if stage_solve is None or cones:  # (locks in parallel: the cone split)
            return system.solve(U, h, x, v, fk, kernels, scale, max_iters=iters,
                                cones=cones or None, least_squares=t == infeasible_at
                                and modes == infeasible_modes)
        got = stage_solve(U, h, x, v, fk, scale, iters)
        U = got[0] if got[0] is not None else U
        return got

    def defect(U: list[float], h: float) -> float:
        """The largest scaled defect of the step's dense output against the held laws
        (:func:`lumped.solvers.dense_defect.dense_defect`)."""
        F0 = dense_start_forces(U, h)
        v_scale = max([abs(vi) for vi in v] + [abs(U[2 * n + i]) for i in range(N)])
        x_scale = max(abs(xi) for xi in x) + h * v_scale
        return dense_defect([system.element_nodes(U, h, x, v, F0, e) for e in range(E)],
                            kernels, spring, rtol, atol, v_scale, x_scale, F_seen)[0]

    def kink(U: list[float], h: float) -> float | None:
        """Where a step whose force split among locks in parallel kinks should end
        (:func:`lumped.solvers.split_kink.split_kink`), or None."""
        free = system.free_split
        if free is None or not cones:
            return None
        F0 = dense_start_forces(U, h)  # (where the dense output starts, after an event)
        nodes = {e: (system.element_nodes(U, h, x, v, F0, e)[1],
                     system.element_nodes(free, h, x, v, F0, e)[1]) for e in cones}
        scale = max(max(abs(Fe) for Fe in F0), max(abs(f) for e in cones for f in nodes[e][0]))
        return split_kink(nodes, cones, 0.5 * rtol * scale)

    def end_guard(U: list[float], h: float, which) -> tuple[float, float]:
        e = watched[which[0]]
        q, Fe = system.element_nodes(U, h, x, v, F, e)
        return guards[e](q[3], Fe[3])[which[1]], guard_tolerance(q[3], Fe[3])

    def state() -> dict:
        """The loop's state for the compiled loop (:mod:`lumped.solvers.adaptive_fast`)."""
        return {"t": t, "h": h, "x": x, "v": v, "F": F, "dF_n": dF_n, "F_seen": F_seen,
                "h_acc": h_acc, "err_acc": err_acc, "h_good": h_good, "stalled": stalled,
                "t_stop": breaks[bi] if bi < len(breaks) else t_final, "t_final": t_final,
                "prev_break": breaks[bi - 1] if bi > 0 else math.nan, "rtol": rtol,
                "atol": atol, "m_min": m_min, "max_steps": opts["max_steps"]}

    bridges: list[str] = []  # the stops bridged by backward Euler, and where

    def bridge_over() -> bool:
        """Backward Euler over the stop (``status``, ``message``) from the last accepted
        state (:mod:`lumped.solvers.bridge`), its steps in the output; then the mode the
        full laws choose at its end. Whether the run goes on."""
        nonlocal t, x, v, F, h, h_acc, dF_n, target, kept, stalled, creeping, \
            floor_tried, hold_check, status, message, committed, kink_cuts
        if len(bridges) >= MAX_BRIDGES:
            message += f" (after {len(bridges)} bridges by backward Euler, the most a run takes)"
            return False
        start = committed if committed[0] == t else (t, x, v, F)
        got = take_bridge(scene, start, len(bridges), rtol, h_big, t_final, settings.options,
                          opts["restitution"], dense, rows, events, ms.log, stats)
        if isinstance(got, str):
            message += f"; {got}"
            return False
        t0 = t
        t, x, v, F, to_end, delta = got
        committed = (t, list(x), list(v), list(F))
        bridges.append(f"[{t0!r}, {t!r}] over: {message}")
        stats["bridges"] = len(bridges)
        status, message = Status.SUCCESS, ""
        target, dF_n, h_acc = None, None, None
        kept, floor_tried, hold_check = False, False, True
        stalled = creeping = kink_cuts = 0
        tangent.clear()
        h = max(h_good, delta)
        ms.recent.clear()
        if not to_end:
            stop = at_event(t, h, "start")
            if stop:
                status, message = stop
        return True

    A_ = _A
    stalled = 0  # loop passes since the last accepted step (a guard against any cycle)
    creeping = 0  # accepted steps in a row below the step floor (landings; see below)
    kink_cuts = 0  # steps cut at a kink of the split since the last accepted step
    hold_check = True
    while t < t_final:
        if status is not Status.SUCCESS:
            # a stop mid-run: backward Euler bridges it (lumped.solvers.bridge), or the
            # run ends here
            if not (opts["bridge"] and status in _BRIDGED
                    and len(events) <= opts["max_events"] and bridge_over()):
                break
            continue
        if hold_check and target is None and not kept:
            # at rest in a mode that locks every node: the static balance up to the
            # break-out or the stop, no steps (the same in both loops)
            hold_check = False
            seg = hold_interval(scene, plan, ms, t, breaks[bi] if bi < len(breaks)
                                else t_final, x, v, F, dense, rows)
            if seg is not None:
                t, F, broke = seg[0], list(seg[1]), seg[2]
                committed = (t, list(x), list(v), list(F))
                stats["held_intervals"] += 1
                dF_n = h_acc = None
                stop = None
                if broke:
                    stop = at_event(t, h, "guard")
                    # the forces are continuous across a break-out: the balance's exact
                    # values, not the probe's (off by O(h_p), which the new branch's
                    # guard can read as a return at once)
                    F[:] = seg[1]
                elif bi < len(breaks) and t == breaks[bi]:
                    bi += 1
                    ms.time_event(t)
                    stop = at_event(t, h, "time")
                if stop:
                    status, message = stop
                    continue
                continue
        if fast is None and stats["steps"] >= adaptive_fast.COMPILE_AFTER and stats[
                "loop"].startswith(
                "python: not compiled yet"):  # a long run: compile the scene's loop now
            fast, stats["loop"] = compiled_loop(scene, plan, None, stats["steps"])
            ms.fast = fast
            if fast is not None:
                fast.setup(t_final, rtol, atol, m_min)
        if fast is not None and target is None and not kept and not ms.forces_from_probe:
            # the held-mode steps compiled (the same numbers as the loop below); it
            # returns before the pass this loop must take (a stop, an event, ...)
            st = state()
            before = stats["steps"]
            why = fast.run(st, modes, watched, stats, dense, rows)
            t, h, x, v, F, dF_n = st["t"], st["h"], st["x"], st["v"], st["F"], st["dF_n"]
            committed = (t, list(x), list(v), list(F))
            F_seen, h_acc, err_acc, h_good = st["F_seen"], st["h_acc"], st["err_acc"], st["h_good"]
            stalled = st["stalled"]
            if stats["steps"] > before:
                floor_tried, creeping = False, 0
            if why == "stopped":  # it took the step to the stop: a time event, or the end
                if bi < len(breaks) and t == breaks[bi]:
                    bi += 1
                    ms.time_event(t)
                    dF_n = h_acc = None
                    stop = at_event(t, h, "time")
                    if stop:
                        status, message = stop
                        continue
                continue
        stalled += 1
        if stalled > STALL_PASSES:
            status, message = Status.STEP_TOO_SMALL, (
                f"radau5 stopped at t = {t!r}: {STALL_PASSES} attempts without an accepted step "
                f"(step size {h!r})")
            continue
        if stats["steps"] >= opts["max_steps"]:
            status, message = Status.MAX_ITERS, (f"radau5 stopped at t = {t!r}: "
                                                 f"max_steps = {opts['max_steps']} reached")
            continue
        t_stop = breaks[bi] if bi < len(breaks) else t_final
        room = t_stop - t
        to_stop = False
        if t + 1.0001 * h >= t_stop or h >= room:
            h = room
            to_stop = True
        h_min = 16.0 * _EPS * max(abs(t), t_final * 1e-3)
        if h < h_min and target is None and watched and not floor_tried:
            # the held branches end here (e.g. a law whose slip branch has no continuation
            # at zero rate, where Newton fails on every step): let the full laws choose
            floor_tried = True
            h_acc = None
            changed = choose_again(h_good)
            if changed is None:
                continue
            if changed:
                h = h_good
                continue
        if h < h_min and target is None:
            status, message = Status.STEP_TOO_SMALL, (
                f"radau5: step size {h!r} below its floor {h_min!r} at t = {t!r}")
            continue
        # this attempt compiled (the same numbers), unless a Jacobian is singular
        got = None if fast is None else fast.attempt(
            t, h, x, v, F, dF_n, F_seen, breaks[bi - 1] if bi > 0 else math.nan, modes,
            watched)
        if got is not None:
            sol, its, nfac, err_norm, F_seen, hit_c = got
        else:
            sol, its, nfac = attempt(h, max_newton)
        if sol is None and target is not None:
            # a landing step near the singular end of a branch (a junction's
            # Herschel-Bulkley n < 1 dashpot stopping in finite time, its rate ~ sqrt(t* -
            # t)): Newton contracts slowly there and 10 iterations missed steps that 60
            # take; the bracket closed early, 1e-5 s before the stop, again and again
            # down to the step floor. Once more, with a longer budget
            sol, its_more, nfac_more = attempt(h, 6 * max_newton)
            its, nfac, got = its + its_more, nfac + nfac_more, None
        elif sol is None and not cones and stalled >= DAMPED_AFTER:
            # an eighth failure in a row: a stage that starts where its branch's rate is
            # flat in the force (Herschel-Bulkley n > 1 at its yield force), which the
            # simplified Newton misses at every step size; the line-search fallback
            sol, its_more, nfac_more = attempt(h, max_newton, damped=True)
            its, nfac, got = its + its_more, nfac + nfac_more, None
        stats["newton_iterations"] += its
        stats["factorizations"] += nfac
        stats["nfev"] += its + 1
        stats["njev"] += nfac
        stats["max_newton_iterations"] = max(stats["max_newton_iterations"], its)
        if sol is None:
            stats["rejected"] += 1
            h_acc = None
            if system.infeasible and target is None and t != infeasible_at:
                # the locks in parallel cannot carry the load together (no guard sees
                # it: the cone split keeps every force in its cone): let the full laws
                # choose the mode at t, once per t
                infeasible_at = t
                # (probes on the scale of the step that failed: the lock breaks within it)
                changed = choose_again(h)
                if changed is None:
                    continue
                if changed:
                    h = h_good
                    continue
                # the full laws keep the locks (a probe's step holds where the stage's
                # does not): the split of least squares stands, as before, until an
                # accepted step
                infeasible_modes = list(modes)
                continue
            # a landing step that Newton cannot take: no solution that far, the bracket
            # ends there (halving alone went below the step that held, to 0)
            h_next = None if target is None else target.failed_stage(h, t)
            if h_next is not None:
                h = h_next
                continue
            h *= 0.5
            if target is not None and h < h_min:  # no landing step holds: the event is
                target, dF_n = None, None  # at t itself, the full laws choose the mode
                old = list(modes)
                stop = at_event(t, h_good, "guard")
                if stop:
                    status, message = stop
                    continue
                kept, h = modes == old, h_good
                tangent.clear()
            continue
        if got is None:
            t_n0 = math.nextafter(t, math.inf) if (bi > 0 and t == breaks[bi - 1]) else t
            net_n = scene.net_forces(t_n0, F)
            q_n = scene.elongations(x, v)
            jac_n = [kernels[e](q_n[e], F[e])[1:] for e in range(E)]
            err = system.error(U, h, x, v, net_n, jac_n)
            err_norm = math.inf if err is None else system.error_norm(
                U, h, x, v, F, err, rtol, atol, dF_n, watched, Fref)
        fac = 0.9 * (2 * max_newton + 1) / (2 * max_newton + its)
        if not math.isfinite(err_norm):
            stats["rejected"] += 1
            h *= 0.2
            h_acc = None
            continue
        quot = max(0.125, min(5.0, err_norm ** 0.25 / fac))
        if err_norm > 1.0 and target is None:
            stats["rejected"] += 1
            h = h / quot
            h_acc = None
            continue
        s_kink = kink(sol, h) if target is None and kink_cuts < _KINK_CUTS else None
        if s_kink is not None:
            kink_cuts += 1
            # the split among locks in parallel kinks inside the step, and the force's
            # cubic overshoots its lock's interval: end the step at the kink
            stats["rejected"] += 1
            stats["split_rejected"] = stats.get("split_rejected", 0) + 1
            h *= s_kink
            h_acc = None
            continue
        # (the compiled attempt has found the crossing by the same algorithm; after an
        # event it saw the probe's forces: test here from the stage forces)
        hit = crossing(sol, h) if got is None or ms.forces_from_probe or tangent else hit_c
        while kept and hit is not None and (hit[0] * h <= 16 * _EPS * max(1.0, abs(t)) or (
                tangent and hit[0] <= 1.001 * C[0])):
            # the full laws kept the mode at t: a guard read crossed at t is a tangency
            # (round-off), but another guard that crosses later in the step is still an
            # event (a Coulomb element stuck at exactly its yield force beside two
            # stuck dashpots hid their break-out, and the step went on to 2 % beyond
            # their yield forces). One crossed by the first stage already is the state
            # at t too (a stuck Coulomb element whose stage split sits a hair beyond its
            # yield force, beside a junction's Herschel-Bulkley dashpot stopping: landed
            # on again and again, the run crept on by 1e-15 s)
            tangent.add(hit[1])
            hit = crossing(sol, h)
        if target is not None:  # a landing step: bracket the event by end-of-step values
            if hit is not None and hit[1] != target.which and hit[0] < 1.0:
                # another guard crosses first; at t itself: no landing, the event is at t
                at_t = hit[0] * h <= 16 * _EPS * max(1.0, abs(t))
                target = None if at_t else Landing(hit[1], h, end_guard(sol, h, hit[1])[0],
                                                   target.h_found)
                h = h if at_t else hit[0] * h
                continue
            g_end, tol = end_guard(sol, h, target.which)
            if not target.landed(g_end, tol, t):
                h = target.next_size(h, g_end, hit[0] if hit is not None and hit[1]
                                     == target.which and hit[0] < 1.0 else None)
                continue
        elif hit is not None and hit[0] < 1.0 and not (
                kept and hit[0] * h <= 16 * _EPS * max(1.0, abs(t))):
            s_hit = hit[0]
            if s_hit * h <= 16 * _EPS * max(1.0, abs(t)):
                # the event is at t itself: choose the mode again, no step
                dF_n = None
                old = list(modes)
                stop = at_event(t, h, "guard")
                if stop:
                    status, message = stop
                    continue
                # the full laws keep the mode at t (a tangency, round-off): the retried
                # step is accepted unless a guard fails later in it
                kept = modes == old
                tangent.clear()
                continue
            target = Landing(hit[1], h, end_guard(sol, h, hit[1])[0], h)
            h = s_hit * h
            continue
        if ms.forces_from_probe and target is None:
            # the first step after an event, no guard crossed in it: its dense output
            # against the held laws between the nodes (a junction's Herschel-Bulkley
            # n < 1 dashpot breaking out starts as (t - t*)^n, which the error estimate
            # does not see)
            d = defect(sol, h)
            if d > 1.0:
                stats["rejected"] += 1
                stats["defect_rejected"] = stats.get("defect_rejected", 0) + 1
                h *= max(0.1, min(0.5, 0.8 / d))
                h_acc = None
                continue
        F_0 = start_forces(sol) if checked else F
        folded = [e for e in checked
                  if fold_crossed(kernels[e], *system.element_nodes(sol, h, x, v, F_0, e))]
        if folded:
            el = scene.elements[folded[0]]
            status, message = Status.BRANCH_LOST, (
                f"element {el.name!r} (law {el.law_name!r}) reaches a fold of its law "
                f"between t = {t!r} and {t + h!r}: dR/dq or dR/dF changes sign, there is no "
                "solution continuous with the past beyond it")
            continue
        # accept
        Y = []
        for k in range(3):
            Xk = []
            for i in range(N):
                s_ = 0.0
                for j in range(3):
                    s_ += A_[k][j] * sol[j * n + i]
                Xk.append(x[i] + h * s_)
            Y.append(Xk + sol[k * n:k * n + N] + sol[k * n + N:k * n + n])
        F0 = dense_start_forces(sol, h)
        ms.forces_from_probe = False
        dense.add(t, h, x + v + F0, Y)
        dF_n = system.end_slope(sol, h, F)
        event_here = target is not None
        h_found = target.h_found if event_here else 0.0
        ms.hint = watched[target.which[0]] if event_here else None
        target = None
        t_prev, t = t, (t_stop if to_stop else t + h)
        x = Y[2][:N]
        v = Y[2][N:2 * N]
        F = Y[2][2 * N:]
        committed = (t, list(x), list(v), list(F))
        stats["steps"] += 1
        kink_cuts = 0
        rows.append(row_of(t, x, v, F))
        # a landing step is exempt from the step floor; landings of ulps, one after the
        # other, with the full laws keeping the mode each time, move t by nothing (a
        # junction on a Coulomb element, a Herschel-Bulkley n = 0.3 dashpot and a spring
        # in parallel: 2000 steps moved t by 1e-12, and max_steps = 1e6 would take hours)
        # (or 1e-12 of the run: a junction on one Coulomb element beside a mass landed
        # 5000 times on its guard with steps of 3e-14 s, 40 times the floor, 77 s a run)
        creep_floor = max(h_min, _CREEP_FRACTION * t_final)
        creeping = creeping + 1 if t - t_prev < creep_floor else 0
        if creeping >= _CREEP_STEPS:
            el = scene.elements[ms.hint] if ms.hint is not None else None
            status, message = Status.STEP_TOO_SMALL, (
                f"radau5 stopped at t = {t!r}: {creeping} accepted steps in a row below the "
                f"creep floor {creep_floor!r} (the run creeps"
                + (f", landing again and again on a guard of element {el.name!r} (law "
                   f"{el.law_name!r})" if el is not None else "") + ")")
            continue
        ms.mark_free(t_prev, t, x, v, F)  # locks on cycles: forces not unique
        # the step size for the next step (Gustafsson's predictive controller)
        h_new = h / quot
        if h_acc is not None and err_norm > 0.0:
            facgus = (h_acc / h) * (err_norm ** 2 / err_acc) ** 0.25 / 0.9
            facgus = max(0.125, min(5.0, facgus))
            h_new = h / max(quot, facgus)
        h_acc, err_acc = h, max(1e-2, err_norm)
        h_good, floor_tried, kept, stalled = h, False, False, 0
        h_big = max(h_big, h)
        tangent.clear()
        # after a landing the step goes on from the size that found the event (the
        # landing step can be ulps long when the event sits at the step's start)
        h = max(h_new, h_found)
        is_break = to_stop and bi < len(breaks) and t == breaks[bi]
        if is_break:
            bi += 1
            ms.time_event(t)
        if event_here or is_break:
            dF_n = h_acc = None
            stop = at_event(t, h, "guard" if event_here else "time")
            if stop:
                status, message = stop
                continue
    stats["events"] = len(events)
    if bridges:
        message = (message + " " if message else "") + (
            f"radau5 bridged {len(bridges)} stop(s) by backward Euler: " + "; ".join(bridges))
    if status is not Status.SUCCESS and settings.throw:
        error = BranchError if status is Status.BRANCH_LOST else SolverError
        raise error(message, status=status, t=t, where="", residual=math.nan)
    data = output_data(rows, dense, dt, settings.t_end, t)
    return RawRun(data, stats, status, message, events, dense if len(dense) else None,
                  indeterminate=ms.log.result())

