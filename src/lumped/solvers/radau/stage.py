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

with ``q_e = X_b - X_a`` (springs) or ``V_b - V_a`` (dashpots), ground at 0, plus an
element's support offset ``o_e(t_n + c_k h)`` at the stage's own time when the scene has
moving supports (:attr:`StageSystem.frame`: the clock of the shifted laws is set to each
stage's time before its rows are formed, :mod:`lumped.scene.supports`). The step's
result is stage 3 (``c_3 = 1``: stiffly accurate), and the stage values with ``y_n`` are
the nodes of the collocation polynomial (the dense output,
:func:`~lumped.solvers.radau.tableau.dense_weights`; the method's coefficients are in
:mod:`lumped.solvers.radau.tableau`).

This module owns the stage system (:class:`StageSystem`: its residual and Jacobian, its
simplified Newton with the active set of the cone split, the damped fallback, the element values
at the polynomial's nodes) and the limits of the ``radau5`` loop (:data:`STALL_PASSES`,
:data:`MAX_NEWTON`, :data:`DAMPED_AFTER`). The linear solves, plain and split among locks in
parallel, are in :mod:`lumped.solvers.radau.cone_split`; the error estimate and its norm in
:mod:`lumped.solvers.radau.error`. Everything here runs on flat lists of Python floats with
scalar loops (numba-friendly). The unknowns are laid out stage by stage: ``U[k*n + i]`` is
``V_k,i`` for a node ``i < N`` and ``U[k*n + N + e]`` is ``F_k,e``, ``n = N + E``.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from .cone_split import cone_solver, linear_solver, row_scale, solves
from .error import ErrorEstimate
from .roundoff import junction_columns, rate_rows, roundoff_worst
from .tableau import END_SLOPES, A, C, W

__all__ = ["DAMPED_AFTER", "MAX_NEWTON", "STALL_PASSES", "StageSystem"]

#: The nodes ``s`` of a step's polynomial (:meth:`StageSystem.element_nodes`).
_NODES = (0.0, *C)

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


class StageSystem(ErrorEstimate):
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
        self.infeasible = self._least_squares = False
        #: after :meth:`solve` held a force of ``cones`` at its bound: the stage values of
        #: the split before any was held (:mod:`lumped.solvers.modes.split_kink`), else None
        self.free_split: list[float] | None = None
        self.m = [float(mi) for mi in masses]
        self.junction = junction_columns(self.m, self.n)  # (a junction's velocity)
        self.ea = list(elem_a)
        self.eb = list(elem_b)
        self.spring = list(spring)
        self.rate = rate_rows(self.N, self.spring)  # (a dashpot's law)
        #: the :class:`~lumped.scene.supports.SupportFrame` of a scene with moving
        #: supports (the kernels read its offsets), else None; ``t_n`` the step's start
        self.frame = None
        self.t_n = 0.0
        self.after_impact = False  #: the step starts at an impact (:mod:`.roundoff`)

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
        which the lock would turn into rates of ``ulp(x) / h`` and forces of ``m ulp(x) /
        h^2``, so that on a short step Newton cycled at round-off and the step fell to its
        floor. The positions still follow the velocities (``q`` at ``L`` to their rounding).
        """
        N, E, n = self.N, self.E, self.n
        m, ea, eb, spring = self.m, self.ea, self.eb, self.spring
        size = 3 * n
        G = [0.0] * size
        J = [[0.0] * size for _ in range(size)]
        frame = self.frame  # a lock on a support moves with it (h A o_e')
        moves = frame.lock_moves(self.t_n, h, A, C) if frame is not None else None
        for k in range(3):
            base = k * n
            fk = f[k]
            Wk = W[k]
            if frame is not None:  # the shifted laws at the stage's time
                frame.at_time(self.t_n + C[k] * h)
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
                    R, Rq, RF = getattr(kernels[e], "bare", kernels[e])(lock, Fe)
                    R += Rq * (h * (qb - qa) + (moves[k][e] if moves else 0.0))
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

        Converged when ``max_j |dU_j| / scale_j <= tol`` (a junction's velocity also at its
        round-off, :mod:`~lumped.solvers.radau.roundoff`); the Jacobian is refactored when
        the contraction rate exceeds 1/2 (simplified Newton otherwise). Returns
        ``(U or None, iterations, factorisations)``; ``None`` when Newton failed
        (non-finite or no convergence): the caller shrinks the step.  A singular Jacobian
        (locked elements in parallel: the split of their forces is free) is solved by the
        minimum-norm correction, the rule of the fixed-step methods, or, when ``cones``
        names the locked elements in parallel (``e -> (centre, half-width)`` of the force
        interval their lock admits), by the split of
        :func:`~lumped.solvers.radau.cone_split.cone_solver`. With ``cones``
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
        column -> force) held where the cone split puts them
        (:func:`~lumped.solvers.radau.cone_split.cone_solver`)."""
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
            worst = roundoff_worst(du, U, J2, scale, self.junction, self.rate, f, tol, worst,
                                   h, self.after_impact)
            if worst <= tol:
                # the pseudo-inverse of the cone split converges to a least-squares point
                # when the locks cannot carry the load together: only a root is a solution
                if cones and not self._least_squares and not solves(G, J2, scale, tol):
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
        convergence test, and :meth:`solve` then converges from there by its own test (the
        stage this returns is one :meth:`solve` accepts). Returns ``(U or None, iterations,
        factorisations)``.
        """
        its = 0
        for _ in range(4 * max_iters):
            G, J = self.evaluate(U, h, x_n, v_n, f, kernels)
            S = [row_scale(row, scale) + 1e-300 for row in J]
            phi = max(abs(g) / s for g, s in zip(G, S, strict=True))
            if not math.isfinite(phi):
                return None, its, its
            its += 1
            du = linear_solver(J)([-g for g in G])
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
            return cone_solver(J, U, cones, self.N, self.n, held)
        return linear_solver(J)

    def element_nodes(self, U: list[float], h: float, x_n: list[float], v_n: list[float],
                      F_n: list[float], e: int) -> tuple[tuple[float, ...], tuple[float, ...]]:
        """``(q, F)`` of element ``e`` at the polynomial's nodes ``s = 0, c_1, c_2, 1``.

        ``q`` is linear in the state, so its collocation polynomial has these nodes: the
        guards along the step need no state vector
        (:func:`lumped.solvers.modes.crossing_root.first_root_py`)."""
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
        if self.frame is not None:  # the law's argument: the support offset at each node
            q = tuple(qk + o[e] for qk, o in zip(
                q, self.frame.offsets_along(self.t_n, h, _NODES), strict=True))
        col = N + e
        return q, (F_n[e], U[col], U[n + col], U[2 * n + col])

    def end_slope(self, U: list[float], h: float, F_n: list[float]) -> list[float]:
        """``F'`` of every element at the end of the step, from its collocation polynomial."""
        N, n = self.N, self.n
        s1, s2, s3 = END_SLOPES
        return [(s1 * (U[N + e] - F_n[e]) + s2 * (U[n + N + e] - F_n[e])
                 + s3 * (U[2 * n + N + e] - F_n[e])) / h for e in range(self.E)]
