r"""Semismooth Newton-Raphson for the small nonlinear systems of one time step.

The system ``G(u) = 0`` is given by one callback that returns, at ``u``, the residual
``G``, a generalised Jacobian ``J`` (an element of Clarke's Jacobian at kinks, as the
element laws supply it) and a per-row *scale* ``S`` (the sum of the magnitudes of the
terms that make up each row, used by the residual test)::

    evaluate(u) -> (G, J, S)        lists of floats; J is a list of rows

Iteration ``k`` solves ``J_k du = -G_k`` by dense LU with partial pivoting (plain Python
floats up to :data:`DENSE_PYTHON_MAX` unknowns, numpy above), then damps the step by
backtracking (after ``free_steps`` full steps, see :class:`NewtonOptions`):
``u_{k+1} = u_k + lam du`` with ``lam = 1,
1/2, 1/4, ...`` until ``phi(u_{k+1}) <= (1 - 1e-4 lam) phi(u_k)``, where the merit
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
  the piece on the other side proposes a long step.

On success the last (small) correction is applied too: it costs nothing more and makes
the result exact up to rounding on piecewise-linear pieces. When the last Newton step
changed the active pieces (a kink was crossed), the corrected point is evaluated and
kept only if it passes the residual test or stays on the same pieces: a correction
taken with one piece's Jacobian at a kink may point back across it.

On a piecewise-linear system whose active pieces are guessed right (a time step started
from the previous step's solution), the first Newton step is exact, so one iteration
suffices; a change of piece costs one more.

The result carries a :class:`NewtonCode` and the counters; a non-finite residual,
Jacobian or step is reported as ``NON_FINITE`` and never returned as a solution.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from .linalg import (
    DENSE_PYTHON_MAX,
    FactorCache,
    factor_solver,
    lu_factor,
    lu_solve,
    unrolled_lu_solve,
)

__all__ = [
    "NewtonCode",
    "NewtonOptions",
    "NewtonResult",
    "FactorCache",
    "newton_solve",
    "min_norm_solver",
    "unrolled_lu_solve",
    "lu_factor",
    "lu_solve",
    "DENSE_PYTHON_MAX",
]


Evaluate = Callable[[list[float]], tuple[list[float], list[list[float]], list[float]]]


class NewtonCode(enum.Enum):
    """How a Newton solve ended."""

    SUCCESS = "success"
    MAX_ITERS = "max_iters"  #: the iteration budget ran out
    DIVERGED = "diverged"  #: the line search found no decrease of the residual
    SINGULAR = "singular"  #: a zero pivot in the LU factorisation
    NON_FINITE = "non_finite"  #: NaN or infinity in the residual, Jacobian or step


@dataclass(frozen=True)
class NewtonOptions:
    """Tolerances and budgets of :func:`newton_solve`.

    Attributes
    ----------
    rtol, atol : float
        Relative and absolute tolerances of both convergence tests.
    max_iters : int
        Newton iterations (factorisations) allowed per solve.
    max_backtracks : int
        Halvings of the step allowed in the line search of one iteration.
    free_steps : int
        The first ``free_steps`` iterations take the full Newton step whenever it is
        finite, even if the residual grows (a watchdog: on a piecewise-linear law the
        full step from a wrong piece lands on the right one, where the next step is
        exact, while a line search would creep along the wrong piece).
    """

    rtol: float = 1e-10
    atol: float = 1e-12
    max_iters: int = 50
    max_backtracks: int = 40
    free_steps: int = 2

    def __post_init__(self) -> None:
        from ..._validate import as_int_at_least, as_positive

        as_positive("rtol", self.rtol)
        as_positive("atol", self.atol)
        as_int_at_least("max_iters", self.max_iters, 1)
        as_int_at_least("max_backtracks", self.max_backtracks, 0)
        as_int_at_least("free_steps", self.free_steps, 0)


@dataclass
class NewtonResult:
    """Outcome of :func:`newton_solve`.

    Attributes
    ----------
    u : list of float
        The last iterate (the solution when ``code`` is ``SUCCESS``).
    code : NewtonCode
    iterations, residual_evals, jacobian_evals, factorizations : int
        Cost counters of this solve.
    residual : list of float
        ``G(u)`` at the returned iterate.
    worst_row : int
        Index of the row with the largest ``|G_i| / (rtol S_i + atol)``.
    jacobian : list of list of float
        ``J(u)`` at the returned iterate (callers read element derivatives from it).
    singular : bool
        A singular Jacobian was met (and, with ``min_norm=True``, stepped over by a
        minimum-norm correction).
    """

    u: list[float]
    code: NewtonCode
    iterations: int
    residual_evals: int
    jacobian_evals: int
    factorizations: int
    residual: list[float]
    worst_row: int
    jacobian: list[list[float]]
    singular: bool = False


def newton_solve(
    evaluate: Evaluate,
    u0: Sequence[float],
    options: NewtonOptions = NewtonOptions(),
    cache: FactorCache | None = None,
    *,
    min_norm: bool = False,
    project: Callable[[list[float]], list[float]] | None = None,
    check_scaled: bool = False,
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
            solve = factor_solver(J)
            n_fact += 1
            if solve is None:
                met_singular = True
                if not min_norm:
                    return result(NewtonCode.SINGULAR)
                solve = min_norm_solver(J)
            elif cache is not None:
                cache.store(J, solve)
        du = solve(G)  # J du = G; the step is -du
        if not finite(du):
            return result(NewtonCode.NON_FINITE)
        if min_norm:
            d3 = _null_step_removed(J, G, du, u)
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
            probe = [_hair(ui, di) for ui, di in zip(u, du, strict=True)]
            _, J_dir, _ = evaluate(probe)
            n_res += 1
            if J_dir != J and all(finite(row) for row in J_dir):
                n_jac += 1
                solve_dir = factor_solver(J_dir)
                n_fact += 1
                if solve_dir is not None:
                    d2 = solve_dir(G)
                    if finite(d2) and update_ok(d2, u, rtol, atol):
                        u = [ui - di for ui, di in zip(u, d2, strict=True)]
                        return result(NewtonCode.SUCCESS)
            # An unknown near zero whose rounding is set by large terms (a velocity
            # v ~ 0 of a mass under forces ~1e5): its correction is measured against
            # the terms it enters (see _update_ok_scaled).
            if _update_ok_scaled(du, u, J, S, rtol, atol):
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
                                   or _update_ok_scaled(d3, u, J, S, rtol, atol)):
                    met_singular = True
                    u = [ui - di for ui, di in zip(u, d3, strict=True)]
                    return result(NewtonCode.SUCCESS)
        if iters >= options.max_iters:
            return result(NewtonCode.MAX_ITERS)
        lam = 1.0
        if iters >= options.free_steps and norm < 0.0:
            norm = _merit(G, S, floor)
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
                if _merit(G_new, S, floor) <= (1.0 - 1e-4 * lam) * norm:
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


def min_norm_solver(J: Sequence[Sequence[float]]):
    """``solve(b)``: the minimum-norm least-squares solution of ``J y = b`` (numpy SVD).

    Singular values below ``n * eps`` times the largest count as zero, so an exactly
    rank-deficient step matrix (two locked elements in parallel) is solved on its range
    and leaves the null space (the free split of the forces) untouched.
    """
    import numpy as np

    A = np.array(J, dtype=float)
    pinv = np.linalg.pinv(A, rcond=len(A) * 2.220446049250313e-16)

    def solve(b: Sequence[float]) -> list[float]:
        # (a non-finite result is Newton's to report, NON_FINITE: no numpy warning)
        with np.errstate(invalid="ignore", over="ignore"):
            return (pinv @ np.asarray(b, dtype=float)).tolist()

    return solve


def equilibrated_min_norm(J: Sequence[Sequence[float]], G: Sequence[float]) -> list[float]:
    """The minimum-norm solution of ``J d = G`` with rows and columns scaled to unit
    largest entries first: a matrix singular only in its scales (``k h = 1e8`` beside
    ``m / h = 1``) keeps its full rank (the plain LU solution), one with rows that are
    proportional up to rounding (locks in parallel) loses their null space."""
    import numpy as np

    A = np.array(J, dtype=float)
    r = np.abs(A).max(axis=1)
    r[r == 0.0] = 1.0
    A /= r[:, None]
    c = np.abs(A).max(axis=0)
    c[c == 0.0] = 1.0
    A /= c[None, :]
    pinv = np.linalg.pinv(A, rcond=len(A) * 2.220446049250313e-16)
    return ((pinv @ (np.asarray(G, dtype=float) / r)) / c).tolist()


#: A Newton correction longer than this times ``1 + max |u|`` is checked for a step
#: along a null space that only rounding hides (:func:`_null_step_removed`).
_NULL_STEP_RATIO = 1e6


def _null_step_removed(J: Sequence[Sequence[float]], G: Sequence[float], du: list[float],
                       u: Sequence[float]) -> list[float] | None:
    """The minimum-norm correction in place of the LU correction ``du`` (``J du = G``)
    where ``du`` is a long step along a null space that only rounding hides; else None.

    Locked elements in a cycle (two stuck dashpots in parallel, a string taut beside a
    stuck dashpot) make the step matrix singular, their rows proportional; but LU, when
    the ratio of those rows is not a power of two, eliminates one of them to a pivot of
    an ulp instead of zero, and while the residual is not yet small (another law still
    converging) the correction moves the free split of the forces by ``residual / ulp``
    (``1e13``), from where Newton crawls back by halving and runs out of iterations.
    Checked only when ``du`` exceeds :data:`_NULL_STEP_RATIO` times ``1 + max |u|``:
    the minimum-norm solution of the equilibrated matrix
    (:func:`equilibrated_min_norm`) replaces it when it is a thousand times shorter and
    solves ``J d = G`` (residual below ``1e-8`` of the terms). On a regular matrix the two
    agree to rounding, so ``du`` stays."""
    big = max(abs(d) for d in du)
    if not big > _NULL_STEP_RATIO * (1.0 + max(abs(x) for x in u)):
        return None
    d3 = equilibrated_min_norm(J, G)
    short = max(abs(d) for d in d3)
    if not (math.isfinite(short) and 1e3 * short < big):
        return None
    terms = max(max(abs(g) for g in G), max(abs(Jij) * short for row in J for Jij in row))
    for row, g in zip(J, G, strict=True):
        r = sum(Jij * dj for Jij, dj in zip(row, d3, strict=True)) - g
        if not abs(r) <= 1e-8 * terms:
            return None
    return d3


def _hair(u: float, d: float) -> float:
    """``u - 1e-8 d``, but at least one ulp away from ``u`` (towards ``-d``) when ``d != 0``.

    The probe of the directional Jacobian must leave ``u`` for real: when the Newton
    correction is below ``1e8`` ulps of ``u`` (e.g. ``F = tau`` exactly with the true
    root ``1e-35`` beyond it), ``u - 1e-8 d`` rounds back to ``u`` and the probe would
    read the very piece it is meant to look past.
    """
    p = u - 1e-8 * d
    if p == u and d != 0.0:
        p = math.nextafter(u, -math.inf if d > 0.0 else math.inf)
    return p


def _merit(G: Sequence[float], S: Sequence[float], floor: float) -> float:
    """Largest relative residual ``|G_i| / (S_i + atol / rtol)`` (unit-free per row)."""
    m = 0.0
    for g, s in zip(G, S, strict=True):
        r = abs(g) / (s + floor)
        if r > m:
            m = r
    return m


def residual_ok(G: Sequence[float], S: Sequence[float], rtol: float, atol: float) -> bool:
    for g, s in zip(G, S, strict=True):
        if not abs(g) <= rtol * s + atol:
            return False
    return True


def update_ok(du: Sequence[float], u: Sequence[float], rtol: float, atol: float) -> bool:
    for d, x in zip(du, u, strict=True):
        if not abs(d) <= rtol * abs(x) + atol:
            return False
    return True


def _update_ok_scaled(du: Sequence[float], u: Sequence[float], J: Sequence[Sequence[float]],
                      S: Sequence[float], rtol: float, atol: float) -> bool:
    r"""The update test with the scale of the terms each unknown enters.

    ``|du_j| <= rtol * max(|u_j|, T_j) + atol`` with ``T_j = min_i S_i / |J_ij|`` over
    the rows ``i`` that contain ``u_j``: a correction that changes no equation by more
    than ``rtol`` times the size of that equation's terms is negligible, whatever the
    size of ``u_j`` itself (e.g. ``0``, where ``rtol |u_j|`` vanishes and ``atol`` in
    the unknown's units may be far below its round-off). Used after the plain test.
    """
    for j, (d, x) in enumerate(zip(du, u, strict=True)):
        a = abs(d)
        if a <= rtol * abs(x) + atol:
            continue
        T = math.inf
        for row, s in zip(J, S, strict=True):
            c = abs(row[j])
            if c > 0.0 and s / c < T:
                T = s / c
        if not a <= rtol * T + atol:  # T = inf (an empty column) fails too
            return False
    return True


def _converged(G, S, du, u, rtol, atol) -> bool:
    return residual_ok(G, S, rtol, atol) and update_ok(du, u, rtol, atol)
