r"""The probe step of :mod:`lumped.solvers.modes.mode_guess` compiled with numba.

:func:`probe_modes` is :func:`lumped.solvers.modes.mode_guess.try_modes`'s inner part (one probe
size): for each candidate mode in turn, the held-mode probe step by Newton's method
(:func:`~lumped.solvers.modes.mode_guess._probe`, with its Gaussian elimination
:func:`~lumped.solvers.modes.mode_guess._solve`) and the branch read at the result, operation
for operation (the numbers agree bit for bit; the Python functions are the readable
reference and the test compares the two on probes from real scenes). The scene's
kernels come in as the addresses of its generated ``branch_law``, ``active_branch`` and
``branch_guards`` (:mod:`lumped.codegen.jit`), so the code is compiled once for every
scene and cached on disk.
"""

from __future__ import annotations

import math

import numpy as np

from ...codegen.function_types import branch_type, function_at, guards_type, law_type
from ...codegen.jit import njit, numba_enabled
from ...codegen.templates import GUARD_ROOM
from .mode_guess import REFUSED, UNDECIDED
from .on_demand import compiled_once

__all__ = ["probe_modes", "compiled_probe_modes", "CONFIRMED", "UNDECIDED",
           "REFUSED"]

_MAX_ITERS = 30
#: :func:`probe_modes`'s answers besides a candidate's index: no candidate confirmed,
#: one read as the current mode (undecided), or none of either.
CONFIRMED = 0  # (and above: the index of the confirmed candidate)


def probe_modes(law_addr, branch_addr, guards_addr, lawc, masses, ea, eb, spring, cands, current,
                f, x, v, F, h_p, out, wm, locks):
    """The first of the candidate modes (rows of ``cands``) that the full laws confirm
    after the probe step of size ``h_p`` (see :func:`lumped.solvers.modes.mode_guess.try_modes`):
    its index, with ``v_p`` and ``F_p`` in ``out[:N]`` and ``out[N:N + E]``; else
    :data:`UNDECIDED` when one candidate's result reads as ``current`` (an empty array:
    no current mode), or :data:`REFUSED`. ``lawc``: the scene's law constants; ``locks``:
    each candidate's position locks, held on the velocity level
    (:func:`~lumped.solvers.modes.mode_guess.lock_rows`). ``wm``
    is work space, at least ``(n + 4, n)`` with ``n = N + E`` and room in its last row
    for a branch's guards (:func:`probe_workspace`). The branch read is
    :func:`~lumped.solvers.modes.mode_guess.read_branches`: the held branch where all its
    stage guards are positive, else the law's."""
    branch_law = _law_at(law_addr)
    active_branch = _branch_at(branch_addr)
    branch_guards = _guards_at(guards_addr)
    N = masses.shape[0]
    E = ea.shape[0]
    n = N + E
    J = wm[:n, :n]
    G = wm[n, :n]
    u = wm[n + 1, :n]
    q = wm[n + 2, :E]
    gbuf = wm[n + 3]
    undecided = False
    for c in range(cands.shape[0]):
        modes = cands[c]
        ok = _probe(branch_law, lawc, masses, ea, eb, spring, modes, f, x, v, F, h_p, J, G, u, q,
                    locks[c])
        if not ok:
            continue
        same = True
        cur = current.shape[0] > 0
        for e in range(E):
            b = modes[e]
            count = branch_guards(e, b, q[e], u[N + e], gbuf, lawc)
            for j in range(count):
                if not gbuf[j] > 0.0:
                    b = active_branch(e, q[e], u[N + e], lawc)
                    break
            if b != modes[e]:
                same = False
            if cur and b != current[e]:
                cur = False
        if same:
            for k in range(n):
                out[k] = u[k]
            return c
        undecided = undecided or cur
    return UNDECIDED if undecided else REFUSED


