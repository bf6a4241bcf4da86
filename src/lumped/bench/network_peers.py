r"""The scipy peer for networks: any scene of springs and dashpots as an ODE, with every
Bingham or Coulomb dashpot replaced by its tanh-smoothed force law, for
:func:`scipy.integrate.solve_ivp` (what :mod:`.peers` does for one mass).

Smoothed laws (``q`` the elongation or its rate, ``F`` the tension, ``eps > 0``):

=================  ==========================================================
``linear_spring``  ``F = k q``
``newtonian``      ``F = c q``
``bingham``        ``F = q / gamma + tau tanh(q / eps)``
``coulomb``        ``F = tau tanh(q / eps)``
=================  ==========================================================

Away from ``q = 0`` (``|q| >> eps``) the smoothed Bingham and Coulomb forces equal the
exact laws' slipping branches, ``q/gamma + sgn(q) tau`` and ``sgn(q) tau``; near it they
replace the set-valued stuck branch by a steep slope ``tau / eps``, so the model error
shrinks with ``eps`` and ``eps`` must shrink with the accuracy sought.

State ``y = (x_i for every node, v_i for every mass)`` in the scene's node order. The
velocity of a massless junction is not a state: it is the root of the junction's force
balance (eq. 4a with ``m = 0``)

.. math::  0 = f_j(t) + \sum_{e: a_e = j} F_e - \sum_{e: b_e = j} F_e,

solved by Newton's method at every right-hand-side call, warm-started from the previous
call. Every dashpot force is increasing in its rate, so the balance is decreasing in the
junction velocities and the Newton matrix is a weighted graph Laplacian; a junction
touched by no dashpot has no velocity equation and is refused. The analytic Jacobian
differentiates the junction velocities by the implicit function theorem.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ..scene import Mass, Scene
from ..solvers.eventdriven.setup import breakpoints
from ..solvers.newton.linalg import lu_factor, lu_solve

__all__ = ["SMOOTHED_LAWS", "TanhNetwork", "solve_tanh_network"]

#: The laws the smoothed model knows.
SMOOTHED_LAWS = ("linear_spring", "newtonian", "bingham", "coulomb")


def _sech2_over_eps(u: float, eps: float) -> float:
    """``d tanh(u / eps) / du``, free of overflow (``e^{-2|u|/eps} <= 1``)."""
    e = math.exp(-2.0 * abs(u) / eps)
    return 4.0 * e / ((1.0 + e) * (1.0 + e)) / eps


class TanhNetwork:
    r"""``scene`` as the ODE ``y' = f(t, y)`` of its tanh-smoothed laws.

    Parameters
    ----------
    scene : Scene
        Masses, junctions and elements with laws among :data:`SMOOTHED_LAWS`.
    eps : float
        Smoothing velocity of ``tanh(q / eps)``, ``> 0``.

    Attributes
    ----------
    y0 : list of float
        The scene's initial ``x`` of every node, then ``v`` of every mass.
    x_slots : dict
        Node name -> index of its ``x`` in ``y``.
    """

    def __init__(self, scene: Scene, eps: float) -> None:
        if not (isinstance(eps, (int, float)) and math.isfinite(eps) and eps > 0):
            raise ValueError(f"`eps` must be a finite number > 0, got {eps!r}")
        self.scene, self.eps = scene, float(eps)
        n = len(scene.nodes)
        self.masses = [i for i, nd in enumerate(scene.nodes) if isinstance(nd, Mass)]
        self.junctions = [i for i, nd in enumerate(scene.nodes) if not isinstance(nd, Mass)]
        self.x_slots = {nd.name: i for i, nd in enumerate(scene.nodes)}
        self.y0 = [nd.x0 for nd in scene.nodes] + [scene.nodes[i].v0 for i in self.masses]
        self._v_slot = {i: n + s for s, i in enumerate(self.masses)}
        # per element: (is dashpot, a, b, slope 1/gamma or k or c, tau)
        self.elements: list[tuple[bool, int, int, float, float]] = []
        for el, a, b in zip(scene.elements, scene.elem_a, scene.elem_b, strict=True):
            p, name = el.law.params, el.law_name
            if name == "linear_spring":
                row = (False, a, b, float(p["k"]), 0.0)
            elif name == "newtonian":
                row = (True, a, b, float(p["c"]), 0.0)
            elif name == "bingham":
                row = (True, a, b, 1.0 / float(p["gamma"]), float(p["tau"]))
            elif name == "coulomb":
                row = (True, a, b, 0.0, float(p["tau"]))
            else:
                raise ValueError(
                    f"the tanh peer has no smoothed form of law {name!r} (element "
                    f"{el.name!r}); it knows {list(SMOOTHED_LAWS)}")
            self.elements.append(row)
        for j in self.junctions:
            if not any(d and j in (a, b) for d, a, b, _, _ in self.elements):
                raise ValueError(f"junction {scene.nodes[j].name!r} is touched by no dashpot: "
                                 "its velocity has no equation in the smoothed ODE")
        self._vj = [0.0] * len(self.junctions)
        self.junction_newton_iterations = 0

    # -- the laws ---------------------------------------------------------------------------
    def force(self, e: int, q: float) -> float:
        """Smoothed force of element ``e`` at elongation (rate) ``q``."""
        dash, _, _, s, tau = self.elements[e]
        return s * q + (tau * math.tanh(q / self.eps) if tau else 0.0)

    def slope(self, e: int, q: float) -> float:
        """``dF/dq`` of element ``e``, ``> 0`` wherever the law has a slope."""
        _, _, _, s, tau = self.elements[e]
        return s + (tau * _sech2_over_eps(q, self.eps) if tau else 0.0)

    def _node_values(self, y: Sequence[float], vj: Sequence[float]) -> tuple[list, list]:
        n = len(self.scene.nodes)
        x = [float(y[i]) for i in range(n)]
        v = [0.0] * n
        for i in self.masses:
            v[i] = float(y[self._v_slot[i]])
        for s, j in enumerate(self.junctions):
            v[j] = vj[s]
        return x, v

    def _forces(self, x: list, v: list) -> list[float]:
        out = []
        for e, (dash, a, b, _, _) in enumerate(self.elements):
            w = v if dash else x
            out.append(self.force(e, (w[b] if b >= 0 else 0.0) - (w[a] if a >= 0 else 0.0)))
        return out

    # -- junction velocities ----------------------------------------------------------------
    def junction_velocities(self, t: float, y: Sequence[float], max_iters: int = 100
                            ) -> list[float]:
        r"""The velocities of the junctions, roots of their force balances at ``(t, y)``.

        Newton's method from the previous root, with step halving on the balance's norm.
        Raises ``RuntimeError`` naming ``t`` and the residual if it does not converge.
        """
        if not self.junctions:
            return []
        f = self.scene.external_forces(t)
        vj = list(self._vj)
        res = self._junction_residual(y, vj, f)
        norm = max(abs(r) for r in res)
        for _ in range(max_iters):
            x, v = self._node_values(y, vj)
            scale = 1.0 + max(abs(F) for F in self._forces(x, v))
            if norm <= 1e-14 * scale:
                break
            self.junction_newton_iterations += 1
            lu = lu_factor(self._junction_matrix(y, vj))
            if lu is None:
                raise RuntimeError(f"singular junction balance at t = {t!r}")
            dv = lu_solve(lu, [-r for r in res])
            step = 1.0
            while True:
                trial = [a + step * b for a, b in zip(vj, dv, strict=True)]
                res_t = self._junction_residual(y, trial, f)
                norm_t = max(abs(r) for r in res_t)
                if norm_t < norm or step < 1e-10:
                    break
                step *= 0.5
            converged = max(abs(step * d) for d in dv) <= 1e-15 * (1.0 + max(map(abs, vj)))
            vj, res, norm = trial, res_t, norm_t
            if converged:
                break
        else:
            raise RuntimeError(f"junction balance did not converge at t = {t!r}: "
                               f"residual {norm!r}")
        self._vj = vj
        return vj

    def _junction_residual(self, y: Sequence[float], vj: Sequence[float],
                           f: Sequence[float]) -> list[float]:
        x, v = self._node_values(y, vj)
        net = list(f)
        for F, (_, a, b, _, _) in zip(self._forces(x, v), self.elements, strict=True):
            if a >= 0:
                net[a] += F
            if b >= 0:
                net[b] -= F
        return [net[j] for j in self.junctions]

    def _junction_matrix(self, y: Sequence[float], vj: Sequence[float]) -> list[list[float]]:
        x, v = self._node_values(y, vj)
        col = {j: s for s, j in enumerate(self.junctions)}
        J = [[0.0] * len(vj) for _ in vj]
        for e, (dash, a, b, _, _) in enumerate(self.elements):
            if not dash:
                continue
            s = self.slope(e, (v[b] if b >= 0 else 0.0) - (v[a] if a >= 0 else 0.0))
            # +F on a, -F on b; dF/dv_b = s, dF/dv_a = -s
            for row_node, sign in ((a, 1.0), (b, -1.0)):
                if row_node in col:
                    if b in col:
                        J[col[row_node]][col[b]] += sign * s
                    if a in col:
                        J[col[row_node]][col[a]] -= sign * s
        return J

    # -- the ODE ---------------------------------------------------------------------------
    def rhs(self, t: float, y: Sequence[float]) -> list[float]:
        r"""``y' = (v_i for every node, net_i / m_i for every mass)``."""
        vj = self.junction_velocities(t, y)
        x, v = self._node_values(y, vj)
        net = self.scene.net_forces(t, self._forces(x, v))
        return v + [net[i] / self.scene.nodes[i].m for i in self.masses]

    def jac(self, t: float, y: Sequence[float]) -> np.ndarray:
        r"""``df/dy``, with ``dv_J/dy = -(dG/dv_J)^{-1} dG/dy`` at the junctions (``G``
        their balances)."""
        n, nm = len(self.scene.nodes), len(self.masses)
        vj = self.junction_velocities(t, y)
        x, v = self._node_values(y, vj)
        # dX/dy and dV/dy with the junction velocities held fixed
        PX = np.zeros((n, n + nm))
        PX[:, :n] = np.eye(n)
        PV = np.zeros((n, n + nm))
        for i in self.masses:
            PV[i, self._v_slot[i]] = 1.0
        AX, AV = np.zeros((n, n)), np.zeros((n, n))  # d net / dX, d net / dV
        for e, (dash, a, b, _, _) in enumerate(self.elements):
            w = v if dash else x
            s = self.slope(e, (w[b] if b >= 0 else 0.0) - (w[a] if a >= 0 else 0.0))
            A = AV if dash else AX
            for row, sign in ((a, 1.0), (b, -1.0)):
                if row < 0:
                    continue
                if b >= 0:
                    A[row, b] += sign * s
                if a >= 0:
                    A[row, a] -= sign * s
        dnet = AX @ PX + AV @ PV
        dV = PV
        if self.junctions:
            J = self.junctions
            dvj = -np.linalg.solve(AV[np.ix_(J, J)], dnet[J, :])
            dV = PV.copy()
            dV[J, :] = dvj
            dnet = AX @ PX + AV @ dV
        inv_m = np.array([1.0 / self.scene.nodes[i].m for i in self.masses])
        return np.vstack([dV, dnet[self.masses, :] * inv_m[:, None]])


