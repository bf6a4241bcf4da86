r"""The junctions' velocities at the time of a mode choice, not at the end of its probe.

A mode choice (:meth:`~lumped.solvers.eventdriven.mode_state.ModeState.change_mode`)
reads the mode off a probe step of length ``h_p`` and takes the probe's junction
velocities, those of ``t + h_p``. At the start that is ``1e-9`` of the run: a junction
tied to a mass at rest by stuck dashpots, beside a Herschel-Bulkley dashpot to ground
that slips from rest, took the probe's ``7.5e-11`` in row 0 while the mass stood at 0
(and that dashpot the force ``tau + 2.7e-7`` of the probe's rate). The first step
starts from that row, and its dense output reads it (issue 29).

:func:`junctions_at` solves the mode's algebraic system at ``t`` itself, with every
mass's position and velocity held: the unknowns are the junction velocities ``w_j`` and
the forces ``F_e`` of the elements with an end at a junction, the equations the
junctions' balances and those elements' laws on their held branches,

.. math::

    f_j(t) + \sum_{a_e = j} F_e - \sum_{b_e = j} F_e = 0, \qquad
    R_e^{(b_e)}(q_e, F_e) = 0,

with ``q_e`` the elongation of ``x`` (a spring; held on a position lock, the lock's
value, as in the probe's velocity form) or the rate of the velocities (a dashpot). It is
the probe's system in the limit ``h_p -> 0`` with the masses' rows dropped. Newton's
method starts from the probe's state and takes the minimum-norm correction
(:func:`~lumped.solvers.newton.min_norm.min_norm_solver`): where the system leaves a
direction free (locks in parallel, whose split is free; a junction held by springs
alone, whose velocity is of index 2 and not fixed at ``t``) the probe's value stays.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from ...scene import Mass, Scene
from ..newton.min_norm import min_norm_solver

__all__ = ["junctions_at", "rate_lock_chains"]

_MAX_ITERS = 40


def junctions_at(scene: Scene, branches: Sequence, modes: Sequence[int], t: float,
                 x: list[float], v: list[float], v_probe: list[float], F: list[float]
                 ) -> tuple[list[float], list[float]] | None:
    """The junction velocities and the forces of the elements at junctions at ``t`` on
    the mode ``modes``, the masses' ``x`` and ``v`` held (see the module notes).

    Parameters
    ----------
    scene : Scene
        The scene (its laws and forcing read at ``t``: the caller has set a moving
        support's clock there).
    branches : sequence
        The elements' law branches (``stage_kernel_for``).
    modes : sequence of int
        The branch each element is held on.
    t : float
        The time.
    x, v : list of float
        The node positions and velocities at ``t`` (the masses' are held).
    v_probe, F : list of float
        The probe's velocities and forces: the junctions' velocities and the forces start
        Newton's method there.

    Returns
    -------
    tuple of (list of float, list of float) or None
        ``(v, F)``: the velocities with the junctions' at ``t`` and the forces with those
        of the elements at junctions at ``t``; ``None`` where the scene has no junction,
        or Newton's method does not converge or leaves a balance or a law off (the caller
        keeps the probe's).
    """
    nodes, ea, eb = scene.nodes, scene.elem_a, scene.elem_b
    junction = [not isinstance(nd, Mass) for nd in nodes]
    if not any(junction):
        return None
    nodes_j = [i for i, free in enumerate(junction) if free]
    elems = [e for e in range(len(F))
             if (ea[e] >= 0 and junction[ea[e]]) or (eb[e] >= 0 and junction[eb[e]])]
    col = {i: k for k, i in enumerate(nodes_j)}
    col.update({len(nodes) + e: len(nodes_j) + k for k, e in enumerate(elems)})
    row = {i: k for k, i in enumerate(nodes_j)}
    kernels = {e: branches[e].stage_kernel_for(modes[e]) for e in elems}
    spring = {e: scene.elements[e].kind == "spring" for e in elems}
    f = scene.external_forces(t)
    vel = [w if free else vi for vi, w, free in zip(v, v_probe, junction, strict=True)]
    force = list(F)
    n = len(nodes_j) + len(elems)
    for _ in range(_MAX_ITERS):
        G, J, sizes = _system(nodes_j, elems, kernels, spring, row, col, ea, eb, f, x, vel,
                              force, n)
        du = min_norm_solver(J, rows=True)(G)
        if not all(map(math.isfinite, du)):
            return None
        done = True
        for i in nodes_j:
            vel[i] -= du[col[i]]
            done = done and abs(du[col[i]]) <= 1e-14 * (1.0 + abs(vel[i]))
        for k, e in enumerate(elems):
            force[e] -= du[len(nodes_j) + k]
            done = done and abs(du[len(nodes_j) + k]) <= 1e-14 * (1.0 + abs(force[e]))
        if done:
            G, _, sizes = _system(nodes_j, elems, kernels, spring, row, col, ea, eb, f, x,
                                  vel, force, n)
            held = all(abs(g) <= 1e-8 * (1.0 + s) for g, s in zip(G, sizes, strict=True))
            return (_on_rate_locks(scene, branches, modes, vel), force) if held \
                else None
    return None


def _on_rate_locks(scene: Scene, branches: Sequence, modes: Sequence[int],
                   vel: list[float]) -> list[float]:
    """``vel`` with every junction that dashpots on rate locks tie to a mass or ground
    given that rate exactly (:func:`rate_lock_chains`): the minimum-norm corrections leave
    it off by round-off (``-3.8e-31`` beside a mass at rest, against the slipping
    branch's guard ``q >= 0`` of a dashpot to ground at the junction: the first step
    failed down to its floor)."""
    for j, i, L in rate_lock_chains(scene, branches, modes):
        vel[j] = (vel[i] if i >= 0 else 0.0) + L
    return vel


def rate_lock_chains(scene: Scene, branches: Sequence, modes: Sequence[int]
                     ) -> list[tuple[int, int, float]]:
    """The junctions that dashpots on rate locks (``q = L``, held by ``modes``) tie to a
    mass or ground, in order from them: ``(j, i, L)``, the junction ``j`` moves at node
    ``i``'s rate (``-1``: ground) plus ``L``, ``i`` a mass, ground or a junction listed
    before. Dashpots on a moving support are left out (their rates carry the
    support's)."""
    ea, eb, nodes = scene.elem_a, scene.elem_b, scene.nodes
    on_support = {end.element for end in scene.support_ends}
    locks = []
    for e, el in enumerate(scene.elements):
        info = branches[e].info[modes[e]]
        if el.kind == "dashpot" and info.locks and info.lock_value is not None \
                and e not in on_support:
            locks.append((ea[e], eb[e], float(info.lock_value)))
    known = [isinstance(nd, Mass) for nd in nodes]
    out: list[tuple[int, int, float]] = []
    changed = True
    while changed:
        changed = False
        for a, b, L in locks:
            if (a < 0 or known[a]) and b >= 0 and not known[b]:
                out.append((b, a, L))
                known[b] = changed = True
            elif (b < 0 or known[b]) and a >= 0 and not known[a]:
                out.append((a, b, -L))
                known[a] = changed = True
    return out


def _system(nodes_j, elems, kernels, spring, row, col, ea, eb, f, x, vel, force, n):
    """The residual ``G``, its Jacobian ``J`` (in the unknowns' order: the junctions'
    velocities, then the forces of ``elems``) and each row's size (the sum of its terms'
    magnitudes) at ``(vel, force)``."""
    N = len(vel)
    nj = len(nodes_j)
    G = [0.0] * n
    J = [[0.0] * n for _ in range(n)]
    sizes = [0.0] * n
    for i in nodes_j:
        G[row[i]] = -f[i]
        sizes[row[i]] = abs(f[i])
    for k, e in enumerate(elems):
        a, b, Fe = ea[e], eb[e], force[e]
        for end, sign in ((a, -1.0), (b, 1.0)):
            if end >= 0 and end in row:
                G[row[end]] += sign * Fe
                J[row[end]][col[N + e]] += sign
                sizes[row[end]] += abs(Fe)
        if spring[e]:
            lock = getattr(kernels[e], "lock_value", None)
            qe = lock if lock is not None else (x[b] if b >= 0 else 0.0) - (
                x[a] if a >= 0 else 0.0)
        else:
            qe = (vel[b] if b >= 0 else 0.0) - (vel[a] if a >= 0 else 0.0)
        R, Rq, RF = kernels[e](qe, Fe)
        G[nj + k] = R
        sizes[nj + k] = abs(Rq * qe) + abs(RF * Fe)
        J[nj + k][col[N + e]] = RF
        if not spring[e]:
            if b >= 0 and b in row:
                J[nj + k][col[b]] += Rq
            if a >= 0 and a in row:
                J[nj + k][col[a]] -= Rq
    return G, J, sizes
