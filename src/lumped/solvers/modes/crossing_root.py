r"""The first guard crossing on a ``radau5`` step's collocation polynomial, one algorithm
for both loops: :func:`first_root_py` (the pure-Python loop, the laws' Python guards) and
:func:`first_root` (compiled, the generated guard kernels), with the same operations.

The guards of the watched elements are sampled at ``s = k / 8``
(:data:`lumped.solvers.radau.tableau.SAMPLES`) on the polynomial through the element's ``(q,
F)`` at the nodes ``s = 0, c_1, c_2, 1``; at the first sample where a guard, shifted by
its round-off tolerance (:func:`lumped.solvers.modes.guards.guard_tolerance`), is negative, the
smallest such guard is followed back to the previous sample and its root is found by the
Illinois variant of regula falsi: the secant through the bracket, and the value kept at
an end that stayed twice in a row halved, which gives superlinear convergence without
the one-sided stall of plain regula falsi. It stops when the bracket is below
``4 eps + 1e-15 s`` or a guard value is exactly zero.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import numpy as np

from ...codegen.jit import njit
from ..radau.step_jit import element_nodes
from ..radau.tableau import SAMPLES, C

__all__ = ["collocation_at", "collocation_at_py", "first_root", "first_root_py", "illinois"]

_C0, _C1, _C2 = C
_D1 = _C0 * (_C0 - _C1) * (_C0 - _C2)
_D2 = _C1 * (_C1 - _C0) * (_C1 - _C2)
_D3 = _C2 * (_C2 - _C0) * (_C2 - _C1)
_SAMPLES = np.array(SAMPLES)
_TOL = 64.0 * 2.220446049250313e-16
_MAX_ITERS = 200


@njit(cache=True)
def collocation_at(s, y0, y1, y2, y3):
    """The polynomial through ``y0..y3`` at the nodes ``0, c_1, c_2, 1``, at ``s``."""
    l1 = s * (s - _C1) * (s - _C2) / _D1
    l2 = s * (s - _C0) * (s - _C2) / _D2
    l3 = s * (s - _C0) * (s - _C1) / _D3
    return y0 + (l1 * (y1 - y0) + l2 * (y2 - y0) + l3 * (y3 - y0))


#: :func:`collocation_at` uncompiled, for the Python loop: the same numbers bit for bit
#: (no fused multiply-add in the compiled one), and a first run of a structure in the
#: Python loop compiles nothing for its events (issue 27)
collocation_at_py = getattr(collocation_at, "py_func", collocation_at)


def illinois(g: Callable[[float], float], a: float, b: float, ga: float, gb: float
             ) -> float:
    """A root of ``g`` in ``[a, b]`` with ``ga = g(a) > 0 > gb = g(b)`` (see the module
    notes); the compiled twin is inlined in :func:`first_root`."""
    side = 0
    for _ in range(_MAX_ITERS):
        if b - a <= 4.0 * 2.220446049250313e-16 + 1e-15 * b:
            break
        c = b - gb * (b - a) / (gb - ga)
        if not (a < c < b):
            c = 0.5 * (a + b)
        gc = g(c)
        if gc == 0.0:
            return c
        if gc > 0.0:
            a, ga = c, gc
            if side == 1:
                gb *= 0.5
            side = 1
        else:
            b, gb = c, gc
            if side == -1:
                ga *= 0.5
            side = -1
    return 0.5 * (a + b)


def first_root_py(nodes: Sequence[tuple[Sequence[float], Sequence[float]]],
                  guard_fns: Sequence[Callable]) -> tuple[float, tuple[int, int]] | None:
    """``(s, (w, j))``: the first crossing of guard ``j`` of watched element ``w`` on the
    step (``nodes[w]`` its ``(q, F)`` at ``s = 0, c_1, c_2, 1``, ``guard_fns[w]`` its
    branch's guards), or ``None``."""
    prev = 0.0
    for s in SAMPLES:
        best, which = np.inf, (0, 0)
        for w, ((q0, q1, q2, q3), (f0, f1, f2, f3)) in enumerate(nodes):
            qs = collocation_at_py(s, q0, q1, q2, q3)
            Fs = collocation_at_py(s, f0, f1, f2, f3)
            tol = _TOL * (1.0 + abs(qs) + abs(Fs))
            for j, g in enumerate(guard_fns[w](qs, Fs)):
                if g + tol < best:
                    best, which = g + tol, (w, j)
        if best < 0.0:
            w, j = which
            (q0, q1, q2, q3), (f0, f1, f2, f3) = nodes[w]

            def g(z: float, w=w, j=j, q=(q0, q1, q2, q3), f=(f0, f1, f2, f3)) -> float:
                return guard_fns[w](collocation_at_py(z, *q), collocation_at_py(z, *f))[j]

            g0 = g(prev)
            if not g0 > 0.0:
                return prev, which
            return illinois(g, prev, s, g0, g(s)), which
        prev = s
    return None


@njit(cache=True)
def _guard(branch_guards, lawc, e, mode, j, s, qw, Fw, gbuf) -> float:
    branch_guards(e, mode, collocation_at(s, qw[0], qw[1], qw[2], qw[3]),
                  collocation_at(s, Fw[0], Fw[1], Fw[2], Fw[3]), gbuf, lawc)
    return gbuf[j]


@njit(cache=True)
def first_root(branch_guards, lawc, ea, eb, spring, modes, watched, A, h, x_n, v_n, F_n, U, N, n,
               qn, Fn, gbuf, which) -> float:
    """:func:`first_root_py` compiled: the root ``s`` (``which[0], which[1]`` = ``w, j``),
    or ``-1.0`` when no guard is negative at a sample."""
    nw = watched.shape[0]
    for w in range(nw):
        element_nodes(ea, eb, spring, A, h, x_n, v_n, F_n, U, N, n, watched[w], qn[w], Fn[w])
    prev = 0.0
    for si in range(_SAMPLES.shape[0]):
        s = _SAMPLES[si]
        best = np.inf
        bw = 0
        bj = 0
        for w in range(nw):
            e = watched[w]
            qs = collocation_at(s, qn[w, 0], qn[w, 1], qn[w, 2], qn[w, 3])
            Fs = collocation_at(s, Fn[w, 0], Fn[w, 1], Fn[w, 2], Fn[w, 3])
            tol = _TOL * (1.0 + abs(qs) + abs(Fs))
            count = branch_guards(e, modes[e], qs, Fs, gbuf, lawc)
            for j in range(count):
                if gbuf[j] + tol < best:
                    best = gbuf[j] + tol
                    bw = w
                    bj = j
        if best < 0.0:
            which[0] = bw
            which[1] = bj
            bj = which[1]  # (an int64: a literal 0 would compile a second _guard)
            e = watched[bw]
            qw, Fw = qn[bw], Fn[bw]
            a = prev
            ga = _guard(branch_guards, lawc, e, modes[e], bj, a, qw, Fw, gbuf)
            if not ga > 0.0:
                return a
            b = s
            gb = _guard(branch_guards, lawc, e, modes[e], bj, b, qw, Fw, gbuf)
            side = 0
            for _ in range(_MAX_ITERS):
                if b - a <= 4.0 * 2.220446049250313e-16 + 1e-15 * b:
                    break
                c = b - gb * (b - a) / (gb - ga)
                if not (a < c < b):
                    c = 0.5 * (a + b)
                gc = _guard(branch_guards, lawc, e, modes[e], bj, c, qw, Fw, gbuf)
                if gc == 0.0:
                    return c
                if gc > 0.0:
                    a = c
                    ga = gc
                    if side == 1:
                        gb *= 0.5
                    side = 1
                else:
                    b = c
                    gb = gc
                    if side == -1:
                        ga *= 0.5
                    side = -1
            return 0.5 * (a + b)
        prev = s
    return -1.0