def solve_tanh_network(
    scene: Scene, t_end: float, t_eval: np.ndarray, *, eps: float, rtol: float,
    atol: float, method: str = "LSODA", max_nfev: int = 200_000,
) -> tuple[np.ndarray, dict]:
    r"""Run :func:`scipy.integrate.solve_ivp` on the smoothed ``scene`` up to ``t_end``.

    The run restarts at every breakpoint of the forcing (a sine burst's switch-off), as
    the one-mass peer does. Returns ``x`` of every node at ``t_eval`` (shape
    ``(len(t_eval), n_nodes)``, from the dense output) and counters ``steps``,
    ``nfev``, ``njev``. Raises ``RuntimeError`` if scipy fails or more than ``max_nfev``
    right-hand sides are evaluated.
    """
    from scipy.integrate import solve_ivp

    model = TanhNetwork(scene, eps)
    count = [0]

    def rhs(t: float, y: Sequence[float]) -> list[float]:
        count[0] += 1
        if count[0] > max_nfev:
            raise RuntimeError(f"gave up after {max_nfev} right-hand-side evaluations")
        return model.rhs(t, y)

    edges = [0.0, *breakpoints(scene, t_end), t_end]
    t_eval = np.asarray(t_eval, dtype=float)
    out = np.empty((len(t_eval), len(scene.nodes)))
    y0: list[float] = list(model.y0)
    lo, steps, njev = 0, 0, 0
    for k, (a, b) in enumerate(zip(edges[:-1], edges[1:], strict=True)):
        sol = solve_ivp(rhs, (a, b), y0, method=method, rtol=rtol, atol=atol,
                        jac=None if method in ("RK45", "DOP853") else model.jac,
                        dense_output=True)
        if sol.status < 0:
            raise RuntimeError(f"solve_ivp ({method}) status {sol.status}: {sol.message}")
        hi = len(t_eval) if k == len(edges) - 2 else int(np.searchsorted(t_eval, b, "right"))
        out[lo:hi] = sol.sol(t_eval[lo:hi])[: len(scene.nodes)].T
        lo, y0 = hi, [float(c) for c in sol.y[:, -1]]
        steps += len(sol.t) - 1
        njev += int(sol.njev)
    return out, {"steps": steps, "nfev": count[0], "njev": njev}

