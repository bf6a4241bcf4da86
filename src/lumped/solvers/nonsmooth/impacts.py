r"""Impacts at position locks: which elements lock, and the impulse they carry.

A spring-like element *locks* when the active branch of its law fixes the elongation
and leaves the force free: ``R`` on that branch does not depend on ``F`` and does depend
on ``q`` (a taut inextensible string, ``q = L``; any user law with a hard stop). The
branch is read from the law's generated code (:func:`lumped.codegen.branches.law_branches`),
never from the law's name. When the elongation rate ``q' = v_b - v_a`` of such an element
does not vanish as it locks, the velocities must jump: an impact.

The impact law (Moreau; Newton's restitution law on the locked elements)::

    M (v+ - v-) = -B^T P         (masses: momentum; junctions, m = 0: B^T P = 0)
    B v+ = -e B v-               (each locked element; e = 0: perfectly inelastic)

``B`` is the incidence of the locked elements (row ``e``: ``+1`` at node ``b_e``, ``-1``
at node ``a_e``, ground dropped, so ``B v`` are their elongation rates) and ``P`` their
impulses (N s), positive in tension like the forces: ``+P`` acts on ``a``, ``-P`` on
``b``. For ``e = 0`` this is Gauss' principle:
``v+`` is the velocity closest to ``v-`` in the kinetic-energy norm among those that keep
every locked element rigid, so momentum is conserved through masses and junctions and
kinetic energy is lost, never gained::

    energy_lost = 1/2 sum_i m_i ((v-_i)^2 - (v+_i)^2) >= 0.

A lock can only *hold*, never push: an element whose impulse comes out with the sign
opposite to its approach rate (it would be pulled into the lock) is released and the
impulse is recomputed without it (a small active set, at most one pass per element).
Where the impulses are not unique (two strings in parallel), or a junction's velocity
is not fixed by the locks, the minimum-norm solution is taken (documented in
``docs/theory/events.md``).

**A lock on a moving support** (:mod:`lumped.scene.supports`; the scene the view of a
:class:`~lumped.scene.supports.SupportFrame`, its clock at the impact's time): the
element's rate is ``q' = (B v)_e + o_e'(t)``, the support's ``o_e' = +-v_s(t)`` (``+``
at its end ``b``), and the law above holds for it (``B v+ + o' = -e (B v- + o')``): the
support's motion is prescribed (infinite mass), it takes no momentum, and does the work
``o_e' P_e`` through the impulse, which the energy lost includes::

    energy_lost = 1/2 sum_i m_i ((v-_i)^2 - (v+_i)^2) + sum_e o_e' P_e >= 0

(one mass on a string to a support at ``v_s``: ``(1 - e^2) m (v- - v_s)^2 / 2``).

All inputs and outputs are Python floats; the one linear solve per impact uses numpy.
"""

from __future__ import annotations

from collections.abc import Sequence

from ...scene.network import across
from ...scene.supports import clock_rates

__all__ = ["lockable_elements", "locking_elements", "lock_state", "impact_velocities",
           "onto_locks"]


def _branches(law):
    """``law_branches(law)`` when the branch machinery is there, else ``None``."""
    try:
        from lumped.codegen.branches import law_branches
    except ImportError:  # pragma: no cover - before the branch machinery lands
        return None
    try:
        return law_branches(law)
    except Exception:  # noqa: BLE001 - a law the branch analysis cannot take: use the kernel
        return None


def lock_state(law, q: float, F: float) -> bool:
    """True when the active branch of ``law`` at ``(q, F)`` fixes ``q`` and leaves ``F`` free.

    From the generated branches (``law_branches(law).info[i].locks``); a law without
    them falls back to its kernel's generalised Jacobian at the point: ``dR/dF == 0``
    and ``dR/dq != 0`` (the same test, read off the active branch's derivatives).
    """
    lb = _branches(law)
    if lb is not None:
        return bool(lb.info[lb.branch(q, F)].locks)
    R, Rq, RF = law.kernel(q, F)
    return RF == 0.0 and Rq != 0.0 and Rq == Rq


def lockable_elements(scene) -> list[int]:
    """Spring-like elements whose law has a locking branch (all spring-like elements when
    the law's branches cannot be read: the per-point test then decides)."""
    out = []
    for e, el in enumerate(scene.elements):
        if el.kind != "spring":
            continue
        lb = _branches(el.law)
        if lb is None or any(info.locks for info in lb.info):
            out.append(e)
    return out


