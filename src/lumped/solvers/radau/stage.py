r"""One step of the 3-stage Radau IIA method (order 5) on a scene's DAE, one mode held.

The scene's semi-explicit DAE (:mod:`lumped.scene`) in the unknowns node velocities
``v`` and element forces ``F``, with ``x' = v`` for every node::

    m_i v_i' = net_i(t, F)      (masses)        0 = net_i(t, F)     (junctions)
    0 = R_e^{(b_e)}(q_e, F_e)   (every element, on its held branch ``b_e``)

``net_i = f_i(t) + sum_{a_e = i} F_e - sum_{b_e = i} F_e``. One step of size ``h`` from
``(x_n, v_n)`` solves for the stage values ``V_k, F_k`` (``k = 1, 2, 3`` at
``t_n + c_k h``) with the stage positions ``X_k = x_n + h sum_l a_kl V_l`` and the
collocation derivative ``V_k' ~ (1/h) sum_l w_kl (V_l - v_n)``, ``W = A^{-1}``::

    m_i / h sum_l w_kl (V_l,i - v_n,i) - net_i(t_n + c_k h, F_k) = 0    (masses)
                                      - net_i(t_n + c_k h, F_k) = 0    (junctions)
    R_e^{(b_e)}(q_e(X_k, V_k), F_k,e) = 0                              (elements)

with ``q_e = X_b - X_a`` (springs) or ``V_b - V_a`` (dashpots), ground at 0. The step's
result is stage 3 (``c_3 = 1``: stiffly accurate), and the stage values with ``y_n`` are
the nodes of the collocation polynomial (the dense output, :func:`dense_weights`; the
method's coefficients are in :mod:`lumped.solvers.radau.tableau`).

Everything here runs on flat lists of Python floats with scalar loops (numba-friendly).
The unknowns are laid out stage by stage: ``U[k*n + i]`` is ``V_k,i`` for a node ``i < N``
and ``U[k*n + N + e]`` is ``F_k,e``, ``n = N + E``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from ..newton.linalg import lu_factor, lu_solve
from ..newton.min_norm import min_norm_solver
from .tableau import (
    E_ERR,
    END_SLOPES,
    MU_REAL,
    START_WEIGHTS,
    A,
    C,
    W,
    dense_slopes,
    dense_weights,
)

__all__ = ["C", "A", "W", "E_ERR", "MU_REAL", "START_WEIGHTS", "StageSystem", "dense_weights",
           "dense_slopes"]


def _solver(J: list[list[float]]) -> Callable[[list[float]], list[float]]:
    """``solve(b)`` for ``J y = b``: the LU with pivoting, or the minimum-norm least-squares
    solution when ``J`` is singular (:func:`lumped.solvers.newton.min_norm.min_norm_solver`)."""
    fac = lu_factor(J)
    if fac is not None:
        return lambda b: lu_solve(fac, b)
    if not all(math.isfinite(a) for row in J for a in row):  # a law undefined here
        return lambda b: [math.nan] * len(b)
    return min_norm_solver(J)


def _row_scale(row: list[float], scale: list[float]) -> float:
    """``sum_j |J_ij| scale_j``: how much row ``i`` of the stage system changes when every
    unknown moves by its tolerance ``scale_j``."""
    return sum(abs(a) * sc for a, sc in zip(row, scale, strict=True))


def _solves(G: list[float], J: list[list[float]], scale: list[float], tol: float) -> bool:
    """Whether the residual ``G`` is one a Newton correction within the convergence test
    removes: ``|G_i| <= 10 tol sum_j |J_ij| scale_j`` on every row (a row that no
    unknown enters must be zero to round-off)."""
    for g, row in zip(G, J, strict=True):
        if not abs(g) <= 10.0 * tol * _row_scale(row, scale) + 1e-300:
            return False
    return True


def _cone_solver(J: list[list[float]], U: list[float], cones: dict[int, tuple[float, ...]],
                 N: int, n: int, held: dict[int, float] | None = None
                 ) -> Callable[[list[float]], list[float]]:
    """``solve(b)`` for a singular ``J`` whose free directions split the force among locked
    elements in parallel: of all the solutions, the one whose new forces minimise
    ``sum (F_e - c_e)^2 / w_e`` over the elements of ``cones`` (``e -> (c_e, w_e, lo_e,
    hi_e)``, the centre and half-width of the force interval ``[lo_e, hi_e]`` the
    element's lock admits, :func:`lumped.solvers.modes.events.lock_cones`) and the
    correction's norm over the other unknowns. Two stuck dashpots in parallel share a load
    ``S`` in proportion to their capacities (each within its cone whenever ``|S|`` is within
    the sum), a rigid lock (``w_e`` huge) takes what the others do not.

    With ``du = D z + o`` (``D = sqrt(w_e)``, ``o = c_e - U_j`` on those forces; ``D = 1``,
    ``o = 0`` elsewhere; ``U`` the iterate, read at every call): ``z`` is the minimum-norm
    solution of ``J D z = b - J o``.
    ``held`` (stage column -> force): forces held at a bound of their interval (centre
    moved there, weight ``1e-12 w_e``), see :meth:`StageSystem.solve`."""
    import numpy as np

    size = len(U)
    held = held or {}
    cols = {k * n + N + e: (c, w) for k in range(3) for e, (c, w, *_) in cones.items()}
    A = np.array(J, dtype=float)
    D = np.ones(size)
    for j, (_, w) in cols.items():
        D[j] = math.sqrt(w * 1e-12 if j in held else w)
    # rows equilibrated (the same solutions; a junction's row through a flat law, dq/dF
    # ~ 1e-7, is not cut off as round-off beside the momentum rows' m / h)
    AD = A * D
    r = np.abs(AD).max(axis=1)
    r[r == 0.0] = 1.0
    pinv = np.linalg.pinv(AD / r[:, None], rcond=size * 2.220446049250313e-16) / r
    # a row with one nonzero (a stuck dashpot to ground: ``V = 0``) fixes its unknown by
    # one division, exactly, as the LU's singleton pivots do
    single = [(i, int(nz[0]), float(A[i, nz[0]])) for i in range(size)
              for nz in [np.flatnonzero(A[i])] if len(nz) == 1]

    def solve(b: list[float]) -> list[float]:
        o = np.zeros(size)
        for j, (c, _) in cols.items():  # ``U`` is the caller's iterate, updated in place
            o[j] = held.get(j, c) - U[j]
        z = pinv @ (np.asarray(b, dtype=float) - A @ o)
        du = (D * z + o).tolist()
        for i, j, a in single:
            du[j] = b[i] / a
        return du

    return solve


#: Passes of the ``radau5`` loop without an accepted step after which it stops (a guard
#: against any cycle; backward Euler then bridges the point,
#: :mod:`lumped.solvers.eventdriven.bridge`).
STALL_PASSES = 1_000

#: Newton iterations of a ``radau5`` stage solve, in both loops (a landing step retried
#: with six times as many in the Python loop); also the controller's Newton factor.
MAX_NEWTON = 10

#: Newton failures in a row after which a ``radau5`` step tries the line-search fallback
#: (:meth:`StageSystem.solve_damped`); the compiled loop hands that pass to Python.
DAMPED_AFTER = 8

#: How much looser the forces of guarded elements are held than ``x`` and ``v``.
FORCE_TOL_FACTOR = 100.0

class StageSystem:
    """The Radau IIA stage equations of one scene, for the branch kernels of one mode.

    Parameters
    ----------
    masses : sequence of float
        ``m_i`` per node, ``0.0`` for a junction.
    elem_a, elem_b : sequence of int
        End nodes of every element (``-1`` for ground).
    spring : sequence of bool
        ``True`` where the element's law is in the elongation (else in its rate).
    """

    def __init__(self, masses: Sequence[float], elem_a: Sequence[int],
                 elem_b: Sequence[int], spring: Sequence[bool]) -> None:
        self.N = len(masses)
        self.E = len(elem_a)
        self.n = self.N + self.E
        #: the last :meth:`solve` failed because the locks in parallel cannot carry the
        #: load together (a least-squares point, not a root): a lock must break
        self.infeasible = False
        self._least_squares = False
        #: after :meth:`solve` held a force of ``cones`` at its bound: the stage values of
        #: the split before any was held (:mod:`lumped.solvers.modes.split_kink`), else None
        self.free_split: list[float] | None = None
        self.m = [float(mi) for mi in masses]
        self.ea = list(elem_a)
        self.eb = list(elem_b)
        self.spring = list(spring)

    # -- the stage system ----------------------------------------------------------------
    def evaluate(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                 f: list[list[float]], kernels: Sequence[Callable]):
        """Residual ``G`` and Jacobian ``J`` (list of rows) of the stage system at ``U``.

        ``f[k]`` is the external force per node at ``t_n + c_k h``; ``kernels[e]`` is the
        held branch's kernel ``(q, F) -> (R, dR/dq, dR/dF)`` of element ``e``.

        A spring held on a branch that locks its elongation at ``L`` (a kernel with a
        ``lock_value``, :meth:`lumped.codegen.branches.LawBranches.kernel_for`: a taut
        string) is held on the velocity level: its branch is affine in ``q`` with constant
        coefficients, and its residual is taken as ``R(L) + dR/dq h sum_l a_kl (V_l,b -
        V_l,a)``, not ``R(X_k,b - X_k,a)``: the positions carry their rounding, ``ulp(x)``,
        which the
        lock would turn into rates of ``ulp(x) / h`` and forces of ``m ulp(x) / h^2``,
        so that on a short step Newton cycled at round-off and the step size fell to its
        floor. The positions still follow the velocities, so ``q`` stays at ``L`` to
        their rounding.
        """
        N, E, n = self.N, self.E, self.n
        m, ea, eb, spring = self.m, self.ea, self.eb, self.spring
        size = 3 * n
        G = [0.0] * size
        J = [[0.0] * size for _ in range(size)]
        for k in range(3):
            base = k * n
            fk = f[k]
            Wk = W[k]
            for i in range(N):
                row = J[base + i]
                if m[i] > 0.0:
                    acc = 0.0
                    for j in range(3):
                        acc += Wk[j] * (U[j * n + i] - v_n[i])
                        row[j * n + i] = m[i] / h * Wk[j]
                    G[base + i] = m[i] / h * acc - fk[i]
                else:
                    G[base + i] = -fk[i]
            Ak = A[k]
            for e in range(E):
                col = base + N + e
                Fe = U[col]
                a, b = ea[e], eb[e]
                # net force: +F on a, -F on b; the balance row holds -net
                if a >= 0:
                    G[base + a] -= Fe
                    J[base + a][col] = -1.0
                if b >= 0:
                    G[base + b] += Fe
                    J[base + b][col] = 1.0
                lock = getattr(kernels[e], "lock_value", None) if spring[e] else None
                if lock is not None:  # a held position lock: on the velocity level
                    qb = 0.0
                    qa = 0.0
                    if b >= 0:
                        for j in range(3):
                            qb += Ak[j] * U[j * n + b]
                    if a >= 0:
                        for j in range(3):
                            qa += Ak[j] * U[j * n + a]
                elif spring[e]:
                    qb = 0.0
                    qa = 0.0
                    if b >= 0:
                        s = 0.0
                        for j in range(3):
                            s += Ak[j] * U[j * n + b]
                        qb = x_n[b] + h * s
                    if a >= 0:
                        s = 0.0
                        for j in range(3):
                            s += Ak[j] * U[j * n + a]
                        qa = x_n[a] + h * s
                else:
                    qb = U[base + b] if b >= 0 else 0.0
                    qa = U[base + a] if a >= 0 else 0.0
                if lock is not None:  # R(L + dq) = R(L) + dR/dq dq: affine, exactly
                    R, Rq, RF = kernels[e](lock, Fe)
                    R += Rq * (h * (qb - qa))
                else:
                    R, Rq, RF = kernels[e](qb - qa, Fe)
                lrow = J[col]
                G[col] = R
                lrow[col] = RF
                if spring[e]:
                    for j in range(3):
                        g = Rq * h * Ak[j]
                        if b >= 0:
                            lrow[j * n + b] += g
                        if a >= 0:
                            lrow[j * n + a] -= g
                else:
                    if b >= 0:
                        lrow[base + b] += Rq
                    if a >= 0:
                        lrow[base + a] -= Rq
        return G, J

    def solve(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
              f: list[list[float]], kernels: Sequence[Callable], scale: list[float],
              tol: float = 1e-3, max_iters: int = 10,
              cones: dict[int, tuple[float, ...]] | None = None,
              least_squares: bool = False) -> tuple[list[float] | None, int, int]:
        """Newton on the stage system from the guess ``U`` (modified in place).

        Converged when ``max_j |dU_j| / scale_j <= tol``; the Jacobian is refactored when
        the contraction rate exceeds 1/2 (simplified Newton otherwise). Returns
        ``(U or None, iterations, factorisations)``; ``None`` when Newton failed
        (non-finite or no convergence): the caller shrinks the step.  A singular Jacobian
        (locked elements in parallel: the split of their forces is free) is solved by the
        minimum-norm correction, the rule of the fixed-step methods, or, when ``cones``
        names the locked elements in parallel (``e -> (centre, half-width)`` of the force
        interval their lock admits), by the split of :func:`_cone_solver`. With ``cones``
        a stage is accepted only at a root (every residual within what a converged
        correction removes); a least-squares point of the split (the locks cannot carry
        the load together) sets :attr:`infeasible` and fails, unless ``least_squares``.
        """
        self.infeasible = False
        self._least_squares = least_squares
        self.free_split = None
        if not cones:
            return self._newton(U, h, x_n, v_n, f, kernels, scale, tol, max_iters, None, {})
        # locks in series and in parallel: the split of least weighted norm can leave a
        # cone while another split stays in every cone; hold the forces that left theirs
        # at the bound they crossed and solve again (an active set, at most 3 passes).
        # When no held split solves the stage (the cones cannot carry the load together:
        # the mode probe decides whether a lock breaks), the first split stands.
        start = list(U)
        held: dict[int, float] = {}
        its = nfac = 0
        first: list[float] | None = None
        for _ in range(3):
            U[:] = start
            got, k_its, k_fac = self._newton(U, h, x_n, v_n, f, kernels, scale, tol,
                                             max_iters, cones, held)
            its, nfac = its + k_its, nfac + k_fac
            if got is None:
                if first is None:
                    return None, its, nfac
                U[:] = first
                self.infeasible = False  # (a held pass that missed a root)
                return U, its, nfac
            if first is None:
                first = list(U)
            out = {}
            for k in range(3):
                for e, (_, w, lo, hi) in cones.items():
                    j = k * self.n + self.N + e
                    if j in held:
                        continue
                    # (an end held 1e-6 of the half-width inside, where the branch's
                    # guards are > 0)
                    inside = 1e-6 * w
                    if U[j] > hi + 1e-9 * w:
                        out[j] = hi - inside
                    elif U[j] < lo - 1e-9 * w:
                        out[j] = lo + inside
            if not out:
                if held:  # (the first pass: the split before any force was held)
                    self.free_split = first
                return got, its, nfac
            held.update(out)
        U[:] = first
        return U, its, nfac

    def _newton(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                f: list[list[float]], kernels: Sequence[Callable], scale: list[float],
                tol: float, max_iters: int, cones: dict[int, tuple[float, ...]] | None,
                held: dict[int, float]) -> tuple[list[float] | None, int, int]:
        """One simplified Newton solve of :meth:`solve`, with the forces of ``held`` (stage
        column -> force) held where the cone split puts them (:func:`_cone_solver`)."""
        G, J = self.evaluate(U, h, x_n, v_n, f, kernels)
        solve = self._solver(J, U, cones, held)
        nfac = 1
        prev = math.inf
        for it in range(1, max_iters + 1):
            du = solve([-g for g in G])
            worst = 0.0
            for j in range(len(U)):
                d = du[j]
                U[j] += d
                r = abs(d) / scale[j]
                if not r <= worst:
                    worst = r  # NaN lands here too
            if not math.isfinite(worst):
                return None, it, nfac
            G, J2 = self.evaluate(U, h, x_n, v_n, f, kernels)
            if worst <= tol:
                # the pseudo-inverse of the cone split converges to a least-squares point
                # when the locks cannot carry the load together: only a root is a solution
                if cones and not self._least_squares and not _solves(G, J2, scale, tol):
                    self.infeasible = True
                    return None, it, nfac
                return U, it, nfac
            if worst > 0.5 * prev:
                solve = self._solver(J2, U, cones, held)
                nfac += 1
            prev = worst
        return None, max_iters, nfac

    def solve_damped(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                     f: list[list[float]], kernels: Sequence[Callable], scale: list[float],
                     tol: float = 1e-3, max_iters: int = 10
                     ) -> tuple[list[float] | None, int, int]:
        r"""Full Newton with a backtracking line search from ``U`` (modified in place),
        then :meth:`solve` from where it ends: the fallback for a stage that the
        simplified Newton of :meth:`solve` misses at every step size.

        Such a stage starts at a branch's end where the rate is flat in the force,
        ``dR/dF = 0`` (Herschel-Bulkley with ``n > 1`` at its yield force, ``q = gamma
        (F - tau)^n``): the force then grows like ``(q / gamma)^{1/n}``, ``sqrt(h)`` for
        ``n = 2``, and the full Newton step from the end overshoots it by ``h^{-1/2}``,
        after which the iterates come back only by halving, more slowly the shorter the
        step. Each iteration solves ``J dU = -G`` and takes ``U + lam dU`` with ``lam = 1,
        1/2, ...`` until the merit ``phi = max_i |G_i| / S_i``, ``S_i = sum_j |J_ij|
        scale_j`` (the rows' change per tolerance of the unknowns, fixed within one line
        search), falls by at least ``1e-4 lam``; it stops when the correction is within the
        convergence test,
        and :meth:`solve` then converges from there by its own test (the stage this
        returns is one :meth:`solve` accepts). Returns ``(U or None, iterations,
        factorisations)``.
        """
        its = 0
        for _ in range(4 * max_iters):
            G, J = self.evaluate(U, h, x_n, v_n, f, kernels)
            S = [_row_scale(row, scale) + 1e-300 for row in J]
            phi = max(abs(g) / s for g, s in zip(G, S, strict=True))
            if not math.isfinite(phi):
                return None, its, its
            its += 1
            du = _solver(J)([-g for g in G])
            if max(abs(d) / sc for d, sc in zip(du, scale, strict=True)) <= tol:
                break
            lam = 1.0
            while lam > 1e-12:
                trial = [u + lam * d for u, d in zip(U, du, strict=True)]
                G_t = self.evaluate(trial, h, x_n, v_n, f, kernels)[0]
                phi_t = max(abs(g) / s for g, s in zip(G_t, S, strict=True))
                if phi_t <= (1.0 - 1e-4 * lam) * phi:
                    U[:] = trial
                    break
                lam *= 0.5
            else:
                return None, its, its
        else:
            return None, its, its
        got, k_its, k_fac = self.solve(U, h, x_n, v_n, f, kernels, scale, tol=tol,
                                       max_iters=max_iters)
        return got, its + k_its, its + k_fac

    def _solver(self, J: list[list[float]], U: list[float],
                cones: dict[int, tuple[float, ...]] | None, held: dict[int, float]):
        # locks in parallel make J singular, but only to round-off once the stage rows
        # mix: an LU would then pick the split from the round-off; the SVD does not
        if cones and all(math.isfinite(a) for row in J for a in row):
            return _cone_solver(J, U, cones, self.N, self.n, held)
        return _solver(J)

    # -- the error estimate ---------------------------------------------------------------
    def error(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
              net_n: list[float], jac_n: list[tuple[float, float]]) -> list[float] | None:
        r"""The filtered local error estimate of RADAU5, ``(e_x (N), e_v (N), e_F (E))``.

        Solves ``(mu/h M - J) e = f(y_n) + M sum_k E_k Z_k / h`` with ``Z_k = Y_k - y_n``:
        rows ``x' = v`` per node, momentum per mass (the junction balances and the laws
        have ``M = 0`` and right side 0: ``y_n`` is consistent), with the laws
        linearised at ``y_n`` (``jac_n[e] = (dR/dq, dR/dF)``); minimum norm if singular.
        """
        N, E, n = self.N, self.E, self.n
        m, ea, eb, spring = self.m, self.ea, self.eb, self.spring
        size = 2 * N + E
        M = [[0.0] * size for _ in range(size)]
        rhs = [0.0] * size
        g = MU_REAL / h
        for i in range(N):
            zx = 0.0
            zv = 0.0
            for k in range(3):
                s = 0.0
                for j in range(3):
                    s += A[k][j] * U[j * n + i]
                zx += E_ERR[k] * s  # (X_k - x_n) / h
                zv += E_ERR[k] * (U[k * n + i] - v_n[i])
            M[i][i] = g
            M[i][N + i] = -1.0
            rhs[i] = v_n[i] + zx
            if m[i] > 0.0:
                M[N + i][N + i] = g * m[i]
                rhs[N + i] = net_n[i] + m[i] * zv / h
        for e in range(E):
            col = 2 * N + e
            a, b = ea[e], eb[e]
            if a >= 0:
                M[N + a][col] -= 1.0
            if b >= 0:
                M[N + b][col] += 1.0
            Rq, RF = jac_n[e]
            off = 0 if spring[e] else N
            if b >= 0:
                M[col][off + b] -= Rq
            if a >= 0:
                M[col][off + a] += Rq
            M[col][col] = -RF
        return _solver(M)(rhs)

    def error_norm(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                   F_n: list[float], err: list[float], rtol: float, atol: float,
                   dF_n: list[float] | None, watched: Sequence[int], F_ref: float) -> float:
        r"""RMS of the scaled error: ``x`` of every node and ``v`` of every mass from ``err``
        (:meth:`error`), and the forces of the ``watched`` elements (those whose guards
        decide the events) when their slope ``dF_n`` at ``t_n`` is known (the previous
        step's polynomial): ``gamma_0 (h F'_n + sum_k E_k (F_k - F_n))``, the embedded
        estimate of their polynomial, unfiltered (a force is as smooth as the rates that
        set it). Scales: ``atol + rtol max(|y_n|, |y_n+1|)``, for forces
        ``rtol_F max(|F_n|, |F_n+1|, F_ref)`` with ``rtol_F = min(1e-3, 100 rtol)``: the
        forces' polynomial only has to show a guard's sign change, whose time is then
        found on exact end-of-step values."""
        N, n, m = self.N, self.n, self.m
        A3 = A[2]
        acc = 0.0
        cnt = 0
        for i in range(N):
            x_new = x_n[i] + h * (A3[0] * U[i] + A3[1] * U[n + i] + A3[2] * U[2 * n + i])
            sc = atol + rtol * max(abs(x_n[i]), abs(x_new))
            acc += (err[i] / sc) ** 2
            cnt += 1
            if m[i] > 0.0:
                sc = atol + rtol * max(abs(v_n[i]), abs(U[2 * n + i]))
                acc += (err[N + i] / sc) ** 2
                cnt += 1
        if dF_n is not None:
            g0 = 1.0 / MU_REAL
            rtol_F = min(1e-3, FORCE_TOL_FACTOR * rtol)
            for e in watched:
                k0 = N + e
                Fe = F_n[e]
                est = h * dF_n[e]
                for k in range(3):
                    est += E_ERR[k] * (U[k * n + k0] - Fe)
                sc = rtol_F * max(abs(Fe), abs(U[2 * n + k0]), F_ref)
                acc += (g0 * est / sc) ** 2
                cnt += 1
        return math.sqrt(acc / cnt)

    def element_nodes(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                      F_n: list[float], e: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """``(q, F)`` of element ``e`` at the polynomial's nodes ``s = 0, c_1, c_2, 1``.

        ``q`` is linear in the state, so its collocation polynomial has these nodes: the
        guards along the step need no state vector (:func:`lumped.solvers.modes.events.
        first_crossing_on`)."""
        N, n = self.N, self.n
        a, b = self.ea[e], self.eb[e]
        if self.spring[e]:
            def at(i: int, k: int) -> float:
                if i < 0:
                    return 0.0
                if k < 0:
                    return x_n[i]
                Ak = A[k]
                return x_n[i] + h * (Ak[0] * U[i] + Ak[1] * U[n + i] + Ak[2] * U[2 * n + i])
        else:
            def at(i: int, k: int) -> float:
                if i < 0:
                    return 0.0
                return v_n[i] if k < 0 else U[k * n + i]
        q = tuple(at(b, k) - at(a, k) for k in (-1, 0, 1, 2))
        col = N + e
        return q, (F_n[e], U[col], U[n + col], U[2 * n + col])

    def end_slope(self, U: list[float], h: float, F_n: list[float]) -> list[float]:
        """``F'`` of every element at the end of the step, from its collocation polynomial."""
        N, n = self.N, self.n
        s1, s2, s3 = END_SLOPES
        return [(s1 * (U[N + e] - F_n[e]) + s2 * (U[n + N + e] - F_n[e])
                 + s3 * (U[2 * n + N + e] - F_n[e])) / h for e in range(self.E)]
