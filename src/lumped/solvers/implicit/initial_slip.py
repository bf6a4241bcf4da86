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
``radau5``'s row 0 after its start probe (:func:`start_at_known_rates`) moves the yield
dashpots at junctions too, and its locks with them (:func:`junction_slips_at_start`).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from ...scene import Mass, Scene
from ...scene.network import across
from ..newton.scalar_root import scalar_root
from ..nonsmooth.lock_forces import forces_from_accelerations

__all__ = ["known_rate_dashpots", "rates_below_resolution", "rest_edge",
           "set_valued_at_rest", "settle_on_rest_set", "start_at_known_rates",
           "junction_slips_at_start"]


def known_rate_dashpots(scene: Scene, candidates: list[int]) -> list[int]:
    """Those of ``candidates`` that are dashpots whose rate at ``t = 0`` is the masses'
    ``v_b(0) - v_a(0)``: each end a mass or ground, none on a moving support."""
    if not candidates:
        return []
    kept = getattr(scene, "__dict__", {}).get("_known_rate_dashpots")
    if kept is None or kept[0] is not scene.nodes or kept[1] is not scene.elements \
            or kept[2] is not scene.support_ends:
        nodes, ea, eb = scene.nodes, scene.elem_a, scene.elem_b
        on_support = {end.element for end in scene.support_ends}
        known = frozenset(
            e for e, el in enumerate(scene.elements)
            if e not in on_support and el.kind == "dashpot"
            and (ea[e] < 0 or isinstance(nodes[ea[e]], Mass))
            and (eb[e] < 0 or isinstance(nodes[eb[e]], Mass)))
        kept = (scene.nodes, scene.elements, scene.support_ends, known)
        if hasattr(scene, "__dict__"):  # (kept per scene: while its nodes, elements and
            scene.__dict__["_known_rate_dashpots"] = kept  # supports are those objects)
    known = kept[3]
    return [e for e in candidates if e in known]


def set_valued_at_rest(kernel) -> bool:
    """``R(0, 0) = 0`` with ``dR/dF = 0``: the law leaves the force free at rest (a yield
    law), rather than fixing it continuously in ``q`` (newtonian)."""
    R, _, RF = kernel(0.0, 0.0)
    return R == 0.0 and RF == 0.0


def _turned(before: float, after: float) -> bool:
    """A rate ``before != 0`` that ``after`` stops (0) or reverses."""
    return after == 0.0 or (after > 0.0) != (before > 0.0)


def _reversed(scene: Scene, q0: list[float], q_after: Callable[[int], float],
              v0: list[float], v_after: Callable[[int], float]
              ) -> tuple[list[int], list[int]]:
    """The set-valued dashpots at known rates ``q0[e] != 0`` that a step turns
    (``q_after(e)``), and the masses at their ends whose velocities ``v0[i] != 0`` it
    turns (``v_after(i)``): see :func:`rates_below_resolution`."""
    out: list[int] = []
    masses: list[int] = []
    for e in known_rate_dashpots(scene, [e for e in range(len(q0)) if q0[e] != 0.0]):
        if not set_valued_at_rest(scene.elements[e].law.kernel):
            continue  # a law that fixes the force at rest (newtonian): continuous in q
        if _turned(q0[e], q_after(e)):
            out.append(e)
            for i in (scene.elem_a[e], scene.elem_b[e]):
                if i >= 0 and i not in masses and v0[i] != 0.0 \
                        and _turned(v0[i], v_after(i)):
                    masses.append(i)
    return out, masses


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
    # (a law can leave the force free at a rate below its round-off, e.g. Coulomb's
    # F + r q at q = -5e-324: the limit system read it, its masses start at rest too)
    acc: list[float] = []

    def a(i: int) -> float:
        if not acc:
            net = scene.net_forces(0.0, F)
            acc.extend(net[j] / nd.m if isinstance(nd, Mass) else 0.0
                       for j, nd in enumerate(scene.nodes))
        return acc[i] if i >= 0 else 0.0

    ea, eb = scene.elem_a, scene.elem_b
    v0 = [nd.v0 if isinstance(nd, Mass) else 0.0 for nd in scene.nodes]
    return _reversed(scene, q0, lambda e: q0[e] + eps * (a(eb[e]) - a(ea[e])), v0,
                     lambda i: v0[i] + eps * a(i))


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
    for e in known_rate_dashpots(scene, [e for e, Fp in enumerate(pinned)
                                          if Fp is None and q0[e] == 0.0]):
        out[e] = rest_edge(scene.elements[e].law.kernel, out[e])
    return out