def locking_elements(scene, x: Sequence[float], v: Sequence[float],
                     F: Sequence[float], candidates: Sequence[int] | None = None) -> list[int]:
    """Indices of the spring-like elements whose active branch is a position lock.

    Parameters
    ----------
    scene : Scene
    x, v : sequence of float
        Node displacements and velocities (scene node order).
    F : sequence of float
        Element forces.
    candidates : sequence of int, optional
        Only these elements are tested (e.g. :func:`lockable_elements`, computed once).

    Returns
    -------
    list of int
        Element indices, ascending. Dashpot-like elements (a stuck dashpot is a *rate*
        lock: sticking, not an impact) are never listed.
    """
    elements = scene.elements
    ea, eb = scene.elem_a, scene.elem_b
    out = []
    for e in (range(len(elements)) if candidates is None else candidates):
        el = elements[e]
        if el.kind != "spring":
            continue
        q = (x[eb[e]] if eb[e] >= 0 else 0.0) - (x[ea[e]] if ea[e] >= 0 else 0.0)
        if lock_state(el.law, q, F[e]):
            out.append(e)
    return out


def _rates(scene, v: Sequence[float], elems: Sequence[int],
           moving: bool = False) -> list[float]:
    """``v_b - v_a`` per element of ``elems``, plus the support's ``o_e'`` at the
    support clock's time when ``moving`` (:func:`lumped.scene.supports.clock_rates`)."""
    offsets = clock_rates(scene) if moving else None
    out = []
    for e in elems:
        a, b = scene.elem_a[e], scene.elem_b[e]
        r = across(v, a, b)
        out.append(r if offsets is None else r + offsets[e])
    return out


def impact_solve(scene, v: Sequence[float], elems: Sequence[int], restitution: float,
           target: Sequence[float] | None = None, moving: bool = False):
    """The impact equations for the elements ``elems``: ``(v+, P, rates)`` (minimum norm);
    ``target`` replaces ``-e q'`` as the locked rates after the impact.

    With ``moving`` the rates ``q'`` of elements on a moving support include the
    support's ``o_e'`` at the support clock's time (the impact law of the module notes;
    ``target`` then is the whole rate ``q'`` after); without it they are ``B v`` (an
    increment of positions or of node rates alone)."""
    import numpy as np

    N, L = len(scene.nodes), len(elems)
    m = scene.masses
    rates = _rates(scene, v, elems, moving)
    # unknowns (dv_1..dv_N, P_1..P_L); rows: node balances, then lock conditions
    K = np.zeros((N + L, N + L))
    rhs = np.zeros(N + L)
    for i in range(N):
        K[i, i] = m[i]
    for r, e in enumerate(elems):
        a, b = scene.elem_a[e], scene.elem_b[e]
        for node, sgn in ((a, -1.0), (b, 1.0)):
            if node >= 0:
                # m dv = +P on a, -P on b  (P in tension, as F)
                K[node, N + r] = sgn
                K[N + r, node] = sgn
        rhs[N + r] = (-(1.0 + restitution) * rates[r] if target is None
                      else target[r] - rates[r])
    sol, *_ = np.linalg.lstsq(K, rhs, rcond=None)
    dv = sol[:N]
    P = sol[N:]
    return [float(v[i] + dv[i]) for i in range(N)], [float(p) for p in P], rates


def _holding_direction(e: int, rate: float, v_scale: float,
                       forces: Sequence[float] | None) -> float:
    """The sign of the impulse with which element ``e`` can hold its lock: that of its
    approach ``rate``, or of its force when the rate is round-off of ``v_scale``."""
    if abs(rate) > 1e-12 * v_scale or forces is None:
        return rate
    return float(forces[e])


