r"""Semismooth Newton-Raphson for the small nonlinear systems of one time step.

The system ``G(u) = 0`` is given by one callback that returns, at ``u``, the residual
``G``, a generalised Jacobian ``J`` (an element of Clarke's Jacobian at kinks, as the
element laws supply it) and a per-row *scale* ``S`` (the sum of the magnitudes of the
terms that make up each row, used by the residual test)::

    evaluate(u) -> (G, J, S)        lists of floats; J is a list of rows

Iteration ``k`` solves ``J_k du = -G_k`` by dense LU with partial pivoting (plain Python
floats up to :data:`~lumped.solvers.newton.linalg.DENSE_PYTHON_MAX` unknowns, numpy
above), then damps the step by backtracking (after ``free_steps`` full steps, see
:class:`~lumped.solvers.newton.options.NewtonOptions`): ``u_{k+1} = u_k + lam du`` with
``lam = 1, 1/2, 1/4, ...`` until ``phi(u_{k+1}) <= (1 - 1e-4 lam) phi(u_k)``, where the merit
``phi(u) = max_i |G_i(u)| / (S_i(u_k) + atol / rtol)`` is the largest residual relative
to the row scales at the current iterate: rows in different units (forces, velocities)
weigh alike, and the weights stay fixed within one line search.

Convergence needs **both** tests:

* residual: ``|G_i(u_{k+1})| <= rtol * S_i + atol`` for every row ``i``;
* update: the next Newton correction ``delta = -J(u_{k+1})^{-1} G(u_{k+1})`` obeys
  ``|delta_j| <= rtol * |u_j| + atol`` for every unknown ``j`` -- or, failing that (and
  the directional retry below), ``|delta_j| <= rtol * max(|u_j|, T_j) + atol`` with
  ``T_j = min_i S_i / |J_ij|`` the scale of the terms ``u_j`` enters (no equation
  changes by more than ``rtol`` of its terms). When ``J(u_{k+1})`` equals
  ``J_k`` (the same pieces of piecewise laws), the LU factors of ``J_k`` are reused: a
  back-substitution, no new factorisation. A stale Jacobian from another piece is never
  used for this test (it could call a wrong piece's residual small). When the residual
  passes but the update does not, the test is retried once with the Jacobian of the
  piece the Newton step points into (evaluated a hair along the step, at least one ulp
  in every moving unknown): at a kink the solution may be exact up to rounding while
  the piece on the other side proposes a long step. When no update test passes but
  every row is at the rounding of its terms, ``|G_i| <= 4 eps S_i``
  (:func:`~lumped.solvers.newton.criteria.at_roundoff`), the rows that the full
  correction does not reduce (nonzero; left bit for bit as they are, or sent across
  zero to the other side of the lattice) are taken as solved: the correction computed
  without them is tested (plain, then scaled). A lock row a
  fraction of an ulp of the positions off asks the velocity for less than an ulp of
  ``x = x_hat + h v`` and the forces for ``m ulp(x) / h^2``: noise that no iteration
  removes.

On success the last (small) correction is applied too: it costs nothing more and makes
the result exact up to rounding on piecewise-linear pieces. When the last Newton step
changed the active pieces (a kink was crossed), the corrected point is evaluated and
kept only if it passes the residual test or stays on the same pieces: a correction
taken with one piece's Jacobian at a kink may point back across it.

On a piecewise-linear system whose active pieces are guessed right (a time step started
from the previous step's solution), the first Newton step is exact, so one iteration
suffices; a change of piece costs one more.

The result carries a :class:`~lumped.solvers.newton.options.NewtonCode` and the
counters; a non-finite residual, Jacobian or step is reported as ``NON_FINITE`` and never
returned as a solution.

This module owns the iteration, :func:`newton_solve`. Its options, result and codes are in
:mod:`lumped.solvers.newton.options`, the convergence tests and the merit in
:mod:`lumped.solvers.newton.criteria`, the minimum-norm steps in
:mod:`lumped.solvers.newton.min_norm`, the LU and the factor cache in
:mod:`lumped.solvers.newton.linalg`; the compiled twin is
:mod:`lumped.solvers.newton.semismooth_jit`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from .criteria import at_roundoff, hair, merit, residual_ok, update_ok, update_ok_scaled
from .linalg import FactorCache, factor_solver
from .min_norm import equilibrated_min_norm, min_norm_solver, null_step_removed
from .options import Evaluate, NewtonCode, NewtonOptions, NewtonResult

__all__ = ["newton_solve"]

#: The default options of :func:`newton_solve` (frozen: one instance serves all calls).
_DEFAULT_OPTIONS = NewtonOptions()


def newton_solve(
    evaluate: Evaluate,
    u0: Sequence[float],
    options: NewtonOptions = _DEFAULT_OPTIONS,
    cache: FactorCache | None = None,
    *,
    min_norm: bool = False,
    project: Callable[[list[float]], list[float]] | None = None,
    check_scaled: bool = False,
    equilibrate: bool = False,
    factor: Callable = factor_solver,
) -> NewtonResult:
    """Solve ``G(u) = 0`` from ``u0`` by damped semismooth Newton (see the module notes).

    Parameters
    ----------
    evaluate : callable
        ``u -> (G, J, S)``: residual, generalised Jacobian (list of rows) and row scales.
    u0 : sequence of float
        Initial guess (for a time step: the previous step's solution).
    options : NewtonOptions
        Tolerances and budgets.
    cache : FactorCache, optional
        Reuse LU factors of an identical Jacobian across solves (e.g. time steps).
    min_norm : bool
        On a singular Jacobian take the minimum-norm least-squares correction
        (:func:`min_norm_solver`) instead of stopping with ``SINGULAR``: where the laws
        leave some unknowns free (locked elements in parallel: the motion is fixed, the
        split of the forces is not), the iterate moves as little as possible, so those
        unknowns keep their start values (the previous step's forces) as far as the
        equations allow. A consistent system still converges (the residual test decides);
        an inconsistent one ends ``DIVERGED`` or ``MAX_ITERS`` with ``singular`` set.
    project : callable, optional
        ``u -> u'`` applied to the start and to every trial iterate (nonlinear
        elimination): e.g. solve each element's own law for its force at the iterate's
        elongation, so that Newton acts on the reduced system where a law's graph is
        steep in ``F`` (Herschel-Bulkley with ``n < 1`` at its yield force).

    check_scaled : bool
        Check the last correction after a kink also when the update passed only the
        scaled test (as after the plain one): keep it only if its residual test passes
        or it stays on the same pieces. The consistent initial state needs it (its
        vanishing-step rows ``eps a = 0`` make a stuck piece's correction of ``F`` as
        large as the tolerance); the time steps keep the unchecked correction, which the
        compiled twin (:mod:`lumped.solvers.newton.semismooth_jit`) mirrors operation for operation.
    equilibrate : bool
        With ``min_norm``, scale the rows of a singular Jacobian to unit largest entries
        before its minimum-norm solve (``min_norm_solver(J, rows=True)``): the consistent
        initial state's vanishing-step rows (entries ``1e-20``) stay in its range.
    factor : callable
        ``J -> solve`` or ``None`` when ``J`` is singular: :func:`~lumped.solvers.newton.
        linalg.factor_solver` (default), or :func:`~lumped.solvers.newton.linalg.
        kept_factor_solver` for solves whose Jacobians recur (its hits count as
        factorisations: the counters do not depend on what was kept).

    Returns
    -------
    NewtonResult
        Never holds a non-finite ``u`` with code ``SUCCESS``.
    """
    rtol, atol = options.rtol, options.atol
    isfinite = math.isfinite
    u = list(u0) if project is None else project(list(u0))
    n = len(u)
    G, J, S = evaluate(u)
    n_res, n_jac, n_fact, iters = 1, 0, 0, 0
    met_singular = False

    def result(code: NewtonCode) -> NewtonResult:
        worst, worst_ratio = 0, -1.0
        if code is NewtonCode.SUCCESS:
            return NewtonResult(u, code, iters, n_res, n_jac, n_fact, G, worst, J,
                                met_singular)
        for i in range(n):
            r = abs(G[i]) / (rtol * S[i] + atol)
            if not r <= worst_ratio:  # NaN counts as worst
                worst, worst_ratio = i, r
                if not isfinite(r):
                    break
        return NewtonResult(u, code, iters, n_res, n_jac, n_fact, G, worst, J, met_singular)

    def final_correction(du: list[float]) -> NewtonResult:
        # The iterate passed both tests: apply the last (small) correction too. When the
        # last step arrived on another piece (a kink was crossed), the correction, taken
        # with this piece's Jacobian, may cross back and leave the solution (e.g. the
        # stuck piece of a Bingham law at F = tau pointing into the slipping one; in the
        # vanishing-step system of the initial state a stuck row ``eps a = 0`` asks for a
        # correction of F as large as the tolerance). Keep it only if the residual test
        # still passes where it lands, or on the same piece.
        nonlocal u, G, J, S, n_res
        u_c = [ui - di for ui, di in zip(u, du, strict=True)]
        if solve_prev is not None and J != J_prev:
            G_c, J_c, S_c = evaluate(u_c)
            n_res += 1
            if J_c != J and not (finite(G_c) and residual_ok(G_c, S_c, rtol, atol)):
                return result(NewtonCode.SUCCESS)
            G, J, S = G_c, J_c, S_c
        u = u_c
        return result(NewtonCode.SUCCESS)

    def finite(vals: Sequence[float]) -> bool:
        # a NaN or an infinity anywhere makes the sum NaN or infinite
        return isfinite(sum(vals))

    if not (finite(G) and finite(u)):
        return result(NewtonCode.NON_FINITE)
    floor = atol / rtol
    norm = -1.0  # the merit of the current iterate, computed when a line search needs it
    solve_prev = None
    J_prev: list[list[float]] | None = None
    while True:
        if not isfinite(sum(map(sum, J))):
            return result(NewtonCode.NON_FINITE)
        res_ok = residual_ok(G, S, rtol, atol)
        if res_ok and solve_prev is not None and J == J_prev:
            # same Jacobian as the last factorisation (same pieces of piecewise laws): the
            # next correction costs a back-substitution only
            delta = solve_prev(G)
            if finite(delta) and update_ok(delta, u, rtol, atol):
                u = [ui - di for ui, di in zip(u, delta, strict=True)]
                return result(NewtonCode.SUCCESS)
        n_jac += 1
        if cache is not None and cache.J == J:
            solve = cache.hit()
        else:
            solve = factor(J)
            n_fact += 1
            if solve is None:
                met_singular = True
                if not min_norm:
                    return result(NewtonCode.SINGULAR)
                solve = min_norm_solver(J, rows=equilibrate)
            elif cache is not None:
                cache.store(J, solve)
        du = solve(G)  # J du = G; the step is -du
        if not finite(du):
            return result(NewtonCode.NON_FINITE)
        if min_norm:
            d3 = null_step_removed(J, G, du, u)
            if d3 is not None:
                met_singular = True
                du = d3
        if res_ok:
            if update_ok(du, u, rtol, atol):
                return final_correction(du)
            # At a kink the residual can be zero up to rounding while the Jacobian of the
            # piece on one side proposes a long step (no floating-point root exists on
            # either piece). Retry the update test with the Jacobian of the piece the
            # step points into: a directional (B-)derivative, evaluated a hair (at least
            # one ulp) along -du.
            probe = [hair(ui, di) for ui, di in zip(u, du, strict=True)]
            _, J_dir, _ = evaluate(probe)
            n_res += 1
            if J_dir != J and all(finite(row) for row in J_dir):
                n_jac += 1
                solve_dir = factor(J_dir)
                n_fact += 1
                if solve_dir is not None:
                    d2 = solve_dir(G)
                    if finite(d2) and update_ok(d2, u, rtol, atol):
                        u = [ui - di for ui, di in zip(u, d2, strict=True)]
                        return result(NewtonCode.SUCCESS)
            # An unknown near zero whose rounding is set by large terms (a velocity
            # v ~ 0 of a mass under forces ~1e5): its correction is measured against
            # the terms it enters (see update_ok_scaled).
            if update_ok_scaled(du, u, J, S, rtol, atol):
                if check_scaled:
                    return final_correction(du)
                u = [ui - di for ui, di in zip(u, du, strict=True)]
                return result(NewtonCode.SUCCESS)
            # A Jacobian singular up to rounding (locked elements in parallel whose rows
            # cancel only to an ulp: LU finds a pivot of 1e-14 instead of 0) turns the
            # round-off of the residual into a long step along its null space -- the
            # free split of the forces -- and Newton wanders there until its budget
            # runs out. The minimum-norm correction leaves that split alone.
            if min_norm:
                d3 = equilibrated_min_norm(J, G)
                if finite(d3) and (update_ok(d3, u, rtol, atol)
                                   or update_ok_scaled(d3, u, J, S, rtol, atol)):
                    met_singular = True
                    u = [ui - di for ui, di in zip(u, d3, strict=True)]
                    return result(NewtonCode.SUCCESS)
            # Every row at the rounding of its terms, and some rows that the full
            # correction does not reduce (bit for bit as they are, or across zero to the
            # other side of the lattice): their demand is noise (a lock row a fraction of
            # an ulp of the positions off asks the velocity for less than an ulp of x =
            # x_hat + h v, and through the momentum balance the forces for m ulp(x) / h^2,
            # again and again). The correction without them decides, with the null step of
            # locks in parallel removed as above. (A row scale above the row's true
            # rounding, a law whose terms cancel exactly, e.g. gamma (F - tau) with gamma =
            # 1e12, passes the first test; the correction reduces its row.) A taut string
            # one ulp short of L after an impact, beside a stuck Coulomb element and
            # another taut string on the same mass: its row flipped between +-1.1e-16 and
            # Newton ran out of iterations (issue 29, seed 22320 of jit-bdf1's property).
            if at_roundoff(G, S):
                G_try = evaluate([ui - di for ui, di in zip(u, du, strict=True)])[0]
                n_res += 1
                if finite(G_try):
                    G_kept = [0.0 if abs(gt) >= abs(g) else g
                              for g, gt in zip(G, G_try, strict=True)]
                    if G_kept != G:
                        d4 = solve(G_kept)
                        if min_norm and finite(d4):
                            d5 = null_step_removed(J, G_kept, d4, u)
                            if d5 is not None:
                                d4 = d5
                        if finite(d4) and (update_ok(d4, u, rtol, atol) or update_ok_scaled(
                                d4, u, J, S, rtol, atol)):
                            u = [ui - di for ui, di in zip(u, d4, strict=True)]
                            return result(NewtonCode.SUCCESS)
        if iters >= options.max_iters:
            return result(NewtonCode.MAX_ITERS)
        lam = 1.0
        if iters >= options.free_steps and norm < 0.0:
            norm = merit(G, S, floor)
        for _ in range(options.max_backtracks + 1):
            if lam == 1.0:
                u_new = [ui - di for ui, di in zip(u, du, strict=True)]
            else:
                u_new = [ui - lam * di for ui, di in zip(u, du, strict=True)]
            if project is not None:
                u_new = project(u_new)
            G_new, J_new, S_new = evaluate(u_new)
            n_res += 1
            if (lam == 1.0 and J_new != J and finite(G_new)
                    and not residual_ok(G_new, S_new, rtol, atol)):
                # The step left the piece it was computed on and missed. If that piece's
                # root lies on its own boundary (a kink; in floating point the root can
                # sit within rounding of it), a hair short of the full step stays on the
                # piece and solves the system: try it.
                u_alt = [ui - (1.0 - 1e-12) * di for ui, di in zip(u, du, strict=True)]
                G_alt, J_alt, S_alt = evaluate(u_alt)
                n_res += 1
                if finite(G_alt) and residual_ok(G_alt, S_alt, rtol, atol):
                    u_new, G_new, J_new, S_new = u_alt, G_alt, J_alt, S_alt
            if finite(G_new):
                if iters < options.free_steps or residual_ok(G_new, S_new, rtol, atol):
                    break
                # sufficient decrease of the merit, with the weights of the current iterate
                if merit(G_new, S, floor) <= (1.0 - 1e-4 * lam) * norm:
                    break
            lam *= 0.5
        else:
            if not finite(G_new):
                return result(NewtonCode.NON_FINITE)
            u, G, J, S = u_new, G_new, J_new, S_new
            iters += 1
            return result(NewtonCode.DIVERGED)
        solve_prev, J_prev = solve, J
        u, G, J, S = u_new, G_new, J_new, S_new
        norm = -1.0
        iters += 1