@njit(cache=True)
def _probe(branch_law, lawc, masses, ea, eb, spring, modes, f, x, v, F, h_p, J, G, u, q,
           lock) -> bool:
    """:func:`lumped.solvers.modes.mode_guess._probe` (``velocity_locks``: ``lock[e]`` a
    held position lock's value, NaN where none) into ``u`` (``v_p, F_p``) and ``q``;
    whether it converged."""
    N = masses.shape[0]
    E = ea.shape[0]
    n = N + E
    for i in range(N):
        u[i] = v[i]
    for e in range(E):
        u[N + e] = F[e]
    for _ in range(_MAX_ITERS):
        for r in range(n):
            G[r] = 0.0
            for c in range(n):
                J[r, c] = 0.0
        for i in range(N):
            cm = masses[i] / h_p
            G[i] = cm * (u[i] - v[i]) - f[i]
            J[i, i] = cm
        for e in range(E):
            a = ea[e]
            b = eb[e]
            Fe = u[N + e]
            if a >= 0:
                G[a] -= Fe
                J[a, N + e] -= 1.0
            if b >= 0:
                G[b] += Fe
                J[b, N + e] += 1.0
            if spring[e]:
                qe = _elongation(x, u, a, b, h_p, lock[e])
                dq = h_p
            else:
                qe = (u[b] if b >= 0 else 0.0) - (u[a] if a >= 0 else 0.0)
                dq = 1.0
            R, Rq, RF = branch_law(e, modes[e], qe, Fe, lawc)
            G[N + e] = R
            if b >= 0:
                J[N + e, b] += Rq * dq
            if a >= 0:
                J[N + e, a] -= Rq * dq
            J[N + e, N + e] = RF
        if not _solve(J, G, n):  # the step, in G
            return False
        done = True
        for k in range(n):
            u[k] -= G[k]
            if not abs(G[k]) <= 1e-14 * (1.0 + abs(u[k])):
                done = False
        if done:
            for e in range(E):
                a = ea[e]
                b = eb[e]
                if spring[e]:
                    q[e] = _elongation(x, u, a, b, h_p, lock[e])
                else:
                    q[e] = (u[b] if b >= 0 else 0.0) - (u[a] if a >= 0 else 0.0)
            return True
    return False


@njit(cache=True)
def _elongation(x, u, a, b, h_p, lock) -> float:
    """:func:`lumped.solvers.modes.mode_guess._elongation` (``lock`` NaN: none)."""
    if lock == lock:
        return lock + h_p * ((u[b] if b >= 0 else 0.0) - (u[a] if a >= 0 else 0.0))
    return ((x[b] + h_p * u[b]) if b >= 0 else 0.0) - ((x[a] + h_p * u[a]) if a >= 0 else 0.0)


@njit(cache=True)
def _solve(J, G, n) -> bool:
    """:func:`lumped.solvers.modes.mode_guess._solve`: ``J^-1 G`` into ``G`` (``J`` consumed);
    False for a zero pivot or a non-finite result."""
    for c in range(n):
        p = c
        big = abs(J[c, c])
        for r in range(c + 1, n):
            if abs(J[r, c]) > big:
                p = r
                big = abs(J[r, c])
        if not (0.0 < big and big < math.inf):
            return False
        if p != c:
            for k in range(n):
                J[c, k], J[p, k] = J[p, k], J[c, k]
            G[c], G[p] = G[p], G[c]
        piv = J[c, c]
        for r in range(c + 1, n):
            fac = J[r, c] / piv
            if fac != 0.0:
                for k in range(c, n):
                    J[r, k] -= fac * J[c, k]
                G[r] -= fac * G[c]
    for c in range(n - 1, -1, -1):
        s = G[c]
        for k in range(c + 1, n):
            s -= J[c, k] * G[k]
        G[c] = s / J[c, c]
    for c in range(n):
        if not math.isfinite(G[c]):
            return False
    return True


if numba_enabled():
    _law_at = function_at(law_type())
    _branch_at = function_at(branch_type())
    _guards_at = function_at(guards_type())

_COMPILED: list = []


def compiled_probe_modes(compile: bool = True):
    """:func:`probe_modes` compiled once for every scene (numba's disk cache after the
    first time on a machine), or ``None`` without numba; ``compile=False``: only if
    numba's disk cache holds it (:func:`lumped.solvers.modes.on_demand.compiled_once`)."""
    return compiled_once(_COMPILED, probe_modes, _signature, compile)


def _signature():
    from numba import types as T_

    f8, i8 = T_.float64, T_.int64
    v, m = f8[::1], f8[:, ::1]
    iv = i8[::1]
    return i8(i8, i8, i8, v, v, iv, iv, T_.boolean[::1], i8[:, ::1], iv, v, v, v, v, f8, v, m, m)


def probe_workspace(N: int, E: int) -> tuple[np.ndarray, np.ndarray]:
    """``(out, wm)`` of :func:`probe_modes` for ``N`` nodes and ``E`` elements (the last
    row of ``wm`` holds a branch's guards: room for
    :data:`~lumped.codegen.templates.GUARD_ROOM`, as the compiled loop's)."""
    n = N + E
    return np.zeros(n), np.zeros((n + 4, max(n, GUARD_ROOM)))
