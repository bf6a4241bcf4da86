r"""The choice of the next mode at an event of the adaptive method.

A *mode* holds every element's law on one smooth branch (:func:`lumped.codegen.branches.
law_branches`). At an event the next mode is what the full, nonsmooth laws choose in the
limit of a vanishing implicit step (:func:`select_modes`): one backward-Euler step of the
full laws (the semismooth Newton of the fixed-step methods) of a size ``h_p`` far below the
method's step, read through ``law_branches(...).branch(q, F)``. As ``h_p -> 0`` this is the
rule of :func:`lumped.solvers.implicit.initial_state.consistent_initial_state`: a dashpot
that reaches ``|F| = tau`` sticks if the rest of the system can be balanced by a force
inside the cone, else it reverses. What the new mode then does to the state (rates set on
their locks, impacts) is in :mod:`lumped.solvers.modes.lock_events`; a guessed mode checked
against the full laws in :mod:`lumped.solvers.modes.mode_guess`.
"""

from __future__ import annotations

import dataclasses
import sys
from collections.abc import Sequence

from ...scene import Mass, Scene
from ...scene.shifted_laws import shifted_by
from ...scene.supports import support_time, support_time_restored
from ..implicit.conditioned import conditioned_law
from ..implicit.globalize import solve_globalized
from ..implicit.step_system import make_evaluate
from ..newton.criteria import residual_ok
from ..newton.options import NewtonCode, NewtonOptions, NewtonResult
from ..newton.semismooth import newton_solve
from .mode_guess import lock_drifts

__all__ = ["select_modes"]

_EPS = sys.float_info.epsilon


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

    On a scene with moving supports (a :class:`~lumped.scene.supports.SupportFrame`'s
    view) the laws are read at ``t + h_probe`` (the probe's state) and the clock is set
    back to ``t`` on return.
    """
    with support_time_restored(scene, t):
        support_time(scene, t + h_probe)
        return _select_modes(scene, branches, t, x, v, F, h_probe, options)


def _select_modes(scene: Scene, branches: Sequence, t: float, x: list[float],
                  v: list[float], F: list[float], h_probe: float,
                  options: NewtonOptions | None
                  ) -> tuple[list[int], list[float], list[float]] | str:
    """:func:`select_modes` with the support clock at ``t + h_probe``."""
    N = len(scene.nodes)
    cm = [n.m / h_probe if isinstance(n, Mass) else 0.0 for n in scene.nodes]
    f = scene.external_forces(t + h_probe)
    uref = list(v)
    x_hat = list(x)
    E = len(scene.elements)
    qs, rq, rf = [0.0] * E, [0.0] * E, [0.0] * E
    # steep branches in their inverse form: the same zeros, a root Newton can reach; at
    # the yield force, where the force of a small rate rounds to tau and the law reads its
    # stuck branch, the steep branch whose inverse form holds there and whose stage
    # guards admit the rate (the conditioned law of the fixed-step methods). With the
    # inverse forms alone, a junction's Herschel-Bulkley n = 0.3 dashpot starting to slip
    # forward at 1e-9 had no root at tau (the stuck branch's residual is the rate) and
    # Newton settled on the other slip branch's odd continuation, F = -tau at a positive
    # rate, at every probe up to 2e-7 s (issue 29, seed 22228's start)
    kernels = [conditioned_law(branches[e], el.law.kernel) or el.law.kernel
               for e, el in enumerate(scene.elements)]
    steep = [kernels[e] is not el.law.kernel for e, el in enumerate(scene.elements)]
    # a string at its length held on the velocity level, L + h_p (v_b - v_a), whatever
    # the drift of the positions (mode_guess.lock_drifts)
    drift = lock_drifts(scene, branches, x)
    kernels = [shifted_by(k, d) if d else k for k, d in zip(kernels, drift, strict=True)]
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
    modes = [_branch_read(branches[e], q[e] + drift[e], F_p[e], steep[e]) for e in range(E)]
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
