r"""The event logic of the adaptive method: branch guards along a step, the first crossing,
and the choice of the next mode.

A *mode* holds every element's law on one smooth branch (:func:`lumped.codegen.branches.
law_branches`). The branch's guards ``g(q, F) >= 0`` say where it is admissible. After a
step, the guards are evaluated along the step's collocation polynomial
(:func:`first_crossing`); the first point where one turns negative is located on the
polynomial by Brent's method to a few ulps of ``t`` and the step is redone to end there.

At the event the next mode is what the full, nonsmooth laws choose in the limit of a
vanishing implicit step (:func:`select_modes`): one backward-Euler step of the full laws
(the semismooth Newton of the fixed-step methods) of a size ``h_p`` far below the
method's step, read through ``law_branches(...).branch(q, F)``. As ``h_p -> 0`` this is the
rule of :func:`lumped.solvers.implicit.initial_state.consistent_initial_state`: a dashpot that
reaches ``|F| = tau`` sticks if the rest of the system can be balanced by a force inside
the cone, else it reverses. A dashpot that enters a rate lock (``q = const``) gets its
rate set exactly (:func:`hold_rate_locks`), so a stuck velocity is exactly zero.
"""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Callable, Sequence

from scipy.optimize import brentq

from ...scene import Mass, Scene
from ..implicit.branch_check import left_branch
from ..implicit.globalize import solve_globalized
from ..implicit.step_system import make_evaluate
from ..newton.criteria import residual_ok
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.semismooth import newton_solve
from ..radau.stage import dense_weights

__all__ = ["SAMPLES", "first_crossing", "first_crossing_on", "select_modes", "hold_rate_locks",
           "snap_to_locks", "lock_cones", "apply_impacts", "guard_tolerance", "fold_crossed"]

#: Points ``s`` in ``(0, 1]`` of a step where the guards are sampled (in order).
SAMPLES = tuple(k / 8.0 for k in range(1, 9))
_EPS = sys.float_info.epsilon


def first_crossing(
    guard_at: Callable[[float], tuple[float, int]],
    guard_of: Callable[[float, int], float],
    samples: Sequence[float] = SAMPLES,
) -> tuple[float, int] | None:
    """The first ``s`` in ``(0, 1]`` where a guard of the step turns negative, if any.

    Parameters
    ----------
    guard_at : callable
        ``s -> (g_min, which)``: the smallest guard value at ``t_n + s h`` (already
        shifted by its tolerance, so that ``g_min < 0`` means "left the branch") and the
        index of that guard.
    guard_of : callable
        ``(s, which) -> g``: one guard (shifted likewise) along the step.
    samples : sequence of float
        Increasing sample points ending at 1.

    Returns
    -------
    (s, which) or None
        The root of the first violated guard, located by Brent's method on
        ``[s_prev, s]`` to ``|ds| <= 4 eps``; ``None`` if no sample is negative.
    """
    prev = 0.0
    for s in samples:
        g, which = guard_at(s)
        if g < 0.0:
            g0 = guard_of(prev, which)
            if not g0 > 0.0:
                return prev, which
            root = brentq(lambda z, w=which: guard_of(z, w), prev, s, xtol=4e-16, rtol=1e-15)
            return root, which
        prev = s
    return None


def first_crossing_on(nodes: Sequence[tuple[tuple[float, ...], tuple[float, ...]]],
                      guard_fns: Sequence[Callable]) -> tuple[float, tuple[int, int]] | None:
    """:func:`first_crossing` for one step: ``nodes[w]`` holds the ``(q, F)`` values of a
    watched element at ``s = 0, c_1, c_2, 1`` (:meth:`StageSystem.element_nodes`) and
    ``guard_fns[w]`` its branch's guards. Returns ``(s, (w, j))`` (guard ``j`` of element
    ``w``) or ``None``."""
    cache: dict[float, list] = {}

    def values(s: float) -> list:
        got = cache.get(s)
        if got is None:
            l1, l2, l3 = dense_weights(s)
            got = []
            for (q, F), guards in zip(nodes, guard_fns, strict=True):
                qs = q[0] + (l1 * (q[1] - q[0]) + l2 * (q[2] - q[0]) + l3 * (q[3] - q[0]))
                Fs = F[0] + (l1 * (F[1] - F[0]) + l2 * (F[2] - F[0]) + l3 * (F[3] - F[0]))
                got.append((guards(qs, Fs), guard_tolerance(qs, Fs)))
            cache[s] = got
        return got

    def guard_at(s: float):
        best, which = math.inf, (0, 0)
        for w, (gs, tol) in enumerate(values(s)):
            for j, g in enumerate(gs):
                if g + tol < best:
                    best, which = g + tol, (w, j)
        return best, which

    def guard_of(s: float, which) -> float:
        w, j = which
        return values(s)[w][0][j]

    return first_crossing(guard_at, guard_of)


