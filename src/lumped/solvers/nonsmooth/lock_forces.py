r"""The forces of locked and stuck elements at a given state, from the accelerations.

At a state ``(x, v)`` of a scene, an element whose law leaves its force free there (a
taut string on its lock, ``q = L`` with any ``F >= k L``; a stuck dashpot, rate ``0``
with ``|F| <= tau``: ``dR/dF = 0`` on the law's kernel) keeps its relative motion only
if the forces make the relative *acceleration* across it vanish. With the forces of all
other elements fixed (their laws give them at ``(x, v)``), the balances

.. math::

    m_i a_i = f_i(t) + \sum_{a_e = i} F_e - \sum_{b_e = i} F_e \quad (\text{masses};
    \ 0 = \dots \text{ at a junction}), \qquad a_{b_e} - a_{a_e} + o_e''(t) = 0 \ (e \in K)

are linear in the accelerations ``a`` and the forces ``F_K`` of the force-free set
``K`` (ground has ``a = 0``; an element on a moving support, :mod:`lumped.scene.supports`,
has ``o_e'' = +-a_s(t)``, ``+`` at its end ``b``, for a locked spring's ``q''`` as for a
stuck dashpot's ``q'``: its lock moves with the support; else ``o_e'' = 0``). Their
solution gives the forces these elements carry at that instant, the right limit
``h -> 0`` of an implicit step, without dividing by ``h``.

A backward-Euler step of size ``h`` reads the same forces from ``m (v_1 - v_0) / h``, and
on a position lock ``v_1`` is fixed only to ``ulp(x) / h`` (the rounding of
``q = x + h v``): after a short remainder of a step across an impact those forces are off
by ``m ulp(x) / h^2`` (:mod:`lumped.solvers.bdf.impact_step` uses this module there).

Several force-free elements in parallel leave the split free: the least-squares solution
of minimum weighted norm is taken, the change from the given forces, with a stuck
dashpot's change weighted ``1000`` times a lock's (the dashpot keeps its force, the rigid
element carries the rest). A solution that leaves an element's admissible set (a string
pushed below ``k L``: it goes slack; a dashpot beyond its yield force: it slips) puts
that element on the boundary of its set, read from its kernel by bisection, and solves
again without it.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np

from ...scene import Mass, Scene
from ...scene.supports import support_accelerations
from ..newton.scalar_root import scalar_root
from .impacts import lock_state

__all__ = ["forces_from_accelerations", "forces_with_held", "taut_on_supports"]

#: Weight of a dashpot's force change against a lock's in the minimum-norm split.
_DASHPOT_WEIGHT = 1e3


def _admissible(kernel, q: float, F: float, tol: float) -> bool:
    R, _, RF = kernel(q, F)
    return RF == 0.0 and abs(R) <= tol


def _boundary(kernel, q: float, good: float, bad: float, tol: float) -> float:
    """The admissible force nearest ``bad`` between ``good`` (admissible) and ``bad``."""
    for _ in range(200):
        mid = 0.5 * (good + bad)
        if mid in (good, bad):
            break
        if _admissible(kernel, q, mid, tol):
            good = mid
        else:
            bad = mid
    return good


def forces_from_accelerations(scene: Scene, t: float, x: Sequence[float],
                              v: Sequence[float], F: Sequence[float],
                              free: Sequence[int]) -> list[float] | None:
    """Forces at ``(t, x, v)`` with the elements ``free`` (force-free there: ``dR/dF = 0``
    at ``(q, F)``) holding their relative motion, the others' forces kept from ``F``.

    Parameters
    ----------
    scene : Scene
    t : float
        Time (the forcing is read there).
    x, v : sequence of float
        Node displacements and velocities (the rates across ``free`` are taken as they are).
    F : sequence of float
        Element forces: the others' forces (kept), the start of the split of ``free``.
    free : sequence of int
        Indices of the force-free elements (see the module notes).

    Returns
    -------
    list of float or None
        All element forces; ``None`` when the balances have no solution (the least-squares
        residual above ``1e-9`` of the forces' scale), e.g. no motion holds every lock.
    """
    N = len(scene.nodes)
    ea, eb = scene.elem_a, scene.elem_b
    q = scene.elongations(x, v)
    out = [float(f) for f in F]
    kernels = [el.law.kernel for el in scene.elements]
    masses = [nd.m if isinstance(nd, Mass) else 0.0 for nd in scene.nodes]
    K = list(free)
    moving = (support_accelerations(scene, t) if getattr(scene, "support_frame", None)
              is not None else None)  # +-a_s: a lock on a moving support moves with it
    scale = 1.0 + max((abs(f) for f in out), default=0.0) \
        + max((abs(f) for f in scene.external_forces(t)), default=0.0)
    tol = [1e-12 * (abs(qe) + abs(fe)) + 1e-300 for qe, fe in zip(q, out, strict=True)]
    for _ in range(len(K) + 1):
        # with the forces of K at their given values: the balances' rest, per node
        rhs = np.array(scene.net_forces(t, out), dtype=float)
        n = N + len(K)
        A = np.zeros((n, n))
        A[np.arange(N), np.arange(N)] = masses
        rhs_full = np.zeros(n)
        rhs_full[:N] = rhs  # m a - B_K^T dF_K = the net forces at the given F
        w = np.ones(n)
        for c, e in enumerate(K):
            col = N + c
            if ea[e] >= 0:
                A[ea[e], col] = -1.0
                A[col, ea[e]] = -1.0
            if eb[e] >= 0:
                A[eb[e], col] = 1.0
                A[col, eb[e]] = 1.0
            if scene.elements[e].kind != "spring":
                w[col] = _DASHPOT_WEIGHT
            if moving is not None:
                rhs_full[col] = -moving[e]
        y, *_ = np.linalg.lstsq(A / w, rhs_full, rcond=None)
        z = y / w
        if np.abs(A @ z - rhs_full).max() > 1e-9 * scale:
            return None
        trial = list(out)
        for c, e in enumerate(K):
            trial[e] = out[e] + float(z[N + c])
        leaving = [e for e in K if not _admissible(kernels[e], q[e], trial[e], tol[e])]
        if not leaving:
            return trial
        for e in leaving:  # on the boundary of its set, off the balance's unknowns
            out[e] = _boundary(kernels[e], q[e], out[e], trial[e], tol[e])
        K = [e for e in K if e not in leaving]
        if not K:
            return out
    return out


def taut_on_supports(scene: Scene, t: float, x: Sequence[float], v: Sequence[float],
                     F: Sequence[float]) -> list[float]:
    """The forces ``F`` at ``(t, x, v)`` with those of the spring-like elements on a
    moving support (:mod:`lumped.scene.supports`; ``scene`` the view of a
    :class:`~lumped.scene.supports.SupportFrame`, its clock at ``t``) that sit on a
    position lock at the rate ``q' = 0`` taken from the balance of accelerations
    (:func:`forces_from_accelerations`: the lock moves with the support, ``q'' = 0``).

    The limit system of the initial state reads a lock's elongation at ``eps^2 a`` and
    leaves such a force anywhere on the lock (the string's ``k L``, its kink); a string
    the load keeps taut then carries the load and the support's ``m a_s``. An element
    whose balance would push it off the lock keeps the boundary of its set. Any other
    scene, or none locked: ``F`` unchanged."""
    frame = getattr(scene, "support_frame", None)
    if frame is None:
        return list(F)
    q = scene.elongations(x, v)
    rates = frame.rates_now() or [0.0] * len(F)
    ends = {end.element for end in frame.source.support_ends}
    free = []
    for e in sorted(ends):
        el = scene.elements[e]
        if el.kind != "spring":
            continue
        R, Rq, _ = el.law.kernel(q[e], F[e])
        rate = (v[scene.elem_b[e]] if scene.elem_b[e] >= 0 else 0.0) \
            - (v[scene.elem_a[e]] if scene.elem_a[e] >= 0 else 0.0) + rates[e]
        big = abs(F[e]) * 2.0 + 1.0  # on the lock: any force beyond the kink holds it
        if R == 0.0 and abs(rate) <= 1e-12 * (1.0 + max(map(abs, v), default=0.0)) \
                and lock_state(el.law, q[e], big):
            free.append(e)
    if not free:
        return list(F)
    got = forces_from_accelerations(scene, t, x, v, F, free)
    return list(F) if got is None else got


def forces_with_held(scene: Scene, t: float, x: Sequence[float], v: Sequence[float],
                     F: Sequence[float], held: Sequence[int],
                     q_before: Sequence[float] | None = None) -> list[float] | None:
    r"""The forces at ``(x, v)`` with the elements ``held`` keeping their relative motion.

    Each dashpot not in ``held`` whose law fixes its force (``dR/dF != 0`` at ``(q,
    F_e)``) takes the force its law gives at its rate ``q`` (a scalar root from ``F_e``;
    with ``q_before``, only where its rate differs from ``q_before[e]``: elsewhere ``F_e``
    is already the law's). Where its law leaves the force free at the new rate (a
    dashpot stopped by the lock: Bingham, Herschel-Bulkley at ``q = 0``, any ``|F| <=
    tau``) it takes the force of that rest set nearest ``F_e``, its boundary: a slipping
    dashpot stops at its yield force, ``tau sgn(F_e)`` (the root alone lies anywhere in
    the set: ``-0.33`` for a Herschel-Bulkley ``n = 3`` dashpot stopped from ``F_e =
    0.67 > tau = 0.34``, issue 29). Then ``held`` and every element whose law leaves its
    force free (``dR/dF = 0``: a stuck dashpot, another taut lock) take the forces of the
    balance of accelerations (:func:`forces_from_accelerations`), which keeps a dashpot's
    force where it can.

    Returns
    -------
    list of float or None
        The forces, or ``None`` when a dashpot's root fails or the balance has no finite
        solution.
    """
    q = scene.elongations(x, v)
    out = list(F)
    free = list(held)
    for e, el in enumerate(scene.elements):
        if e in held:
            continue
        kernel = el.law.kernel
        if (el.kind == "dashpot" and (q_before is None or q[e] != q_before[e])
                and kernel(q[e], out[e])[2] != 0.0):
            try:
                root, pinned = scalar_root(kernel, q[e], out[e])
            except ValueError:
                return None
            tol = 1e-12 * (abs(q[e]) + abs(root)) + 1e-300
            out[e] = root if pinned or not _admissible(kernel, q[e], root, tol) else \
                _boundary(kernel, q[e], root, out[e], tol)
        if kernel(q[e], out[e])[2] == 0.0:
            free.append(e)
    got = forces_from_accelerations(scene, t, x, v, out, free)
    if got is None or not all(map(math.isfinite, got)):
        return None
    return got