def rest_edge(kernel, F: float) -> float:
    """``F`` if ``R(0, F) = 0`` (or ``F`` not finite, or ``R(0, 0) != 0``), else the float
    ``F*`` on the segment from 0 to ``F`` with ``R(0, F*) = 0`` next to one with
    ``R != 0`` (see :func:`settle_on_rest_set`).

    The set at rest is an interval about 0, so ``F*`` is one float, found by bisection
    between a point inside (``R = 0``) and one outside. Newton steps on ``R(0, .)`` from
    outside come first (at most :data:`_EDGE_NEWTON`): on an affine slip branch (Bingham,
    Coulomb, Herschel-Bulkley ``n = 1``) the first lands on the edge or next to it, and
    the float beside it closes the bracket, in 3 to 5 kernel calls instead of about 55.
    A step that leaves the bracket, or a flat branch (``dR/dF = 0``), hands over to the
    bisection, which gives the same ``F*``."""
    R1, _, RF1 = kernel(0.0, F) if math.isfinite(F) else (0.0, 0.0, 0.0)
    if R1 == 0.0 or kernel(0.0, 0.0)[0] != 0.0:
        return F
    inside, outside = 0.0, F
    for _ in range(_EDGE_NEWTON):
        if not (RF1 != 0.0 and math.isfinite(R1 / RF1)):
            break
        guess = outside - R1 / RF1
        if not (guess != outside and min(inside, outside) < guess < max(inside, outside)):
            break
        R_g, _, RF_g = kernel(0.0, guess)
        if R_g != 0.0:
            outside, R1, RF1 = guess, R_g, RF_g
            continue
        inside = guess
        beside = math.nextafter(guess, outside)
        if beside == outside or kernel(0.0, beside)[0] != 0.0:
            return guess
        inside = beside
        break
    while True:
        mid = 0.5 * (inside + outside)
        if mid in (inside, outside):
            return inside
        if kernel(0.0, mid)[0] == 0.0:
            inside = mid
        else:
            outside = mid


#: Newton steps of :func:`rest_edge` from outside the set at rest, before its bisection.
_EDGE_NEWTON = 3


def start_at_known_rates(scene: Scene, v: list[float], F: list[float],
                         v_probe: list[float], F_probe: list[float],
                         locked: Sequence[bool] = (),
                         taken: tuple[float, list[float]] | None = None
                         ) -> tuple[list[float], list[float]]:
    r"""Row 0 of the adaptive method: the dashpots at known rates on their laws at
    ``t = 0``, after its mode choice by a probe step of length ``h_p`` (``1e-9`` of the
    run, far longer than the initial state's ``eps``).

    Where the probe's state is taken at ``t = 0`` (the consistent initial forces miss a
    law at the probe's junction velocities), a dashpot between masses and ground would
    keep the probe's force: read at the rate ``q_0 + h_p (a_b - a_a)``, a Herschel-Bulkley
    ``n = 2`` dashpot at ``v_0 = 1e-113`` then takes ``tau + sqrt(h_p |a| / gamma)``
    (``2.4e-4`` beyond ``tau`` at ``h_p = 5e-10``), off its law at ``q_0``. Here, as in
    :func:`rates_below_resolution` with the probe for the limit step:

    1. a set-valued dashpot whose rate ``q_0 != 0`` the probe reverses or stops starts
       at rest: each mass at its end whose ``v_0`` the probe reverses or stops gets
       ``v(0) = 0`` (a change below ``h_p |a|``), and the dashpot the edge of its set at
       rest nearest the probe's force (its yield force with the sign of the slip that
       follows, the paper's (16)); so does one the chosen mode locks (``locked``) whose
       probe rate is round-off of ``q_0`` (``|q| <= eps |q_0|``): the full laws found its
       stop inside the probe, whose rate may end short of zero (a Herschel-Bulkley ``n =
       1.5`` dashpot from ``v_0 = 1e-10``: ``5.7e-42``; a lock to a moving support keeps
       its rate ``q_0``, the support's),
       and row 0 would otherwise pair ``v(0) = 0``, set by the lock, with the slipping
       force of the initial state, above the yield force;
    2. every other dashpot at a known rate ``q = v_b(0) - v_a(0)`` whose law fixes its
       force there gets the root of ``R(q, F) = 0``
       (:func:`lumped.solvers.newton.scalar_root.scalar_root`, a sign change between
       neighbouring floats at worst: ``tau`` itself at ``q = 1e-113``); at rest
       (``q = 0``) a force off the set at rest takes that set's edge nearest it;
    3. with ``taken`` (the probe's forces were taken), the yield dashpots at a junction
       too (:func:`junction_slips_at_start`).

    Parameters
    ----------
    scene : Scene
        The scene.
    v, F : list of float
        The node velocities and element forces of row 0 so far (the consistent initial
        ones, or the probe's where its state was taken).
    v_probe, F_probe : list of float
        The velocities and forces of the probe step that chose the mode.
    locked : sequence of bool, optional
        Per element, whether the chosen mode locks it (a stuck dashpot).
    taken : tuple of (float, list of float), optional
        ``(t, x)``, the time and displacements of the start, when ``F`` is the probe's
        (the consistent initial forces missed a law): rule 3 applies.

    Returns
    -------
    v, F : list of float
        The velocities (masses stopped by rule 1) and forces of row 0.
    """
    v, F = list(v), list(F)
    ea, eb = scene.elem_a, scene.elem_b
    known = known_rate_dashpots(scene, list(range(len(F))))

    def rate(vel: list[float], e: int) -> float:
        return across(vel, ea[e], eb[e])

    q0 = [0.0] * len(F)
    for e in known:
        q0[e] = rate(v, e)
    # locked by the chosen mode, the probe's rate round-off of the initial one: stopped
    held = {e for e in known if e < len(locked) and locked[e]
            and abs(rate(v_probe, e)) <= 2.220446049250313e-16 * abs(q0[e])}
    turned, stopped = _reversed(scene, q0, lambda e: 0.0 if e in held else rate(v_probe, e),
                                v, lambda i: v_probe[i])
    for i in stopped:
        v[i] = 0.0
    for e in known:
        kernel = scene.elements[e].law.kernel
        q = 0.0 if e in held else rate(v, e)  # (a lock's rate: 0; its masses: the lock's)
        start = F_probe[e] if e in turned else F[e]
        try:
            root, fixed = scalar_root(kernel, q, start)
        except ValueError:
            continue
        if fixed and math.isfinite(root):
            F[e] = root
        elif q == 0.0:
            F[e] = rest_edge(kernel, start)
    if taken is not None:
        F = junction_slips_at_start(scene, taken[0], taken[1], v, F, v_probe, F_probe, locked)
    return v, F