def select_modes(
    scene: Scene,
    branches: Sequence,
    t: float,
    x: list[float],
    v: list[float],
    F: list[float],
    h_probe: float,
    options: NewtonOptions | None = None,
) -> tuple[list[int], list[float], list[float]] | str:
    """The branch of every element right after ``t``, by a vanishing implicit step.

    One backward-Euler step of size ``h_probe`` of the full laws from ``(x, v)`` at ``t``
    (forcing at ``t + h_probe``), solved by the semismooth Newton of the fixed-step
    methods; each element's branch is ``branches[e].branch(q, F)`` at the result.

    Returns
    -------
    (modes, v_probe, F_probe) or str
        The branch indices, the velocities and forces of the probe step (the right limits
        at ``t``, up to ``O(h_probe)``), or a message when the step has no solution.
    """
    N = len(scene.nodes)
    cm = [n.m / h_probe if isinstance(n, Mass) else 0.0 for n in scene.nodes]
    f = scene.external_forces(t + h_probe)
    uref = list(v)
    x_hat = list(x)
    E = len(scene.elements)
    qs, rq, rf = [0.0] * E, [0.0] * E, [0.0] * E
    # steep branches in their inverse form: the same zeros, a root Newton can reach
    kernels = [branches[e].stage_law_for(el.law.kernel) or el.law.kernel
               for e, el in enumerate(scene.elements)]
    evaluate = make_evaluate(scene, h_probe, cm, [0.0] * N, [1.0] * N, uref, x_hat, f,
                              qs, rq, rf, roundoff=True, kernels=kernels)
    probe_opts = _probe_options(options)
    # as the fixed-step methods: locks in parallel (a singular step) by the minimum-norm
    # correction, hard points of a law (Herschel-Bulkley n < 1 at its yield force) by the
    # globalised solve
    res = _accept_at_roundoff(
        newton_solve(evaluate, list(v) + list(F), probe_opts, min_norm=True),
        evaluate, probe_opts)
    if res.code is not NewtonCode.SUCCESS:
        res = solve_globalized(scene, evaluate, h_probe, x_hat, list(v), list(F), probe_opts)
    if res.code is not NewtonCode.SUCCESS:  # the balance sweeps (issue 11)
        try:
            res = solve_globalized(scene, evaluate, h_probe, x_hat, list(v), list(F),
                                   probe_opts, sweeps=True)
        except ValueError:  # the bounded split of a force fixed by its law (lo = hi),
            pass  # until globalize drops such unknowns (branch s3-netbdf): as before
    if res.code is not NewtonCode.SUCCESS:
        return (f"no motion continues from t = {t!r}: the implicit step of the full laws "
                f"({h_probe!r} s) failed ({res.code.value})")
    v_p = res.u[:N]
    F_p = res.u[N:]
    x_p = [x[i] + h_probe * v_p[i] for i in range(N)]
    q = scene.elongations(x_p, v_p)
    modes = [_branch_read(branches[e], q[e], F_p[e], kernels[e] is not
                          scene.elements[e].law.kernel) for e in range(E)]
    return modes, v_p, F_p


def _branch_read(lb, q: float, F: float, steep: bool) -> int:
    """The branch of a law at ``(q, F)``: :attr:`LawBranches.branch`, except where a
    steep branch solved in its inverse form holds there and the branch read does not.

    Herschel-Bulkley ``n = 0.3`` starting to slip (``tau = 1``): at the probe's rate
    ``2e-6`` its force is ``tau + 1.3e-19``, which rounds to ``tau``, where the law
    reads its stuck branch (``q = 0``, violated by ``2e-6``); the held stuck mode was then
    left again at once, an event every ``1e-6`` s. The branch whose residual holds to
    round-off of its terms is the one the probe solved."""
    i = lb.branch(q, F)

    def holds(j: int) -> bool:
        k = lb.stage_kernel_for(j)
        return abs(k(q, F)[0]) <= 8.0 * _EPS * k.magnitude(q, F)

    if not steep or holds(i):
        return i
    return next((j for j, info in enumerate(lb.info) if info.stage is not None and holds(j)),
                i)


