r"""Consistent initial state: the velocities of all nodes and the forces of all elements at
``t = 0``.

The step system with a vanishing step ``h = eps`` and the masses' accelerations as
unknowns (``v_i = v_i(0) + eps a_i``) selects the initial forces that the limit
``dt -> 0`` of the implicit steps selects: a stuck dashpot takes the force that keeps its
mass at rest if its law admits it, else the nearest admissible one (for the paper's scene
``clip(F(0) - k x0, -tau, tau)``, as
:func:`lumped.solvers.closed.closed_form.initial_dashpot_force`), and junction velocities
follow from the laws.

This module owns :func:`consistent_initial_state` and its limit system solved by Newton
with its restarts; the shortcut without Newton when every node is a mass and the cluster
guesses of the last restarts are in :mod:`lumped.solvers.implicit.initial_rest`, the
forces of dashpots slipping from rest at ``t = 0`` (not at ``t = eps``) in
:mod:`lumped.solvers.implicit.initial_slip`, the check of the user's forces in
:mod:`lumped.solvers.implicit.initial_user_forces`.
"""

from __future__ import annotations

import itertools
import math
from functools import lru_cache

from ...scene import Mass, Scene
from ...scene.supports import support_rates
from ..newton.criteria import residual_ok
from ..newton.linalg import kept_factor_solver
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.scalar_root import scalar_root
from ..newton.semismooth import newton_solve
from ..nonsmooth.groups import dashpot_links
from ..nonsmooth.junction_balance import refuse_unbalanced_junctions
from ..nonsmooth.lock_forces import taut_on_supports
from ..status import SolverError
from .initial_kept import kept_per_scene
from .initial_rest import cluster_guesses, initial_rest_forces
from .initial_slip import rates_below_resolution, settle_on_rest_set
from .initial_user_forces import apply_user_forces
from .limit_rows import limit_rows
from .step_system import EPS, newton_failure

__all__ = ["consistent_initial_state"]

_DEFAULT_OPTIONS = NewtonOptions()


@lru_cache(maxsize=32)
def _ic_options(options: NewtonOptions) -> NewtonOptions:
    """``options`` with the budget of the one initial solve per run (degenerate yields
    converge linearly): at least 200 iterations (made once per ``options``)."""
    return NewtonOptions(rtol=options.rtol, atol=options.atol,
                         max_iters=max(options.max_iters, 200),
                         max_backtracks=options.max_backtracks, free_steps=options.free_steps)


