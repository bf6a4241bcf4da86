r"""The rows of the consistent initial state's limit system, evaluated with less work.

The limit ``h = eps -> 0`` of an implicit step (:func:`lumped.solvers.implicit.
initial_state.consistent_initial_state`, step 2), in the unknowns ``u = (a, F)``: the
masses' accelerations (a junction's velocity where the node is a junction) and the
elements' forces. With ``d_i = eps a_i`` for a mass and ``d_i = u_i`` for a junction
(``d_{-1} = 0``, ground), an element ``e`` from node ``a`` to node ``b`` (force ``F_e``
positive in tension: it pulls ``b`` back, ``a`` on) and the load ``f_i``:

.. math::

    G_i = m_i a_i - f_i - \sum_{e: b_e = i} F_e + \sum_{e: a_e = i} F_e
    \quad(\text{junctions: } m_i a_i \text{ absent}),

    G_{N+e} = R_e(q_e, F_e), \quad q_e = q_{0,e} + r_e + s_e (d_b - d_a),

with ``s_e = eps`` for a spring (its elongation moves by ``eps v``), ``1`` for a
dashpot (its rate is ``q0`` plus the change), ``r_e`` a dashpot's rate on a moving
support, and ``G_{N+e} = F_e - F_e^{pin}`` for a force its law alone fixes (pinned).
(The signs as written in the code: ``G_a += -F_e``, ``G_b += F_e``.) The row scales
``S`` are the sums of the terms' magnitudes (a law row's by
:func:`~lumped.solvers.implicit.step_system.law_scale`) and ``J`` the generalised
Jacobian.

:func:`limit_rows` returns ``evaluate(u) -> (G, J, S)``. What does not change with
``u`` is made once per solve: the Jacobian's constant entries (``m_i``, the incidence
``+-1``, a pinned row's ``1``), the junctions' load rows and each element's fixed
numbers. Every row is computed with the same floating-point operations, in the same
order, as the loop it replaces, so the same ``G``, ``J`` and ``S`` bit for bit (a
sum's order decides its rounding; ``-1.0 * F`` is ``-F`` exactly).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from .step_system import law_scale

__all__ = ["limit_rows"]

Rows = tuple[list[float], list[list[float]], list[float]]


def limit_rows(is_mass: Sequence[bool], mass: Sequence[float], f: Sequence[float],
               ea: Sequence[int], eb: Sequence[int], pinned: Sequence[float | None],
               q0: Sequence[float], q_rate: Sequence[float], kernels: Sequence[Callable],
               spring: Sequence[bool], eps: float) -> Callable[[list[float]], Rows]:
    """``evaluate(u) -> (G, J, S)`` of the limit system (see the module notes) for nodes
    ``is_mass``/``mass`` under the loads ``f``, elements ``ea``/``eb`` with the law
    ``kernels``, ``spring`` flags, initial elongations (springs) or rates (dashpots)
    ``q0``, support rates ``q_rate`` and forces ``pinned`` by their laws (``None``
    where free), at the vanishing step ``eps``."""
    N, E = len(is_mass), len(ea)
    n = N + E
    J0 = [[0.0] * n for _ in range(n)]
    G0 = [0.0] * n
    S0 = [0.0] * n
    masses = []
    for i in range(N):
        if is_mass[i]:
            J0[i][i] = mass[i]
            masses.append((i, mass[i], f[i]))
        else:
            G0[i] = -f[i]
            S0[i] = abs(f[i])
    rows = []  # per element, in order: its row, ends, pinned force and law's numbers
    for e in range(E):
        k, a, b = N + e, ea[e], eb[e]
        if a >= 0:
            J0[a][k] = -1.0
        if b >= 0:
            J0[b][k] = 1.0
        Fp = pinned[e]
        if Fp is not None:
            J0[k][k] = 1.0
        rows.append((k, a, b, Fp, q0[e] + q_rate[e], eps if spring[e] else 1.0, kernels[e],
                     a >= 0 and is_mass[a], b >= 0 and is_mass[b],
                     (eps if is_mass[a] else 1.0) if a >= 0 else 0.0,
                     (eps if is_mass[b] else 1.0) if b >= 0 else 0.0))

    def evaluate(u: list[float]) -> Rows:
        G = G0[:]
        S = S0[:]
        J = [row[:] for row in J0]
        for i, m, fi in masses:
            p = m * u[i]
            G[i] = p - fi
            S[i] = abs(p) + abs(fi)
        for k, a, b, Fp, base, scale, kernel, a_mass, b_mass, dd_a, dd_b in rows:
            Fe = u[k]
            if a >= 0:
                G[a] += -1.0 * Fe
                S[a] += abs(Fe)
            if b >= 0:
                G[b] += 1.0 * Fe
                S[b] += abs(Fe)
            if Fp is not None:
                G[k] = Fe - Fp
                S[k] = abs(Fe) + abs(Fp)
                continue
            # d_i: the node's velocity increment (eps a for masses, v for junctions)
            d_b = (eps * u[b] if b_mass else u[b]) if b >= 0 else 0.0
            d_a = (eps * u[a] if a_mass else u[a]) if a >= 0 else 0.0
            q = base + scale * (d_b - d_a)
            R, Rq, RF = kernel(q, Fe)
            G[k] = R
            S[k] = law_scale(kernel, q, Fe, R, Rq, RF)
            Jk = J[k]
            Jk[k] = RF
            if a >= 0:
                Jk[a] = -Rq * scale * dd_a
            if b >= 0:
                Jk[b] = Rq * scale * dd_b
        return G, J, S

    return evaluate