def _accept_at_roundoff(res: NewtonResult, evaluate, options: NewtonOptions) -> NewtonResult:
    """``res`` as a success when Newton ran out of iterations on a point whose residual
    test holds.

    A lock held by positions (a taut string, ``x_b + h v_b - x_a - h v_a = L``) fixes the
    rates only to ``ulp(x) / h``, and the forces that hold it to ``m ulp(x) / h^2``: on
    a probe step of ``h ~ 1e-7`` the iterates cycle between neighbours whose residuals
    are all at round-off while the update test, which asks for ``rtol |u|`` in the force
    of the lock, cannot pass. The probe reads branches, so such a point is an answer."""
    if res.code is not NewtonCode.MAX_ITERS:
        return res
    G, _, S = evaluate(res.u)
    if not residual_ok(G, S, options.rtol, options.atol):
        return res
    return dataclasses.replace(res, code=NewtonCode.SUCCESS, residual=G)


_PROBE_OPTIONS: dict = {}


def _probe_options(options: NewtonOptions | None) -> NewtonOptions:
    """The Newton options of the probe step: ``options`` tightened (made once per
    ``options``, whose checks cost more than a probe's Newton iteration)."""
    got = _PROBE_OPTIONS.get(options)
    if got is None:
        opts = options or NewtonOptions()
        got = NewtonOptions(rtol=min(opts.rtol, 1e-12), atol=min(opts.atol, 1e-14),
                            max_iters=max(opts.max_iters, 100),
                            max_backtracks=opts.max_backtracks, free_steps=opts.free_steps)
        if len(_PROBE_OPTIONS) < 64:
            _PROBE_OPTIONS[options] = got
    return got


def hold_rate_locks(scene: Scene, branches: Sequence, modes: Sequence[int],
                    v: list[float]) -> list[int]:
    """Set exactly the rate fixed by every dashpot on a rate-locking branch (``q = L``).

    Only a dashpot between a mass and ground is set here (``v = +-L``, exactly); one
    between two nodes is left as the probe step found it. Returns the elements set.
    """
    done = []
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot":
            continue
        info = branches[e].info[modes[e]]
        if not info.locks or info.lock_value is None:
            continue
        a, b = scene.elem_a[e], scene.elem_b[e]
        L = float(info.lock_value)
        if a < 0 and b >= 0 and isinstance(scene.nodes[b], Mass):
            v[b] = L
        elif b < 0 and a >= 0 and isinstance(scene.nodes[a], Mass):
            v[a] = -L if L != 0.0 else 0.0
        else:
            continue
        done.append(e)
    return done


def snap_to_locks(scene: Scene, branches: Sequence, x: list[float], v: list[float],
                  F: list[float], tol: float, tol_x: float = 0.0) -> list[int]:
    r"""Put every element that sits on a lock, up to the step's tolerance, exactly on it.

    An element is *on a lock* at an event when one of its law's locking branches with a
    known value ``L`` (:attr:`BranchInfo.locks`, ``lock_value``; a stuck dashpot,
    ``q' = 0``, or a taut string, ``q = L``) admits its force (every guard of that branch
    at ``(L, F_e)`` above ``-sqrt(eps) (1 + |F_e|)``) and its rate is within ``tol`` of the
    lock's rate (``|q - L| <= tol`` for a dashpot, ``|q'| <= tol`` for a spring, whose
    elongation must also be within ``max(sqrt(eps) (1 + |L|), tol_x)`` of ``L``: a slow
    mass whose string's length was located ``1.2e-7`` late, within the step's position
    tolerance ``tol_x``, kept its rate of ``6e-5`` against the taut string, and every
    step from there failed down to the step floor).

    The velocities ``v`` are moved, in place, to the nearest ones in the kinetic-energy norm
    that hold all those rates exactly (:func:`lumped.solvers.nonsmooth.impacts` with targets:
    momentum conserved, a change of at most ``tol``). Why: where a slip branch ends flat
    (``dq/dF = 0`` at the yield force, Herschel-Bulkley ``n > 1``) a force located on its
    guard to round-off still leaves a rate of the order of the Newton tolerance, and the
    vanishing probe step of :func:`select_modes` reads ``m q' / h_p`` as a force far
    beyond the yield force: the element would be sent to the opposite slip branch.

    Returns
    -------
    list of int
        The elements held (empty: ``v`` is unchanged).
    """
    from ..nonsmooth.impacts import impact_solve

    slack = math.sqrt(_EPS)
    held, target = [], []
    q_x = scene.elongations(x, [0.0] * len(x))
    for e, el in enumerate(scene.elements):
        lb = branches[e]
        a, b = scene.elem_a[e], scene.elem_b[e]
        rate = (v[b] if b >= 0 else 0.0) - (v[a] if a >= 0 else 0.0)
        for info in lb.info:
            L = info.lock_value
            if not info.locks or L is None:
                continue
            dashpot = el.kind == "dashpot"
            off = rate - L if dashpot else rate
            if abs(off) > tol or (not dashpot and abs(q_x[e] - L) > max(
                    slack * (1.0 + abs(L)), tol_x)):
                continue
            gs = lb.guards_for(info.index)(L if dashpot else q_x[e], F[e])
            if all(g >= -slack * (1.0 + abs(F[e])) for g in gs):
                held.append(e)
                target.append(float(L) if dashpot else 0.0)
                break
    if held and not _ground_locks(scene, held, target, v):
        v_new, _, _ = impact_solve(scene, v, held, 0.0, target=target)
        v[:] = v_new
    return held


