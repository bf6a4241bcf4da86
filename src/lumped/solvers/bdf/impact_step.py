r"""A fixed step across an impact: locate it, apply the impulse, finish the step.

Used by :func:`lumped.solvers.bdf.fixed_step.run_bdf` when a trial step ends with a
spring-like element on a *locking* branch that was not locked at the start of the step
(:func:`lumped.solvers.nonsmooth.impacts.locking_elements`) while the element's ends still approach
the lock (the impulse that would stop them is not negligible). Then, from the state
``(x_n, v_n)`` at ``t_n``:

1. **Locate.** Backward-Euler substeps of size ``s`` from ``t_n`` show whether the lock is
   reached by ``t_n + s``; bisection on ``s`` brackets the impact time to ``1e-10 dt``.
   The state just before it is the last substep that stays unlocked (``t_n + s_lo``),
   the first locked one ends at ``t_n + s_hi``.
2. **Impulse.** At ``t_n + s_hi``, with the positions there (on the lock) and the
   velocities of the free motion just before (``t_n + s_lo``),
   :func:`lumped.solvers.nonsmooth.impacts.impact_velocities` gives the velocities
   after the impact for the elements locked at ``t_n + s_hi`` (restitution ``e``, ``0``
   by default: momentum conserved, the locked rates stopped), the impulse of each element
   and the kinetic energy lost; each newly locked element gives one
   :class:`~lumped.solvers.status.Event` (``kind="impact"``), the energy split among them
   as ``P_e * rate_e`` (their shares of ``1/2 P^T B v``).
3. **Finish.** One backward-Euler substep from ``t_n + s_hi`` to ``t_{n+1}`` with the new
   velocities (where its Newton fails, 2 to 16 of them: :func:`halved_steps`). If it
   locks another element (not negligibly: a second string taut within the step), steps
   1-2 locate and apply that impact on the rest of the step, in turn (at most
   :data:`_MAX_IMPACTS`; beyond, the step is Moreau's). Elements locked at the end get
   rate zero; where that is more than round-off, the forces come from a substep a hair
   long from the stopped velocities (a dashpot beside the lock follows its new rate;
   ``1e-10 dt``, longer where its Newton fails: :data:`_HAIRS`; on a scene with moving
   supports it ends at ``t + h``, and where every hair fails, the balance of
   accelerations gives the forces: ``q + o_e`` rounds to ``ulp(x_s)``). A lock reached in the
   second half of the step takes the forces of its locked and stuck elements at
   ``t_{n+1}`` from the balance of accelerations (:func:`_forces_after`,
   :mod:`lumped.solvers.nonsmooth.lock_forces`: on the lock a remainder ``h`` fixes the rate only to
   ``ulp(x) / h``, hence the forces only to ``m ulp(x) / h^2``). The caller restarts the
   multistep history (BDF2 takes a BDF1 step next).

Every substep is a backward-Euler step, dissipative for passive laws, and the impulse
only removes energy, so the energy ledger never gains. Backward Euler *across* the lock
(without step 1-2) is already Moreau's time-stepping with restitution 0 and converges at
first order; locating the impact keeps the velocity jump where it belongs, makes the
state after the step exact to the substep's error (``x = L``, ``v = 0`` for a single mass),
and records the impact.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from ...scene import Mass, Scene
from ...scene.supports import clock_rates
from ..implicit.globalize import solve_globalized
from ..implicit.step_system import make_evaluate
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.semismooth import newton_solve
from ..nonsmooth.impacts import impact_velocities, locking_elements, onto_locks
from ..nonsmooth.lock_forces import forces_with_held
from ..status import Event

__all__ = ["ImpactStep", "be_substep", "halved_steps", "impact_step", "impulse_is_negligible"]

#: Bisection of the impact time stops when the bracket is below this fraction of dt.
_LOCATE_RTOL = 1e-10
#: Impacts located within one step at most; beyond, the step is Moreau's (an accumulation).
_MAX_IMPACTS = 16
#: The substep "a hair after" the end of a step (for the forces there) is this many times
#: ``_LOCATE_RTOL dt`` long, the next where Newton fails on the shorter one.
_HAIRS = (1.0, 1e3, 1e6)
#: A lock reached with less than this fraction of the step left takes the forces of its
#: locked and stuck elements at the end of the step from the balance of accelerations
#: (:func:`_forces_after`).
_SHORT_REST = 0.5


@dataclass
class ImpactStep:
    """Outcome of :func:`impact_step`: the state at ``t_{n+1}``, the events, counters,
    and the failed Newton result if a substep failed (then the state is the last good
    one)."""

    x: list[float]
    v: list[float]
    F: list[float]
    events: list[Event] = field(default_factory=list)
    newton_iterations: int = 0
    solves: int = 0
    failure: NewtonResult | None = None
    failure_t: float = 0.0
    #: Two states per impact, just before and just after it, ``(t, x, v, F)``: the knots
    #: of the dense output inside the step (the velocities jump there). Forces after an
    #: impact are those the motion reaches next (the next impact's or the step's end).
    knots: list[tuple[float, list[float], list[float], list[float]]] = \
        field(default_factory=list)


def be_substep(scene: Scene, t_end: float, h: float, x0: list[float], v0: list[float],
               F0: list[float], options: NewtonOptions) -> tuple[list[float], list[float],
                                                                 list[float], NewtonResult]:
    """One backward-Euler step of size ``h`` ending at ``t_end`` from ``(x0, v0)``,
    Newton started at ``(v0, F0)``; returns ``(x1, v1, F1, result)``."""
    N, E = len(scene.nodes), len(scene.elements)
    f = scene.external_forces(t_end)
    clock = getattr(scene, "support_clock", None)
    if clock is not None:  # support offsets at the substep's end
        clock(t_end)
    cm = [nd.m / h if isinstance(nd, Mass) else 0.0 for nd in scene.nodes]
    qs, rq, rf = [0.0] * E, [0.0] * E, [0.0] * E
    ev = make_evaluate(scene, h, cm, [0.0] * N, [1.0] * N, list(v0), list(x0), f, qs, rq,
                        rf, roundoff=True)
    res = newton_solve(ev, list(v0) + list(F0), options, min_norm=True)
    if res.code is not NewtonCode.SUCCESS:
        res = solve_globalized(scene, ev, h, list(x0), list(v0), list(F0), options,
                               sweeps=True)
    v1 = res.u[:N]
    x1 = [x0[i] + h * v1[i] for i in range(N)]
    return x1, v1, res.u[N:], res


def halved_steps(scene: Scene, t0: float, dt: float, x: list[float], v: list[float],
                 F: list[float], options: NewtonOptions, depth: int = 4):
    """The step ``[t0, t0 + dt]`` as ``2**k`` backward-Euler substeps (``k`` from 1 to
    ``depth``), the first ``k`` whose substeps all converge: a last resort when the step's Newton
    fails (closer starts). Returns ``(x, v, F, iterations)`` or ``None``."""
    its = 0
    for k in range(1, depth + 1):
        n = 2**k
        h = dt / n
        xs, vs, Fs = list(x), list(v), list(F)
        for j in range(1, n + 1):
            xs, vs, Fs, res = be_substep(scene, t0 + j * h, h, xs, vs, Fs, options)
            its += res.iterations
            if res.code is not NewtonCode.SUCCESS:
                break
        else:
            return xs, vs, Fs, its
    return None


def impulse_is_negligible(scene: Scene, v: list[float], new: list[int],
                          impulse_floor: float = 0.0) -> bool:
    """True when stopping the newly locked elements ``new`` at velocities ``v`` costs no
    kinetic energy beyond round-off (a lock reached at rest: a branch switch, no impact;
    measured with restitution 0 whatever the scene's, as the size of the impact), or
    when no impulse exceeds ``impulse_floor`` (the round-off of a step's momentum
    change, ``eps dt |F|``: masses at rest whose velocities are round-off, ``1e-19``,
    lose all of their kinetic energy ``1e-37`` at the lock, which the relative test
    alone reads as an impact)."""
    _, impulses, lost = impact_velocities(scene, [0.0] * len(v), v, new, 0.0)
    if impulse_floor > 0.0 and all(abs(p) <= impulse_floor for p in impulses):
        return True
    kinetic = sum(0.5 * m * vi * vi for m, vi in zip(scene.masses, v, strict=True))
    return lost <= 1e-12 * kinetic + 1e-300


def _branch_index(law, q: float, F: float) -> int:
    try:
        from ...codegen.branches import law_branches

        return int(law_branches(law).branch(q, F))
    except Exception:  # noqa: BLE001 - no branch machinery for this law: n/a
        return -1


def impact_step(scene: Scene, t0: float, dt: float, x: list[float], v: list[float],
                F: list[float], locked0: set[int], options: NewtonOptions,
                restitution: float = 0.0) -> ImpactStep:
    """The step ``[t0, t0 + dt]`` across one impact or several (see the module notes)."""
    out = ImpactStep(list(x), list(v), list(F))

    def sub(s: float, xs, vs, Fs, t_end):
        x1, v1, F1, res = be_substep(scene, t_end, s, xs, vs, Fs, options)
        out.newton_iterations += res.iterations
        out.solves += 1
        return x1, v1, F1, res

    def to_end(s: float, xs, vs, Fs):
        # the substep over the rest of the step; where its Newton fails, the rest as
        # 2 to 16 backward-Euler substeps (halved_steps: closer starts, as the caller's
        # last resort for a whole step; a lock reached inside them is Moreau's, stopped
        # at the end below)
        end = sub(dt - s, xs, vs, Fs, t0 + dt)
        if end[3].code is NewtonCode.SUCCESS:
            return end
        halved = halved_steps(scene, t0 + s, dt - s, xs, vs, Fs, options)
        if halved is None:
            return end
        out.newton_iterations += halved[3]
        res = NewtonResult(list(halved[1]) + list(halved[2]), NewtonCode.SUCCESS,
                           halved[3], 0, 0, 0, [], 0, [])
        return halved[0], halved[1], halved[2], res

    def hair_after(xs, vs, Fs):
        # a substep a hair long from the end of the step, for the forces there; a lock
        # whose elongation rounds a few ulps off its value asks a Newton step of size h
        # for forces of m ulp(x) / h^2 (1e7 for h = 6e-13, a taut string between two
        # masses), which it cannot polish: a longer hair then
        for k in _HAIRS:
            h = min(k * _LOCATE_RTOL * dt, dt)
            got = sub(h, xs, vs, Fs, _after(scene, t0 + dt, h))
            if got[3].code is NewtonCode.SUCCESS:
                return got
        if getattr(scene, "support_clock", None) is not None:
            # a lock on a moving support: q + o_e(t + h) rounds to ulp(x_s), the hair's
            # forces to m ulp(x_s) / h^2 however long it is; the balance of
            # accelerations instead (its lock rows read the support's acceleration)
            held_now = set(locking_elements(scene, xs, vs, Fs)) | held
            after = _forces_after(scene, t0 + dt, dt, xs, vs, Fs, held_now, sub)
            if after is not None:
                return (xs, *after, NewtonResult(list(after[0]) + list(after[1]),
                                                 NewtonCode.SUCCESS, 0, 0, 0, 0, [], 0, []))
        return got

    # s: the time into the step reached so far, so that the first substep is the step
    # itself (``dt``, not ``t0 + dt - t0``, which may round an ulp off it: the same
    # system with another ``h``)
    s, xs, vs, Fs, held = 0.0, list(x), list(v), list(F), set(locked0)
    for located in range(_MAX_IMPACTS + 1):
        rest = dt - s
        end = to_end(s, xs, vs, Fs)
        if end[3].code is not NewtonCode.SUCCESS:
            out.failure, out.failure_t = end[3], t0 + dt
            return out
        new = [e for e in locking_elements(scene, *end[:3]) if e not in held]
        if (not new or located == _MAX_IMPACTS
                or (s > 0.0 and impulse_is_negligible(scene, vs, new))):
            # backward Euler locks nothing new in the rest of the step (or reaches a lock
            # at rest: a branch switch); or the impacts located in this step reached
            # _MAX_IMPACTS (an accumulation): Moreau's step to the end, the locks
            # reached there stopped below
            x1, v1, F1 = end[:3]
            break
        located = _locate_impact(scene, t0 + s, rest, dt, xs, vs, Fs, held, end, sub,
                                 options, out)
        xh, v_after, Fl, s_hi, held = _apply_impact(scene, t0 + s, located, held,
                                                    restitution, out.events)
        t_hit = (t0 + s) + s_hi  # the events' time
        out.knots.append((t_hit, xh, list(located[1][1]), list(Fl)))
        out.knots.append((t_hit, xh, list(v_after), []))
        s += s_hi
        if dt - s <= _LOCATE_RTOL * dt:  # the impact ends the step: forces from a hair after
            x1, v1, F1, res = hair_after(xh, v_after, Fl)
            if res.code is not NewtonCode.SUCCESS:
                out.failure, out.failure_t = res, t0 + dt
                return out
            x1 = xh
            break
        xs, vs, Fs = xh, v_after, Fl
    # locked at the end: their rates are zero (a short remainder turns the rounding of
    # q = x_hat + h v on the lock into a spurious rate ulp / h; an element that locked
    # within the remainder at rest, or after _MAX_IMPACTS, gets Moreau's inelastic
    # velocity). Where that changes a velocity beyond round-off -- a junction's too,
    # which carries no kinetic energy -- the forces are those a hair after (the
    # rate-dependent laws, e.g. a dashpot beside the lock, follow the new velocities)
    end_locked = locking_elements(scene, x1, v1, F1)
    v_stop = impact_velocities(scene, x1, v1, end_locked, 0.0, forces=F1)[0] if end_locked \
        else v1
    v_scale = max(abs(vi) for vi in v1) if v1 else 0.0
    if any(abs(a - b) > 1e-12 * v_scale for a, b in zip(v_stop, v1, strict=True)):
        _, v1, F1, res = hair_after(x1, v_stop, F1)
        if res.code is not NewtonCode.SUCCESS:
            out.failure, out.failure_t = res, t0 + dt
            return out
        end_locked = locking_elements(scene, x1, v1, F1)
    if end_locked:
        v1 = impact_velocities(scene, x1, v1, end_locked, 0.0, forces=F1)[0]
    if s > 0.0 and dt - s < _SHORT_REST * dt:
        # an impact located late in the step: a lock's force comes from the momentum
        # balance m (v1 - v0) / h, with v1 known only to ulp(x) / h (the rounding of
        # q = x + h v on the lock), so after a remainder h much shorter than dt the forces
        # carry m ulp(x) / h^2 (up to the whole load): the locked and stuck elements'
        # forces from the balance of accelerations instead
        after = _forces_after(scene, t0 + dt, dt, x1, v1, F1, held, sub)
        if after is not None:
            v1, F1 = after
    out.x, out.v, out.F = x1, v1, F1
    for k in range(1, len(out.knots), 2):  # forces after an impact: those reached next
        t, x, v, _ = out.knots[k]
        out.knots[k] = (t, x, v, out.knots[k + 1][3] if k + 1 < len(out.knots) else F1)
    return out


def _after(scene, t: float, h: float) -> float:
    """The end of a substep ``h`` long from the end ``t`` of the step: ``t + h`` on a
    scene with moving supports (a lock on a support moves in it, and a substep whose
    laws read the support at ``t`` holds its mass still: forces of ``m v_s / h``), else
    ``t`` (the forcing read at the step's end)."""
    return t + h if getattr(scene, "support_clock", None) is not None else t


def _forces_after(scene, t1, dt, x1, v1, F1, held, sub):
    """The velocities and forces at ``t1`` when the lock is reached late in a step.

    A backward-Euler substep ``dt`` long from ``(x1, v1)`` (the forcing read at ``t1``)
    tells which of the elements locked at the impact (``held``) are still locked; their
    rates at ``t1`` are set to zero (the remainder leaves them ``ulp(x) / h``), a dashpot
    whose rate that changes takes the force its law gives at the new rate, and the forces
    of the locks and of the stuck dashpots come from the balance of accelerations
    (:func:`lumped.solvers.nonsmooth.lock_forces.forces_from_accelerations`), not from the short
    remainder. Returns ``(v1, F1)``, or ``None`` (the remainder's forces stand) when the
    substep fails, keeps none of ``held`` locked, or the balance has no solution."""
    x2, v2, F2, res = sub(dt, x1, v1, F1, _after(scene, t1, dt))
    if res.code is not NewtonCode.SUCCESS:
        return None
    still = [e for e in locking_elements(scene, x2, v2, F2) if e in held]
    if not still:
        return None
    v_stop = impact_velocities(scene, x1, v1, still, 0.0, forces=F2)[0]
    F_new = forces_with_held(scene, t1, x1, v_stop, F1, still,
                             q_before=scene.elongations(x1, v1))
    if F_new is None:
        return None
    return v_stop, F_new


def _locate_impact(scene, ts, rest, dt, x, v, F, held, end, sub, options, out):
    """Bisection of the first lock in ``[ts, ts + rest]`` (backward-Euler substeps from
    ``(x, v, F)`` at ``ts``; ``end`` is the substep over all of it, which locks an element
    not in ``held``). A trial substep whose Newton fails is taken as 2 to 16 substeps
    (:func:`halved_steps`, their iterations added to ``out``), as the rest of the step
    is. Returns ``(s_lo, lo_state, s_hi, hi_state)``."""
    lo, hi = 0.0, rest
    lo_state = (list(x), list(v), list(F))
    hi_state = end
    while hi - lo > _LOCATE_RTOL * dt:
        mid = 0.5 * (lo + hi)
        trial = sub(mid, x, v, F, ts + mid)
        if trial[3].code is not NewtonCode.SUCCESS:
            # closer starts (a string just taut beside a stuck Herschel-Bulkley n < 1
            # dashpot fixes the rate only to ulp(x) / h, where that law is steep)
            halved = halved_steps(scene, ts, mid, x, v, F, options)
            if halved is None:
                break  # keep the bracket found so far
            out.newton_iterations += halved[3]
            trial = (*halved[:3], trial[3])
        if any(e not in held for e in locking_elements(scene, *trial[:3])):
            hi, hi_state = mid, trial
        else:
            lo, lo_state = mid, trial[:3]
    return lo, lo_state, hi, hi_state


def _apply_impact(scene, ts, located, held, restitution, events):
    """The impact at ``ts + s_hi`` of a bracket from :func:`_locate_impact`: positions on
    the locks, the velocities after, one event per newly locked element (appended to
    ``events``). Returns ``(x, v_after, F_before, s_hi, locked)``."""
    _, (xl, vl, Fl), hi, hi_state = located
    xh, vh, Fh = hi_state[:3]
    clock = getattr(scene, "support_clock", None)
    if clock is not None:  # the locks, the snap onto them and the impact law at ts + s_hi
        clock(ts + hi)
    locked = locking_elements(scene, xh, vh, Fh)
    xh = onto_locks(scene, xh, Fh, locked)
    new = [e for e in locked if e not in held]
    # the impact at ts + s_hi: positions on the lock (x_hi), velocities of the free
    # motion just before it (v_lo); the bracket is 1e-10 dt wide
    v_after, impulses, lost = impact_velocities(scene, xh, vl, locked, restitution,
                                                   forces=Fh)
    moving = clock_rates(scene)  # a support's o_e' adds to the rate
    rates = [(vl[scene.elem_b[e]] if scene.elem_b[e] >= 0 else 0.0)
             - (vl[scene.elem_a[e]] if scene.elem_a[e] >= 0 else 0.0)
             + (moving[e] if moving is not None else 0.0) for e in locked]
    shares = {e: abs(p * r) for e, p, r in zip(locked, impulses, rates, strict=True)}
    total = sum(shares[e] for e in new) or 1.0
    qh = scene.elongations(xh, vh)
    ql = scene.elongations(xl, vl)
    for e, p in zip(locked, impulses, strict=True):
        if e not in new:
            continue
        law = scene.elements[e].law
        events.append(Event(
            t=ts + hi, element=scene.elements[e].name, kind="impact",
            from_branch=_branch_index(law, ql[e], Fl[e]),
            to_branch=_branch_index(law, qh[e], Fh[e]),
            impulse=float(p), energy_lost=float(lost * shares[e] / total),
        ))
    return xh, v_after, Fl, hi, set(locked)
