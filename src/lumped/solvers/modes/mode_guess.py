r"""A cheap first try of the mode after an event: the vanishing implicit step of
:func:`lumped.solvers.modes.choice.select_modes` on a *guessed* mode, checked against the full
laws.

:func:`select_modes` solves one backward-Euler step of size ``h_p`` of the full,
nonsmooth laws by the semismooth Newton of the fixed-step methods and reads each
element's branch at the result. When only one element changes branch (the common event:
a dashpot sticks, slips or reverses), the same step on the guessed mode is a smooth
system in the unknowns ``u = (v, F)``,

.. math::

    \frac{m_i}{h_p} (v_i - v_i^0) - \Bigl(f_i(t + h_p) + \sum_{a_e = i} F_e
        - \sum_{b_e = i} F_e\Bigr) = 0, \qquad R_e^{(b_e)}(q_e, F_e) = 0,

with ``q_e`` the elongation of ``x + h_p v`` (springs) or the rate of ``v`` (dashpots),
solved by a plain Newton iteration on lists (Gaussian elimination with partial pivoting).
The guess is accepted only when every element's branch at the result,
``law_branches(...).branch(q_e, F_e)`` or inside the guessed branch by all its stage guards
(:func:`read_branches`), gives the guessed branch: the result then solves
the full laws' step too, and for laws without folds (the elements that
:func:`~lumped.solvers.implicit.branch_check.known_monotone` accepts; a scene with other laws
always takes the full search) that step has one solution, so the full search would read
the same mode. Otherwise (no convergence, a singular matrix, another branch read) the
caller runs the full search.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...scene import Mass, Scene
from ...scene.supports import support_time, support_time_restored

__all__ = ["lock_drifts", "lock_rows", "probe_state", "read_branches",
           "try_modes", "UNDECIDED", "REFUSED"]

#: The probe's verdicts besides a mode: no mode decided yet, or the guess refused
#: (shared with its compiled twin, :mod:`lumped.solvers.modes.mode_guess_jit`).
UNDECIDED, REFUSED = -2, -1

_MAX_ITERS = 30
_SQRT_EPS = 1.4901161193847656e-08


def try_modes(scene: Scene, branches: Sequence, candidates: Sequence[Sequence[int]],
              t: float, x: list[float], v: list[float], F: list[float], h_p: float,
              current: Sequence[int] | None = None, longer: int = 1, fast=None,
              min_norm: bool = False, used: list[float] | None = None
              ) -> tuple[list[int], list[float], list[float]] | None:
    """The first of ``candidates`` (modes) that the full laws confirm after the probe step
    of size ``h_p`` from ``t`` (see the module notes): ``(modes, v_p, F_p)``, or ``None``.

    With ``current`` (a guard event) a result that reads as ``current`` is undecided, as
    in :func:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode`: if no candidate is
    confirmed and one is undecided, the probe is tried ``1000`` times longer, up to
    ``longer`` sizes in all.

    With ``fast`` (the run's :class:`~lumped.solvers.eventdriven.fast.CompiledLoop`) the
    probes and the branch reads run compiled
    (:func:`lumped.solvers.modes.mode_guess_jit.probe_modes`, the same numbers); the loop below
    is the reference. With ``min_norm`` (Python only) a singular step matrix (locks in
    parallel, whose split is free) is solved by the minimum-norm correction instead of
    refusing the candidate. On a scene with moving supports the laws are read at
    ``t + h_p`` and the clock is set back to ``t`` on return. ``used`` (a list) gets the
    size of the probe that decided."""
    if fast is not None and not fast.can_probe():  # (not compiled yet: the reference)
        fast = None
    rows = lock_rows(scene, branches, candidates, x)  # (x is the same at every size)
    with support_time_restored(scene, t):  # (moving supports: the laws at t + h_p)
        for _ in range(longer):
            support_time(scene, t + h_p)
            f = scene.external_forces(t + h_p)
            if fast is not None:
                k, out = fast.probe_modes(candidates, current, f, x, v, F, h_p, rows)
                if k >= 0:
                    N = len(x)
                    if used is not None:
                        used.append(h_p)
                    return list(candidates[k]), out[:N].tolist(), out[N:].tolist()
                if k == REFUSED:
                    return None
                h_p *= 1000.0
                continue
            undecided = False
            for modes, row in zip(candidates, rows, strict=True):
                got = _probe(scene, branches, modes, f, x, v, F, h_p, min_norm,
                             [None if lock != lock else float(lock) for lock in row])
                if got is None:
                    continue
                v_p, F_p, q = got
                read = read_branches(branches, modes, q, F_p)
                if read == list(modes):
                    if used is not None:
                        used.append(h_p)
                    return list(modes), v_p, F_p
                undecided = undecided or (current is not None and read == list(current))
            if not undecided:
                return None
            h_p *= 1000.0
        return None


def lock_rows(scene: Scene, branches: Sequence, candidates: Sequence[Sequence[int]],
              x: Sequence[float]) -> np.ndarray:
    """Each candidate's position locks held on the velocity level (:func:`_elongation`):
    ``[c, e]`` the value a spring ``e`` is held at on the branch ``candidates[c][e]`` (a
    taut string's length ``L``) where its elongation at ``x`` is ``L`` to
    ``sqrt(eps) max(|L|, |x_a|, |x_b|)`` (:func:`_at_its_lock`); NaN elsewhere, where the
    probe holds it in positions' form (a guess that puts a string far from its length
    taut)."""
    out = np.full((len(candidates), len(scene.elements)), np.nan)
    for e, el in enumerate(scene.elements):
        if el.kind != "spring":
            continue
        for c, modes in enumerate(candidates):
            lock = _lock_value(branches[e], modes[e])
            if lock is not None and _at_its_lock(scene, e, x, lock):
                out[c, e] = lock
    return out


def _at_its_lock(scene: Scene, e: int, x: Sequence[float], lock: float) -> bool:
    """Whether the spring ``e``'s elongation at ``x`` is its lock ``lock`` (a taut
    string's length ``L``) to ``sqrt(eps) max(|L|, |x_a|, |x_b|)``: the positions'
    rounding, and the drift a lock held on the velocity level by the steps leaves
    (``1.6e-14`` after 0.25 s taut in seed 25039's scene)."""
    xa, xb = _ends(scene, e, x)
    return abs((xb - xa) - lock) <= _SQRT_EPS * max(abs(lock), abs(xa), abs(xb))


def _ends(scene: Scene, e: int, x: Sequence[float]) -> tuple[float, float]:
    """The positions ``(x_a, x_b)`` of element ``e``'s ends (ground at 0)."""
    a, b = scene.elem_a[e], scene.elem_b[e]
    return (x[a] if a >= 0 else 0.0), (x[b] if b >= 0 else 0.0)


def lock_drifts(scene: Scene, branches: Sequence, x: Sequence[float]) -> list[float]:
    """Per element, ``L - (x_b - x_a)``: how far the positions ``x`` have drifted off the
    lock ``L`` of a spring at its lock (:func:`_at_its_lock`, a string at its length, taut
    or not); ``0.0`` for every other element (and on a moving support, whose branches
    carry no ``lock_value``).

    A law read at ``q + drift`` holds such a spring on the velocity level,
    ``L + h_p (v_b - v_a)``, as the stage solve and the guesses' probe do
    (:func:`_elongation`): the full laws' probe of
    :func:`~lumped.solvers.modes.choice.select_modes` read a taut string stretched
    ``1.4e-14`` past its length in positions' form, which asked a force of ``m
    1.4e-14 / h_p^2`` (2178 where it carried 0.57, on a probe of ``1e-9`` s) and read
    two Coulomb dashpots in parallel beside it slipping on where they reverse: a guard
    every ``1.5e-8`` s, each crossing a full mode choice of 0.3 s (the property of both
    loops, seed 25171)."""
    out = [0.0] * len(scene.elements)
    for e, el in enumerate(scene.elements):
        if el.kind != "spring":
            continue
        lb = branches[e]
        for j in range(lb.count):
            lock = _lock_value(lb, j)
            if lock is not None and _at_its_lock(scene, e, x, lock):
                xa, xb = _ends(scene, e, x)
                out[e] = lock - (xb - xa)
                break
    return out


def _lock_value(lb, branch: int) -> float | None:
    """The ``q`` the branch ``branch`` of ``lb`` locks (its stage kernel's
    ``lock_value``), or ``None``."""
    info = lb.info[branch]
    return info.lock_value if info.locks else None


def read_branches(branches: Sequence, modes: Sequence[int], q: Sequence[float],
                  F: Sequence[float]) -> list[int]:
    """Each element's branch at the probe's result ``(q_e, F_e)``: the held branch
    ``modes[e]`` where all its stage guards
    (:meth:`~lumped.codegen.branches.LawBranches.stage_guards_for`) are positive, else
    ``law_branches(...).branch(q_e, F_e)``.

    The two differ only where a stage guard reads the rate ``w(q)`` and the law's own
    read takes the force (a steep branch solved in its inverse form, or a branch flat at
    its end, :meth:`~lumped.codegen.branches.LawBranches.stage_guards_for`): Herschel-Bulkley
    ``n = 0.3`` (``tau = 0.316``) starting to slip at a rate of ``2e-9`` has the force
    ``tau + 1e-29``, which rounds to ``tau``, where the law reads its stuck branch. The
    right guess (slipping) was refused at the start, and the full search then took a
    spurious root on the other slip branch's odd continuation (``F = -tau`` at a positive
    rate): every step crossed a guard at once, 8 kept modes and 4 bridges, a stop at
    ``1.5e-8`` s (issue 29, the property of both loops, seed 22228)."""
    out = []
    for e, (lb, b) in enumerate(zip(branches, modes, strict=True)):
        if all(g > 0.0 for g in lb.stage_guards_for(b)(q[e], F[e])):
            out.append(b)
        else:
            out.append(lb.branch(q[e], F[e]))
    return out


def probe_state(scene: Scene, branches: Sequence, modes: Sequence[int], t: float,
                x: list[float], v: list[float], F: list[float], h_p: float
                ) -> tuple[list[float], list[float]] | None:
    """The probe step of size ``h_p`` from ``t`` on the mode ``modes`` (no branch read):
    ``(v_p, F_p)``, the junction velocities and forces at ``t + h_p``, or ``None``. A held
    position lock (a taut string) is held on the velocity level, as in the stage solve
    (:func:`_elongation`)."""
    with support_time_restored(scene, t):
        support_time(scene, t + h_p)
        got = _probe(scene, branches, modes, scene.external_forces(t + h_p), x, v, F, h_p,
                     locks=[_lock_value(branches[e], m) for e, m in enumerate(modes)])
    return None if got is None else (got[0], got[1])


def _probe(scene: Scene, branches: Sequence, modes: Sequence[int], f: list[float],
           x: list[float], v: list[float], F: list[float], h_p: float,
           min_norm: bool = False, locks: Sequence[float | None] | None = None):
    """The held-mode probe step by Newton's method: ``(v_p, F_p, q)`` or ``None``
    (``min_norm``: a singular matrix by the minimum-norm correction; ``locks``: each
    element's position lock held on the velocity level, :func:`_elongation`, or ``None``
    for its positions' form; none given: every element in positions' form)."""
    N, E = len(scene.nodes), len(scene.elements)
    n = N + E
    ea, eb = scene.elem_a, scene.elem_b
    kernels = [branches[e].stage_kernel_for(modes[e]) for e in range(E)]
    spring = [el.kind == "spring" for el in scene.elements]
    if locks is None:
        locks = [None] * E
    cm = [nd.m / h_p if isinstance(nd, Mass) else 0.0 for nd in scene.nodes]
    u = list(v) + list(F)
    for _ in range(_MAX_ITERS):
        vel = u[:N]
        G = [0.0] * n
        J = [[0.0] * n for _ in range(n)]
        for i in range(N):
            G[i] = cm[i] * (vel[i] - v[i]) - f[i]
            J[i][i] = cm[i]
        q = [0.0] * E
        for e in range(E):
            a, b = ea[e], eb[e]
            Fe = u[N + e]
            if a >= 0:
                G[a] -= Fe
                J[a][N + e] -= 1.0
            if b >= 0:
                G[b] += Fe
                J[b][N + e] += 1.0
            if spring[e]:
                qe = _elongation(x, vel, a, b, h_p, locks[e])
                dq = h_p
            else:
                qe = (vel[b] if b >= 0 else 0.0) - (vel[a] if a >= 0 else 0.0)
                dq = 1.0
            q[e] = qe
            R, Rq, RF = kernels[e](qe, Fe)
            G[N + e] = R
            if b >= 0:
                J[N + e][b] += Rq * dq
            if a >= 0:
                J[N + e][a] -= Rq * dq
            J[N + e][N + e] = RF
        du = _solve([row[:] for row in J], G[:]) if min_norm else _solve(J, G)
        if du is None and min_norm:
            du = np.linalg.lstsq(np.array(J), np.array(G), rcond=None)[0].tolist()
            if not all(math.isfinite(d) for d in du):
                return None
        if du is None:
            return None
        done = True
        for k in range(n):
            u[k] -= du[k]
            if not abs(du[k]) <= 1e-14 * (1.0 + abs(u[k])):
                done = False
        if done:
            vel = u[:N]
            q = [_elongation(x, vel, ea[e], eb[e], h_p, locks[e]) if spring[e]
                 else (vel[eb[e]] if eb[e] >= 0 else 0.0) - (vel[ea[e]] if ea[e] >= 0 else 0.0)
                 for e in range(E)]
            return vel, u[N:], q
    return None


def _elongation(x: list[float], vel: list[float], a: int, b: int, h_p: float,
                lock: float | None) -> float:
    """The elongation of a spring from ``a`` to ``b`` at ``t + h_p``: of ``x + h_p v``,
    or, held on a position lock at ``lock`` (a taut string), ``lock + h_p (v_b - v_a)``.

    The lock on the velocity level, as the stage solve holds it
    (:meth:`lumped.solvers.radau.stage.StageSystem.evaluate`): the positions carry their
    rounding, ``ulp(x)``, which the lock turns into rates of ``ulp(x) / h_p`` and forces
    of ``m ulp(x) / h_p^2``. A string slack by ``4.6e-17`` (below ``ulp(x)``) on a probe
    of ``4.3e-11`` s left a junction's rate ``1e-6`` off its mass's, and Newton's update
    test, cycling at round-off, refused the probe: the junction then kept the rate of a
    longer probe (``h_p a``, ``5.7e-4``) off the stage solution's, whose dense output
    overshot through a guard at once (issue 29)."""
    if lock is not None:
        return lock + h_p * ((vel[b] if b >= 0 else 0.0) - (vel[a] if a >= 0 else 0.0))
    return ((x[b] + h_p * vel[b]) if b >= 0 else 0.0) - ((x[a] + h_p * vel[a]) if a >= 0
                                                          else 0.0)


def _solve(J: list[list[float]], G: list[float]) -> list[float] | None:
    """``J^-1 G`` by Gaussian elimination with partial pivoting (``J``, ``G`` consumed);
    ``None`` for a zero pivot or a non-finite result (a nearly singular matrix gives an
    iterate that does not converge, or a result the branch check refuses)."""
    n = len(G)
    for c in range(n):
        p, big = c, abs(J[c][c])
        for r in range(c + 1, n):
            if abs(J[r][c]) > big:
                p, big = r, abs(J[r][c])
        if not 0.0 < big < math.inf:
            return None
        if p != c:
            J[c], J[p] = J[p], J[c]
            G[c], G[p] = G[p], G[c]
        piv = J[c][c]
        for r in range(c + 1, n):
            fac = J[r][c] / piv
            if fac != 0.0:
                row, top = J[r], J[c]
                for k in range(c, n):
                    row[k] -= fac * top[k]
                G[r] -= fac * G[c]
    out = [0.0] * n
    for c in range(n - 1, -1, -1):
        s = G[c]
        row = J[c]
        for k in range(c + 1, n):
            s -= row[k] * out[k]
        out[c] = s / row[c]
    return out if all(math.isfinite(o) for o in out) else None