def _ground_locks(scene: Scene, held: Sequence[int], target: Sequence[float],
                  v: list[float]) -> bool:
    """The rates ``target`` of ``held`` set in place when each held element joins its own
    mass to ground: then the nearest velocities in the kinetic-energy norm move only
    those masses, each onto its lock (``v_b = L`` or ``v_a = -L``); ``False`` (nothing
    changed) otherwise."""
    nodes, vals = [], []
    for e, L in zip(held, target, strict=True):
        a, b = scene.elem_a[e], scene.elem_b[e]
        node, val = (b, L) if a < 0 <= b else ((a, -L if L != 0.0 else 0.0) if b < 0 <= a
                                              else (-1, 0.0))
        if node < 0 or node in nodes or not isinstance(scene.nodes[node], Mass):
            return False
        nodes.append(node)
        vals.append(val)
    for node, val in zip(nodes, vals, strict=True):
        v[node] = float(val)
    return True


def lock_cones(branches: Sequence, modes: Sequence[int], F: Sequence[float],
               elements: Sequence[int]) -> dict[int, tuple[float, float, float, float]]:
    r"""The force interval each locked element of ``elements`` admits, as ``e -> (centre,
    half-width, lo, hi)``: where every guard of its locking branch (at ``q`` = the lock's
    value) is non-negative, read off the guards' slopes in ``F`` at ``F_e`` (exact for the
    affine guards of the built-in laws: Bingham, Coulomb, Herschel-Bulkley stuck,
    ``|F| <= tau``). ``lo, hi`` are the interval's ends; the centre and half-width weigh
    the split (:func:`lumped.solvers.radau.stage._cone_solver`). An interval open on a side (a
    taut string, ``F >= k L``) gets the centre ``F_e`` and a half-width ``1e3`` times the
    largest finite one or force, so that it takes the load the others do not, and keeps
    its finite end as ``lo`` or ``hi``: a split below a taut string's ``k L`` (a string
    pushing) is held there. Elements not on a lock with a known value are left out."""
    out: dict[int, tuple[float, float, float, float]] = {}
    open_: list[tuple[int, float, float]] = []
    big = 1.0 + max((abs(f) for f in F), default=0.0)
    for e in elements:
        info = branches[e].info[modes[e]]
        if not info.locks or info.lock_value is None:
            continue
        L, F0 = float(info.lock_value), float(F[e])
        guards = branches[e].guards_for(modes[e])
        d = 1.0 + abs(F0)
        g0, g1 = guards(L, F0), guards(L, F0 + d)
        lo, hi = -math.inf, math.inf
        for a, b in zip(g0, g1, strict=True):
            slope = (b - a) / d
            if slope > 0.0:
                lo = max(lo, F0 - a / slope)
            elif slope < 0.0:
                hi = min(hi, F0 - a / slope)
        if math.isfinite(lo) and math.isfinite(hi) and hi > lo:
            out[e] = (0.5 * (lo + hi), 0.5 * (hi - lo), lo, hi)
            big = max(big, 0.5 * (hi - lo))
        else:
            open_.append((e, lo, hi))
    for e, lo, hi in open_:
        out[e] = (float(F[e]), 1e3 * big, lo, hi)
    return out