def impact_velocities(scene, x: Sequence[float], v: Sequence[float], locked: Sequence[int],
                      restitution: float = 0.0, forces: Sequence[float] | None = None,
                      ) -> tuple[list[float], list[float], float]:
    r"""Velocities after an impact at the locked elements, their impulses, the energy lost.

    Solves ``M dv = -B^T P`` (junctions: ``0 = -B^T P``), ``B (v + dv) = -e B v`` for the
    elements ``locked`` (see the module notes for ``B`` and the sign of ``P``).

    Parameters
    ----------
    scene : Scene
    x : sequence of float
        Node displacements at the impact (not used by the impact law itself, which is
        velocity-level; kept so that every caller passes the full state).
    v : sequence of float
        Node velocities just before the impact.
    locked : sequence of int
        Element indices, e.g. from :func:`locking_elements`.
    restitution : float
        Newton's coefficient ``e`` in ``[0, 1]``; ``0`` (default) keeps the paper's
        inextensible string (perfectly inelastic).
    forces : sequence of float, optional
        Element forces (scene element order) on the locks. An element that sits on its
        lock at rest (rate zero to round-off of the velocities) has no approach rate to
        say which way it holds; its force does (a taut string: tension). Without
        ``forces`` such an element holds either way.

    Returns
    -------
    v_after : list of float
        Node velocities just after.
    impulses : list of float
        Impulse carried by each element of ``locked`` (same order; N s, positive in
        tension). ``0.0`` for an element released because it would have to push.
    energy_lost : float
        ``1/2 sum m_i (v_i^2 - v_after_i^2) >= 0`` (J), plus the supports' work
        ``sum o_e' P_e`` on a scene with moving supports (see the module notes).

    Raises
    ------
    ValueError
        If ``restitution`` is outside ``[0, 1]`` or an index in ``locked`` is not an
        element, or a velocity is not finite.
    """
    import math

    if not (isinstance(restitution, (int, float)) and 0.0 <= restitution <= 1.0):
        raise ValueError(f"`restitution` must be in [0, 1], got {restitution!r}")
    E = len(scene.elements)
    for e in locked:
        if not (isinstance(e, int) and 0 <= e < E):
            raise ValueError(f"`locked` must hold element indices in [0, {E}), got {e!r}")
    if len(v) != len(scene.nodes) or not all(math.isfinite(float(vi)) for vi in v):
        raise ValueError(f"`v` must hold {len(scene.nodes)} finite velocities, got {list(v)!r}")
    v_scale = max((abs(float(vi)) for vi in v), default=0.0)
    active = list(locked)
    impulses = dict.fromkeys(locked, 0.0)
    v_after = [float(vi) for vi in v]
    for _ in range(len(locked) + 1):
        if not active:
            break
        v_after, P, rates = impact_solve(scene, v, active, restitution, moving=True)
        # a lock holds, it never pushes: the impulse opposes the approach rate; an
        # element at rest on its lock (rate below the velocities' round-off, e.g. a
        # string holding a mass that another lock stopped) holds the way its force acts
        wrong = [e for e, p, r in zip(active, P, rates, strict=True)
                 if p * _holding_direction(e, r, v_scale, forces) < 0.0
                 and abs(p) > 1e-12 * (abs(p) + 1.0)]
        for e, p in zip(active, P, strict=True):
            impulses[e] = p
        if not wrong:
            break
        active = [e for e in active if e not in wrong]
        for e in wrong:
            impulses[e] = 0.0
        if not active:
            v_after = [float(vi) for vi in v]
    m = scene.masses
    lost = 0.5 * sum(mi * (vb * vb - va * va) for mi, vb, va in zip(m, v, v_after, strict=True))
    offsets = clock_rates(scene)
    if offsets is not None:  # the work of the supports through the impulses: o_e' P_e
        lost += sum(offsets[e] * impulses[e] for e in locked)
    return v_after, [impulses[e] for e in locked], max(lost, 0.0)


def onto_locks(scene, x: Sequence[float], F: Sequence[float],
               locked: Sequence[int]) -> list[float]:
    """Displacements moved (least, in the kinetic-energy norm) so that every element of
    ``locked`` sits on its lock: ``dq_e = -R_e / (dR/dq)_e`` from its law at ``(q_e, F_e)``.

    Removes the rounding a Newton solve leaves on a lock (``q = L`` to an ulp), which
    the next short step would otherwise turn into a velocity ``ulp / h``.
    """
    q = scene.elongations(x, [0.0] * len(x))
    dq = []
    for e in locked:
        R, Rq, _ = scene.elements[e].law.kernel(q[e], F[e])
        dq.append(-R / Rq if Rq != 0.0 and R == R else 0.0)
    if not any(dq):
        return list(x)
    dx, _, _ = impact_solve(scene, [0.0] * len(x), list(locked), 0.0, target=dq)
    return [xi + di for xi, di in zip(x, dx, strict=True)]
