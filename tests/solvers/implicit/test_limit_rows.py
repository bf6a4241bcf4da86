"""The limit system's rows (lumped.solvers.implicit.limit_rows): the residual, Jacobian
and row scales of the plain loop over nodes and elements that the consistent initial
state used before, bit for bit (signed zeros included), at random states of random
networks."""

from __future__ import annotations

import struct

from hypothesis import given, settings
from hypothesis import strategies as st

from lumped.laws import get_law
from lumped.solvers.implicit.limit_rows import limit_rows
from lumped.solvers.implicit.step_system import law_scale

LAWS = {"spring": [get_law("linear_spring").bind(k=3.7), get_law("string_spring").bind(
    k=12.5, L=0.25)], "dashpot": [get_law("bingham").bind(gamma=2.3, tau=0.7),
                                  get_law("newtonian").bind(c=0.9),
                                  get_law("coulomb").bind(tau=1.1, r=40.0)]}


def loop_rows(is_mass, mass, f, ea, eb, pinned, q0, q_rate, kernels, spring, eps, u):
    """The rows as the loop wrote them (the reference)."""
    N, E = len(is_mass), len(ea)
    n = N + E
    G, S = [0.0] * n, [0.0] * n
    J = [[0.0] * n for _ in range(n)]
    d = [eps * u[i] if is_mass[i] else u[i] for i in range(N)]
    dd = [eps if is_mass[i] else 1.0 for i in range(N)]
    for i in range(N):
        if is_mass[i]:
            p = mass[i] * u[i]
            G[i], S[i], J[i][i] = p - f[i], abs(p) + abs(f[i]), mass[i]
        else:
            G[i], S[i] = -f[i], abs(f[i])
    for e in range(E):
        k, a, b, Fe = N + e, ea[e], eb[e], u[N + e]
        for i, sgn in ((a, -1.0), (b, 1.0)):
            if i >= 0:
                G[i] += sgn * Fe
                S[i] += abs(Fe)
                J[i][k] = sgn
        row = J[k]
        if pinned[e] is not None:
            G[k], S[k], row[k] = Fe - pinned[e], abs(Fe) + abs(pinned[e]), 1.0
            continue
        scale = eps if spring[e] else 1.0
        q = q0[e] + q_rate[e] + scale * ((d[b] if b >= 0 else 0.0) - (d[a] if a >= 0 else 0.0))
        R, Rq, RF = kernels[e](q, Fe)
        G[k], S[k], row[k] = R, law_scale(kernels[e], q, Fe, R, Rq, RF), RF
        if a >= 0:
            row[a] = -Rq * scale * dd[a]
        if b >= 0:
            row[b] = Rq * scale * dd[b]
    return G, J, S


def _bits(rows) -> bytes:
    G, J, S = rows
    flat = list(G) + [x for row in J for x in row] + list(S)
    return struct.pack(f"{len(flat)}d", *flat)


#: Signed zeros, numbers whose sums round (0.1, 1/3) and any others.
values = st.one_of(st.sampled_from([0.0, -0.0, 1.0, -2.5, 0.1, 1.0 / 3.0, -0.7, 1e-9, 1234.567]),
                   st.floats(-1e3, 1e3))


@settings(max_examples=60, deadline=None)
@given(data=st.data(), nodes=st.integers(1, 4), elements=st.integers(1, 5))
def test_the_rows_of_the_loop_bit_for_bit(data, nodes, elements) -> None:
    draw = data.draw
    is_mass = [True] + [draw(st.booleans()) for _ in range(nodes - 1)]
    mass = [draw(st.floats(0.1, 10.0)) if m else 0.0 for m in is_mass]
    f = [draw(values) for _ in range(nodes)]
    ea, eb, kernels, spring, pinned, q0, q_rate = [], [], [], [], [], [], []
    for _ in range(elements):
        a = draw(st.integers(-1, nodes - 1))
        b = draw(st.integers(0, nodes - 1).filter(lambda b, a=a: b != a))
        kind = draw(st.sampled_from(["spring", "dashpot"]))
        ea.append(a), eb.append(b), spring.append(kind == "spring")
        kernels.append(draw(st.sampled_from(LAWS[kind])).kernel)
        pinned.append(draw(st.one_of(st.none(), values)))
        q0.append(draw(values))
        q_rate.append(0.0 if kind == "spring" else draw(st.sampled_from([0.0, 1e-20, -3e-21])))
    eps = draw(st.sampled_from([1e-20, 5e-20, 0.37]))  # (exact for any step)
    args = (is_mass, mass, f, ea, eb, pinned, q0, q_rate, kernels, spring, eps)
    evaluate = limit_rows(*args)
    for _ in range(3):  # one evaluate, several iterates: nothing carried between calls
        u = [draw(values) for _ in range(nodes + elements)]
        got, want = evaluate(u), loop_rows(*args, u)
        assert _bits(got) == _bits(want)
