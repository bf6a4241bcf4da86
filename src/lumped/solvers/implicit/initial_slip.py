r"""The initial forces of dashpots that slip from rest: at ``t = 0``, not at ``t = eps``.

:func:`lumped.solvers.implicit.initial_state.consistent_initial_state` reads the initial
forces off an implicit step of length ``h = eps`` (``1e-20`` of the run's time scale)
whose velocities are ``v_i(0) + eps a_i``. Two of its readings are the step's, not those
of ``t = 0``; this module owns their corrections for the dashpots whose rate at ``t = 0``
is known (each end a mass or ground, none on a moving support):

1. :func:`rates_below_resolution`. A dashpot whose law is set-valued at rest
   (``R(0, 0) = 0`` with ``dR/dF = 0``: Bingham, Herschel-Bulkley, Coulomb) and whose
   rate ``q_0 = v_b(0) - v_a(0)`` is not 0 has its force pinned by ``q_0`` alone:
   ``sgn(q_0) tau`` however small ``q_0``. When the step reverses or stops that rate,

   .. math:: \operatorname{fl}\bigl(q_0 + \varepsilon\,(a_b - a_a)\bigr) = 0
             \ \text{ or }\ \operatorname{sgn} \ne \operatorname{sgn} q_0,

   (a mass at ``v_0 = 1e-113`` under a load past the yield force), that force has the
   wrong sign for the slip that follows, or holds a mass that sticks: the dashpot starts
   at rest (``q_0 = 0``) and the limit system solves its force again; a mass at its end
   whose own ``v_0`` the step reverses starts at rest, ``v(0) = 0`` (a change below
   ``eps |a|``), so that row 0 holds the laws. Its sign is then
   the load's, ``sgn F_d = sgn F~`` (the paper's relation (16), ``F~ = m v_0 / h + F -
   F_s`` with ``m v_0 / h`` negligible).
2. :func:`settle_on_rest_set`. A dashpot at rest at ``t = 0`` (``q_0 = 0``) that slips
   reads its law at the step's rate ``eps (a_b - a_a)``: a Herschel-Bulkley ``n = 2``
   dashpot, ``q = gamma (|F| - tau)^2``, then takes ``tau + sqrt(eps |a| / gamma)``, a
   Bingham dashpot ``tau + eps |a| / gamma`` (``1e-8`` beyond ``tau`` at ``gamma =
   1e-12``), and Newton's residual test, where the forward law is flat in ``F``, fixes
   ``F`` only to about ``sqrt(tol / gamma)``. At ``t = 0`` the force lies in the law's set
   at rest ``{F : R(0, F) = 0}`` (``[-tau, tau]``): the force is moved to that set's edge
   nearest it, ``sgn(F) tau``, by bisection on ``R(0, F) = 0`` (exact in floating point:
   the forward law at ``q = 0`` is ``-gamma max(|F| - tau, 0)^n``, 0 only within the
   band).

The moved forces are those of elements between masses and ground only: no junction's
balance reads them (the masses' accelerations do, which the initial state does not hold).
"""

from __future__ import annotations

import math

from ...scene import Mass, Scene

__all__ = ["rates_below_resolution", "settle_on_rest_set"]


def _known_rate_dashpots(scene: Scene, candidates: list[int]) -> list[int]:
    """Those of ``candidates`` that are dashpots whose rate at ``t = 0`` is the masses'
    ``v_b(0) - v_a(0)``: each end a mass or ground, none on a moving support."""
    if not candidates:
        return []
    nodes, ea, eb = scene.nodes, scene.elem_a, scene.elem_b
    on_support = {end.element for end in scene.support_ends}
    return [e for e in candidates
            if e not in on_support and scene.elements[e].kind == "dashpot"
            and (ea[e] < 0 or isinstance(nodes[ea[e]], Mass))
            and (eb[e] < 0 or isinstance(nodes[eb[e]], Mass))]