@kept_per_scene
def consistent_initial_state(
    scene: Scene, *, time_scale: float = 1.0, options: NewtonOptions | None = None
) -> tuple[list[float], list[float], dict]:
    """Initial velocities of all nodes and forces of all elements at ``t = 0``.

    Masses keep their given ``v0`` (but see step 3). Then:

    1. every element whose ``q`` is known at ``t = 0`` (all springs; dashpots between
       masses and ground) gets its force from its own law, ``R(q0, F) = 0``, if the law
       fixes it there (``dR/dF != 0``);
    2. the rest -- forces of laws that are flat in ``F`` at ``q0`` (a stuck dashpot),
       dashpots at junctions, junction velocities -- solve the limit ``h -> 0`` of an
       implicit step: the masses' accelerations ``a`` are unknowns, a flat law is read
       at ``q0 + h (a_b - a_a)`` with ``h = 1e-20 * time_scale``, junction balances hold.
       A stuck dashpot thus takes the force that keeps its mass at rest if its law
       admits it, else the nearest admissible one (for the paper's scene
       ``clip(F(0) - k x0, -tau, tau)``, as
       :func:`lumped.solvers.closed.closed_form.initial_dashpot_force`). When every node
       is a mass and the system needs no Newton -- every such force held by the balance
       at rest, or a dashpot alone on its mass at the edge of its set at rest nearest
       that force -- it is read off directly
       (:func:`lumped.solvers.implicit.initial_rest.initial_rest_forces`; the counters
       are then zero);
    3. the force of ``t = 0``, not the step's, for a dashpot between masses (or a mass
       and ground) that slips from rest (:mod:`lumped.solvers.implicit.initial_slip`): a
       rate ``q0 != 0`` that the step reverses or stops (``v0 = 1e-113`` under a load past
       the yield force) counts as rest, so does the mass's ``v0`` (``v(0) = 0``), and step
       2 is solved again; a dashpot at rest
       whose force misses its law at rate 0 takes the nearest force its law admits
       there, its yield force ``sgn(F) tau`` with the slip's sign (the paper's (16)).

    User forces ``Element.F0`` are checked against the law at the initial state (and the
    junction balances), then replace the computed ones. The result is kept per scene
    object and arguments (:mod:`lumped.solvers.implicit.initial_kept`).

    Returns
    -------
    v, F, stats
        Node velocities, element forces and Newton counters.

    Raises
    ------
    ValueError
        If no law admits the initial state: an element's law admits no force at its
        initial elongation, or no forces within the laws' ranges balance the junctions
        (:func:`lumped.solvers.nonsmooth.junction_balance.refuse_unbalanced_junctions`).
    InconsistentInitialForce
        If a user ``F0`` breaks its element's law or a junction's force balance.
    SolverError
        If the algebraic system has no solution Newton can find.
    """
    options = options or _DEFAULT_OPTIONS
    nodes, elements = scene.nodes, scene.elements
    E = len(elements)
    eps = 1e-20 * time_scale
    is_mass = [isinstance(nd, Mass) for nd in nodes]
    v0 = [nd.v0 if isinstance(nd, Mass) else 0.0 for nd in nodes]
    x0 = [nd.x0 for nd in nodes]
    ea, eb = scene.elem_a, scene.elem_b
    f = scene.external_forces(0.0)

    def at(vals: list[float], i: int) -> float:
        return vals[i] if i >= 0 else 0.0

    # 1. forces fixed by the laws alone
    pinned: list[float | None] = [None] * E
    q0 = [0.0] * E
    for e, el in enumerate(elements):
        a, b = ea[e], eb[e]
        if el.kind == "spring":
            q0[e] = at(x0, b) - at(x0, a)
        else:
            # a dashpot: the masses' part of its rate (v0 is 0 at junctions, whose
            # velocities are unknowns of the limit system below)
            q0[e] = at(v0, b) - at(v0, a)
            if not all(i < 0 or is_mass[i] for i in (a, b)):
                continue  # a dashpot at a junction: its rate is unknown
        guess = el.F0 if el.F0 is not None else 0.0
        try:
            F_root, fixed = scalar_root(el.law.kernel, q0[e], guess)
        except ValueError as err:
            what = "elongation" if el.kind == "spring" else "elongation rate"
            raise ValueError(
                f"inconsistent initial state: element {el.name!r} starts at the {what} "
                f"q = {q0[e]!r}, which its law {el.law_name!r} admits with no force ({err}); "
                "change the initial positions or velocities"
            ) from None
        if fixed:
            pinned[e] = F_root
    # (a dashpot on a support that accelerates at t = 0 is no load held at rest)
    accelerating = getattr(scene, "support_frame", None) is not None and any(
        r != 0.0 and el.kind == "dashpot"
        for r, el in zip(support_rates(scene, 0.0), elements, strict=True))
    stopped: list[int] = []  # masses whose v0 the limit step reverses: at rest
    for _ in range(2):  # again once, with the rates the limit step reverses at rest
        F_rest = initial_rest_forces(scene, pinned, q0, f, eps) \
            if all(is_mass) and not accelerating else None
        if F_rest is not None:  # at rest, the load held by locks: no Newton
            v, F = list(v0), F_rest
            stats = {"newton_iterations": 0, "residual_evals": 0, "jacobian_evals": 0,
                     "factorizations": 0}
        else:
            v, F, stats = _limit_system(scene, pinned, q0, f, eps, options)
        reversed_, masses = rates_below_resolution(scene, q0, F, eps)  # initial_slip
        for e in reversed_:
            pinned[e], q0[e] = None, 0.0
        stopped += masses
        if not reversed_:
            break
    for i in stopped:
        v[i] = 0.0
    F = settle_on_rest_set(scene, pinned, q0, F)  # a slip from rest: its yield force at t = 0
    F = taut_on_supports(scene, 0.0, x0, v, F)  # a lock moving with a support: its force
    F = apply_user_forces(scene, x0, v, F, f)  # (checked against the laws, balances)
    return v, F, stats