def junction_slips_at_start(scene: Scene, t: float, x: list[float], v: list[float],
                            F: list[float], v_probe: list[float], F_probe: list[float],
                            locked: Sequence[bool]) -> list[float]:
    r"""Rule 3 of :func:`start_at_known_rates`: the yield dashpots with an end at a
    junction on their laws at the start's rates, the locks rebalanced.

    Where the start takes the probe's forces, a yield dashpot (set-valued at rest) that
    the chosen mode does not lock and that joins a junction keeps the force its law gives
    at the probe's rate ``h_p (a_b - a_a)``, not at the start's: one that slips from rest
    there reads ``tau + (h_p |a| / gamma)^(1/n)`` (``1.6e-6`` beyond ``tau`` for ``n =
    1.5``, ``4.5e-5`` for ``n = 2``, at ``h_p = 5e-10``, ``|a| = 4``) beside a start rate
    of round-off (the probe's junction velocity, ``-2e-35``): a dashpot at rest above its
    yield force. Each such dashpot takes, at the rate ``q_0`` of the start (the masses'
    velocities and row 0's junction velocities: those of ``t`` itself,
    :mod:`lumped.solvers.modes.junctions_at`, or the probe's where that fails), the edge
    of its set at rest nearest the probe's force when ``q_0`` is 0 or of the other sign
    than the probe's rate (it slips from rest, the paper's (16)), else its law's force at
    ``q_0`` where the law fixes it
    (:func:`~lumped.solvers.newton.scalar_root.scalar_root`); one whose ``q_0`` is the
    probe's rate keeps its force. The elements the mode locks (``locked``) then take the
    forces of the balance of accelerations
    (:func:`~lumped.solvers.nonsmooth.lock_forces.forces_from_accelerations`), which
    restores the junctions' balances. Where that balance has no solution, or leaves a
    junction's balance worse than the probe's forces had it (beyond the round-off of its
    terms; no lock at that junction takes the change), ``F`` is returned as it is.
    Dashpots on a moving support are left alone (their rates carry the support's).

    Returns
    -------
    list of float
        The forces (``F`` itself when nothing changed or the balance fails).
    """
    ea, eb, nodes = scene.elem_a, scene.elem_b, scene.nodes
    skip = set(known_rate_dashpots(scene, list(range(len(F))))) | {
        end.element for end in scene.support_ends}
    out = list(F)
    for e, el in enumerate(scene.elements):
        if el.kind != "dashpot" or e in skip or (e < len(locked) and locked[e]):
            continue
        kernel = el.law.kernel
        if not set_valued_at_rest(kernel):
            continue
        q0, q_probe = across(v, ea[e], eb[e]), across(v_probe, ea[e], eb[e])
        if q0 == q_probe:  # (the probe's force is the law's at q0)
            continue
        if q0 == 0.0 or _turned(q0, q_probe):
            out[e] = rest_edge(kernel, F_probe[e])
            continue
        try:
            root, fixed = scalar_root(kernel, q0, F_probe[e])
        except ValueError:
            continue
        if fixed and math.isfinite(root):
            out[e] = root
    if out == F:
        return F
    got = forces_from_accelerations(scene, t, x, v, out,
                                    [e for e in range(len(F)) if e < len(locked) and locked[e]])
    if got is None or not all(map(math.isfinite, got)):
        return F
    before, after = scene.net_forces(t, F), scene.net_forces(t, got)
    f = scene.external_forces(t)
    for i, nd in enumerate(nodes):
        if isinstance(nd, Mass):
            continue
        size = abs(f[i]) + sum(abs(got[e]) for e in range(len(F)) if i in (ea[e], eb[e]))
        if abs(after[i]) > abs(before[i]) + 8.0 * 2.220446049250313e-16 * size:
            return F
    return got