def rates_below_resolution(scene: Scene, q0: list[float], F: list[float],
                           eps: float) -> tuple[list[int], list[int]]:
    r"""The dashpots with a rate ``q_0 != 0`` that the limit step reverses or stops (their
    forces pinned by it, as a rule), and the masses at their ends whose velocities it
    reverses or stops.

    Parameters
    ----------
    scene : Scene
        The scene.
    q0 : list of float
        The elements' initial elongations or the masses' part of their rates.
    F : list of float
        The limit system's forces, from which the masses' accelerations
        ``a_i = (f_i + sum_{a_e = i} F_e - sum_{b_e = i} F_e) / m_i`` are read.
    eps : float
        The limit step ``h``.

    Returns
    -------
    dashpots : list of int
        Each such dashpot whose law is set-valued at rest (``R(0, 0) = 0``,
        ``dR/dF = 0``) and whose rate ``fl(q_0 + eps (a_b - a_a))`` is 0 or of the other
        sign than ``q_0`` (see the module notes): it starts at rest.
    masses : list of int
        The nodes at their ends whose ``v_0 != 0`` the step reverses or stops,
        ``fl(v_0 + eps a_i)`` 0 or of the other sign: they start at rest (``v(0) = 0``,
        a change below ``eps |a_i|``), so that row 0 holds the laws (``q = 0``, ``F``
        within the set at rest).
    """
    out: list[int] = []
    masses: list[int] = []
    acc: list[float] = []
    # (a law can leave the force free at a rate below its round-off, e.g. Coulomb's
    # F + r q at q = -5e-324: the limit system read it, its masses start at rest too)
    for e in _known_rate_dashpots(scene, [e for e in range(len(q0)) if q0[e] != 0.0]):
        R, _, RF = scene.elements[e].law.kernel(0.0, 0.0)
        if not (R == 0.0 and RF == 0.0):
            continue  # a law that fixes the force at rest (newtonian): continuous in q
        if not acc:
            net = scene.net_forces(0.0, F)
            acc = [net[i] / nd.m if isinstance(nd, Mass) else 0.0
                   for i, nd in enumerate(scene.nodes)]
        a, b = scene.elem_a[e], scene.elem_b[e]
        q = q0[e] + eps * ((acc[b] if b >= 0 else 0.0) - (acc[a] if a >= 0 else 0.0))
        if q == 0.0 or (q > 0.0) != (q0[e] > 0.0):
            out.append(e)
            for i in (a, b):
                v0 = scene.nodes[i].v0 if i >= 0 else 0.0
                v = v0 + eps * acc[i] if i >= 0 else 0.0
                if v0 != 0.0 and (v == 0.0 or (v > 0.0) != (v0 > 0.0)) and i not in masses:
                    masses.append(i)
    return out, masses


def settle_on_rest_set(scene: Scene, pinned: list[float | None], q0: list[float],
                       F: list[float]) -> list[float]:
    r"""``F`` with each dashpot at rest at ``t = 0`` on its law's set at rest.

    A dashpot whose rate at ``t = 0`` is known and 0 (``q0[e] == 0``, see the module
    notes), whose force its law leaves to the limit system and misses its law there,
    ``R(0, F_e) != 0`` (it slips from rest: the limit system read it at the rate
    ``eps (a_b - a_a)``), takes the edge of the set ``{F : R(0, F) = 0}`` nearest ``F_e``
    on the segment from 0 (in the set) to ``F_e``: the float ``F*`` with ``R(0, F*) = 0``
    next to one with ``R != 0``, by bisection (at most ~1100 kernel calls, ~60 for
    forces of order 1). For the yield laws, ``F* = sgn(F_e) tau``. A law with
    ``R(0, 0) != 0`` is left as it is.

    Parameters
    ----------
    scene : Scene
        The scene.
    pinned : list of float or None
        The forces the laws fix at ``q_0`` alone (``None``: left to the limit system).
    q0 : list of float
        The elements' initial elongations or the masses' part of their rates (0 for a
        dashpot that starts at rest).
    F : list of float
        The limit system's forces (not changed).

    Returns
    -------
    list of float
        The forces, those of the dashpots slipping from rest moved to their yield forces.
    """
    out = list(F)
    for e in _known_rate_dashpots(scene, [e for e, Fp in enumerate(pinned)
                                          if Fp is None and q0[e] == 0.0]):
        kernel = scene.elements[e].law.kernel
        if not math.isfinite(out[e]) or kernel(0.0, out[e])[0] == 0.0 \
                or kernel(0.0, 0.0)[0] != 0.0:
            continue
        inside, outside = 0.0, out[e]
        while True:
            mid = 0.5 * (inside + outside)
            if mid in (inside, outside):
                break
            if kernel(0.0, mid)[0] == 0.0:
                inside = mid
            else:
                outside = mid
        out[e] = inside
    return out