def apply_impacts(scene: Scene, branches: Sequence, old: Sequence[int], new: Sequence[int],
                  x: list[float], v: list[float], threshold: float,
                  restitution: float = 0.0, forces: Sequence[float] | None = None,
                  ) -> tuple[list[tuple[int, float]], float] | str:
    """Apply the impulse of every spring that enters a position lock while its ends approach.

    A spring whose new branch locks ``q`` (:attr:`BranchInfo.locks`) with ``|q'| >
    threshold`` is an impact: the velocities jump to those of
    :func:`lumped.solvers.nonsmooth.impacts.impact_velocities` over all the locked springs (``v`` is
    updated in place), and a lock with a known value between a mass and ground gets its
    position set exactly (``x`` in place). ``forces`` (the element forces before the
    event) say which way a lock at rest holds
    (:func:`~lumped.solvers.nonsmooth.impacts.impact_velocities`): a string taut at rest holds in
    tension, whatever the sign of its rate's round-off.

    Returns
    -------
    (hits, energy_lost) or str
        ``hits``: ``(element, impulse)`` of the impacting elements (empty if none), or a
        message when impacts are needed and :mod:`lumped.solvers.nonsmooth.impacts` is missing.
    """
    ea, eb = scene.elem_a, scene.elem_b
    locked = [e for e, el in enumerate(scene.elements)
              if el.kind == "spring" and branches[e].info[new[e]].locks]
    hits = []
    for e in locked:
        if new[e] == old[e]:
            continue
        a, b = ea[e], eb[e]
        rate = (v[b] if b >= 0 else 0.0) - (v[a] if a >= 0 else 0.0)
        if abs(rate) > threshold:
            hits.append(e)
    if not hits:
        return [], 0.0
    try:
        from ..nonsmooth.impacts import impact_velocities
    except ImportError:  # pragma: no cover - until the impact model is merged
        el = scene.elements[hits[0]]
        return (f"element {el.name!r} (law {el.law_name!r}) locks its elongation while its "
                "ends approach: an impact, and lumped.solvers.nonsmooth.impacts is not available")
    v_after, impulses, lost = impact_velocities(scene, x, v, locked, restitution, forces)
    v[:] = v_after
    inner, gaps = [], []
    for e in hits:
        L = branches[e].info[new[e]].lock_value
        a, b = ea[e], eb[e]
        if L is not None and a < 0 and b >= 0:  # the lock holds q = L and q' = 0 exactly
            x[b], v[b] = float(L), 0.0
        elif L is not None and b < 0 and a >= 0:
            x[a], v[a] = -float(L), 0.0
        elif L is not None and a >= 0 and b >= 0:
            inner.append(e)
            gaps.append(float(L) - (x[b] - x[a]))
    if inner:  # between two nodes: the least move (kinetic-energy norm) onto q = L
        from ..nonsmooth.impacts import impact_solve

        dx, _, _ = impact_solve(scene, [0.0] * len(x), inner, 0.0, target=gaps)
        x[:] = [xi + di for xi, di in zip(x, dx, strict=True)]
    return [(e, impulses[locked.index(e)]) for e in hits], lost


def fold_crossed(kernel: Callable, q: Sequence[float], F: Sequence[float]) -> bool:
    """Whether the law crosses a fold along a step: ``dR/dq`` or ``dR/dF`` changes sign
    strictly between consecutive nodes ``(q[k], F[k])`` of the step's polynomial (the test
    of the fixed-step methods, :mod:`lumped.solvers.implicit.branch_check`)."""
    d = [kernel(qk, Fk) for qk, Fk in zip(q, F, strict=True)]
    for k in range(len(q) - 1):
        if left_branch(kernel, q[k], F[k], d[k][1], d[k][2], q[k + 1], F[k + 1],
                        d[k + 1][1], d[k + 1][2]):
            return True
    return False


def guard_tolerance(q: float, F: float) -> float:
    """How far below zero a guard may sit from round-off alone at ``(q, F)``."""
    return 64.0 * 2.220446049250313e-16 * (1.0 + abs(q) + abs(F))


def _finite(vals: Sequence[float]) -> bool:
    return all(math.isfinite(val) for val in vals)