def _limit_system(scene: Scene, pinned: list[float | None], q0: list[float], f: list[float],
                  eps: float, options: NewtonOptions
                  ) -> tuple[list[float], list[float], dict]:
    """Step 2 of :func:`consistent_initial_state`: the limit ``h -> 0`` of an implicit
    step, by Newton's method; ``(v, F, stats)``."""
    nodes, elements = scene.nodes, scene.elements
    N, E = len(nodes), len(elements)
    is_mass = [isinstance(nd, Mass) for nd in nodes]
    mass = [nd.m if isinstance(nd, Mass) else 0.0 for nd in nodes]
    v0 = [nd.v0 if isinstance(nd, Mass) else 0.0 for nd in nodes]
    ea, eb = scene.elem_a, scene.elem_b

    # 2. the limit system (its rows: lumped.solvers.implicit.limit_rows)
    kernels = [el.law.kernel for el in elements]
    spring = [el.kind == "spring" for el in elements]
    q_rate = [0.0] * E
    frame = getattr(scene, "support_frame", None)
    if frame is not None:
        # a dashpot on a moving support (lumped.scene.supports) reads its rate at eps as
        # (q0 + o_e(0)) + eps (a_b - a_a + o_e'(0)), o_e' = +-a_s, in its law's own
        # kernel (the offset added first: added after the eps terms, as the shifted
        # kernel would, it rounds them away): one stuck to the support takes the force
        # that gives its mass the support's acceleration
        q0 = [q + o for q, o in zip(q0, frame.offsets_at(0.0), strict=True)]
        kernels = [getattr(el.law, "bound", el.law).kernel for el in elements]
        q_rate = [0.0 if spring[e] else eps * r
                  for e, r in enumerate(support_rates(scene, 0.0))]

    evaluate = limit_rows(is_mass, mass, f, ea, eb, pinned, q0, q_rate, kernels, spring, eps)

    # a mass starts at the acceleration of a support it has a dashpot to (stuck there,
    # its rate stays 0): the law row's residual is O(eps) and would pass at a = 0
    a_guess = [0.0] * N
    for e, r in enumerate(q_rate):
        i = ea[e] if eb[e] < 0 else eb[e]
        if r != 0.0 and i >= 0 and is_mass[i] and (ea[e] < 0 or eb[e] < 0):
            a_guess[i] = (r if eb[e] < 0 else -r) / eps  # o_e' = -a_s at a, +a_s at b
    u0 = a_guess + [
        Fp if Fp is not None else (el.F0 if el.F0 is not None else 0.0)
        for Fp, el in zip(pinned, elements, strict=True)
    ]
    # one solve per run: allow a generous budget (degenerate yields converge linearly)
    ic_options = _ic_options(options)
    res = newton_solve(evaluate, u0, ic_options, min_norm=True, check_scaled=True,
                       equilibrate=True, factor=kept_factor_solver)
    if res.code is not NewtonCode.SUCCESS:
        # restarts: the junctions' velocities from their balances solved one by one and
        # by clusters joined by dashpots
        # (lumped.solvers.implicit.balance_sweeps.balance_sweeps), then every junction
        # moving with each dashpot neighbour in turn (see
        # lumped.solvers.implicit.globalize.stuck_guesses), the masses' accelerations
        # zero; each by plain Newton, then with every free force on its own law
        # (nonlinear elimination, see
        # lumped.solvers.implicit.force_projection.force_projector: a law steep in F,
        # Herschel-Bulkley n < 1 near its yield force, is solved in its inverse form)
        from ..nonsmooth.locks import split_free_forces
        from .balance_sweeps import balance_sweeps
        from .globalize import stuck_guesses

        def elongation(u: list[float], e: int) -> float:
            a, b = ea[e], eb[e]
            scale = eps if spring[e] else 1.0
            du_b = (eps * u[b] if is_mass[b] else u[b]) if b >= 0 else 0.0
            du_a = (eps * u[a] if is_mass[a] else u[a]) if a >= 0 else 0.0
            return q0[e] + q_rate[e] + scale * (du_b - du_a)

        def project(u: list[float], free_out: list | None = None) -> list[float]:
            """Every free force on its own law where the law fixes it; with ``free_out``
            (see :func:`lumped.solvers.nonsmooth.locks.split_free_forces`) the forces it leaves
            free are moved to one it admits if needed and listed with their ``q``."""
            out = list(u)
            for e in free:
                q = elongation(u, e)
                try:
                    F, fixed = scalar_root(kernels[e], q, u[N + e])
                except ValueError:
                    continue
                if not math.isfinite(F):
                    continue
                if fixed:
                    out[N + e] = F
                elif free_out is not None:
                    if kernels[e](q, u[N + e])[0] != 0.0:
                        out[N + e] = F
                    free_out.append((N + e, q))
            return out

        def settle(u: list[float]) -> list[float]:
            """From the swept junction velocities: the forces the laws leave free (stuck
            dashpots) split to balance the junctions, then every mass's acceleration from
            its own row (linear in it)."""
            u = split_free_forces(scene, evaluate, project, u, rows=junctions)
            G = evaluate(u)[0]
            for i in range(N):
                if is_mass[i]:
                    u[i] -= G[i] / mass[i]
            return u

        def ulp_floor_ok(u: list[float]) -> bool:
            """The residual test at ``u``, each law row measured against at least its
            round-off floor (the change of ``R`` when ``F`` moves one ulp): a law steep
            in ``F`` whose root lies between two floats (Herschel-Bulkley ``n < 1`` a hair
            beyond its yield force) has no float with a smaller residual, and no Newton
            step can polish it (as for the steps, see
            :func:`lumped.solvers.implicit.globalize.solve_globalized`)."""
            G, _, S = evaluate(u)
            S = list(S)
            for e in range(E):
                k, q, F = N + e, elongation(u, e), u[N + e]
                R = kernels[e](q, F)[0]
                rho = max(abs(kernels[e](q, math.nextafter(F, d))[0] - R)
                          for d in (-math.inf, math.inf))
                if math.isfinite(rho) and rho / EPS > S[k]:
                    S[k] = rho / EPS
            return residual_ok(G, S, ic_options.rtol, ic_options.atol)

        free = [e for e in range(E) if pinned[e] is None]
        starts = [u0] + [[0.0 if is_mass[i] else g[i] for i in range(N)] + g[N:]
                         for g in stuck_guesses(scene, v0, u0[N:])]
        junctions = [i for i in range(N) if not is_mass[i]]
        # a junction may snap onto rest or onto a neighbour's velocity (a junction's
        # u, a mass's v0; the mass's rate eps a is then left to Newton): two junctions
        # joined by a stuck friction element and left a few ulps apart would make it
        # slip with its full yield force, which no start a hair off the kink settles
        def anchors(u: list[float]) -> list[float]:
            return [v0[i] if is_mass[i] else u[i] for i in range(N)]

        # junctions joined by dashpots also move as one (a cluster stuck together, the
        # two ends of a dashpot): one junction at a time, a junction held by a stuck
        # dashpot to a neighbour that is itself held (a dangling junction, F = 0) never
        # breaks free, though the pair must slip as a whole
        balanced = balance_sweeps(evaluate, project, list(u0), junctions, anchors,
                                  dashpot_links(scene))
        settled_points = []
        if balanced is not None:  # the junctions' monotone balances solved one by one
            starts.insert(1, balanced)
            settled_points.append(settle(balanced))
            starts.insert(2, settled_points[-1])
        def cluster_starts():
            # last: every cluster of junctions moving as one with a neighbour outside it
            # (a chain of stuck elements from a moving mass), each also settled as
            # above (also when the guess itself was among the stuck guesses); made only
            # once every start before has failed
            for g in cluster_guesses(scene, v0):
                start = [0.0 if is_mass[i] else g[i] for i in range(N)] + u0[N:]
                if start not in starts:  # (starts, as before: the ones tried so far)
                    starts.append(start)
                    yield start
                settled_start = settle(project(list(start)))
                if settled_start not in starts:
                    settled_points.append(settled_start)
                    starts.append(settled_start)
                    yield settled_start

        for start in itertools.chain(starts, cluster_starts()):
            for proj in (None, project):
                if start is u0 and proj is None:
                    continue  # done above
                retry = newton_solve(evaluate, start, ic_options, min_norm=True, project=proj,
                                     check_scaled=True, equilibrate=True,
                                     factor=kept_factor_solver)
                if retry.code is NewtonCode.SUCCESS:
                    res = retry
                    break
            if res.code is NewtonCode.SUCCESS:
                break
        settled = None
        if res.code is not NewtonCode.SUCCESS:
            settled = next((p for p in settled_points if ulp_floor_ok(p)), None)
        if settled is not None:
            # no Newton polishes a settled point (a root between two floats: Newton
            # reads the law there as flat, stuck, and moves the velocities off), but
            # every law holds there to its round-off and every node balances: keep the
            # first such point
            res = NewtonResult(settled, NewtonCode.SUCCESS, res.iterations, res.residual_evals,
                               res.jacobian_evals, res.factorizations, [], 0, [])
    if res.code is not NewtonCode.SUCCESS:
        refuse_unbalanced_junctions(scene, pinned, q0, f)
        err = newton_failure(scene, res, 0.0, 0)
        raise SolverError(
            f"no consistent initial state: {err}", status=err.status, t=0.0,
            where=err.where, residual=err.residual,
        )
    u = res.u
    v = [v0[i] if is_mass[i] else u[i] for i in range(N)]
    F = list(u[N:])
    stats = {
        "newton_iterations": res.iterations, "residual_evals": res.residual_evals,
        "jacobian_evals": res.jacobian_evals, "factorizations": res.factorizations,
    }
    return v, F, stats
