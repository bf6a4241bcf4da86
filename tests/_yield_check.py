"""A dashpot carries more than its yield force only while it slips: the check shared by
the random-network property suite and its regressions (tests/solvers)."""

from __future__ import annotations

import numpy as np

from lumped.scene import Scene
from lumped.solvers.implicit.step_system import law_scale

YIELDING = ("bingham", "coulomb", "herschel_bulkley")
EPS = float(np.finfo(float).eps)


def check_yield(scene: Scene, sol, force_tol: float = 0.0, rate_tol: float = 0.0,
                rtol: float = 0.0) -> None:
    """A dashpot carries more than its yield force only while it slips at the rate its
    law gives for that force (Coulomb: never more than ``tau``).

    ``force_tol`` (relative to the largest force of the run) is the method's own
    tolerance on forces, used where the rate is not a well-conditioned test: a
    Herschel-Bulkley law with ``n < 1`` maps a force error ``d`` above ``tau`` to a rate
    ``gamma d^n`` (``d = 1e-6``, ``n = 0.3``: ``0.016 gamma``), so there the force is
    compared with the one the law gives at the rate, ``tau + (|q|/gamma)^(1/n)``, where the
    rate is also below half the one the force gives. An
    adaptive method holds forces to ``min(1e-3, 100 rtol)`` of their scale and samples
    them on its dense output between step points, where the rate and the force are
    interpolated apart, so the law holds there only to that tolerance (a Bingham dashpot
    just after its break-out, ``rtol = 1.6e-4``: a force 2.9e-4 above ``tau`` at a rate
    1.4e-4); for such a method (``force_tol > 0``) every Bingham and Herschel-Bulkley
    law gets the force-unit test. A stuck dashpot (rate 0) above ``tau`` by more than
    that tolerance still fails it. The method's error is global, so the scale of that
    tolerance is the run's largest force, not the sample's (seed 24221 of both loops'
    property: a Herschel-Bulkley ``n = 0.8`` dashpot 2.4e-4 s before it stops was
    ``2.3e-4`` above its law at ``rtol = 6.25e-4``, where the sample's largest force was
    0.15 and the run's 0.83; that error falls with ``rtol``).

    ``rate_tol`` is the same method's tolerance on velocities (``atol + rtol max |v|``):
    a rate ``q > 0`` that is not exactly zero (not on a lock) is known to ``rate_tol``
    only, so the force is compared with the law's at ``q + rate_tol``. Where the law is
    steep in the rate (Herschel-Bulkley ``n > 1``: ``dF/dq = 1 / (2 sqrt(gamma q))``
    for ``n = 2``) a rate error within the tolerance shows as a large force error (a
    rate of 7.6e-5 within a velocity tolerance of 1.1e-4, ``gamma = 0.3``: 0.008 in
    force). A rate of exactly zero is known to the rounding of the two velocities it is
    the difference of (``4 eps`` of :func:`_rate_terms`), no better: where ``n > 1`` the law's force
    ``tau + (q/gamma)^(1/n)`` has an infinite slope at ``q = 0``, so a dashpot slipping at
    a rate that a parallel lock holds at zero carries ``tau`` only to
    ``(eps |v| / gamma)^(1/n)`` (``n = 2``, ``gamma = 0.9``, ``|v| = 1``: ``1.6e-8``; seed
    23009 of the tight run: ``8.1e-9`` above ``tau`` at a rate of ``6e-17``). A stuck
    dashpot above ``tau`` by more than that still fails it.

    A Coulomb element's force never exceeds ``tau`` by more than ``rtol`` (the method's
    relative tolerance) of the forces' scale: on the dense output a force that sits at
    its bound (just stuck, or slipping) is interpolated between nodes that hold it."""
    v = {nd.name: sol.v[nd.name] for nd in scene.nodes}
    # Newton's tolerance is relative to the forces at the sample; the adaptive method's
    # force tolerance to the run's largest
    scale = np.abs(sol.forces).max(axis=1)
    run_scale = float(scale.max(initial=0.0))
    for el in scene.elements:
        if el.law_name not in YIELDING:
            continue
        p = el.law.params
        tau = p["tau"]
        F = np.abs(sol.F[el.name])
        above = F > tau * (1 + 1e-9) + 1e-8 * scale + 1e-12
        if el.law_name == "coulomb":
            assert not (above & (F > tau + rtol * scale)).any(), \
                f"{el.name} above its yield force"
            continue
        q_signed = v.get(el.b, 0.0) - v.get(el.a, 0.0) + np.zeros_like(F)
        q = np.abs(q_signed)
        slip_rate = p["gamma"] * np.maximum(F - tau, 0.0) ** p.get("n", 1.0)
        stuck_above = above & (q < 0.5 * slip_rate)
        if p.get("n", 1.0) < 1.0 or force_tol > 0.0:  # the force from the rate, in force units
            # a rate known to rate_tol; a rate of exactly zero to the rounding of the
            # velocities it is the difference of
            q_hi = np.where(q > 0.0, q + rate_tol, 4.0 * EPS * _rate_terms(v, el, F))
            F_law = tau + (q_hi / p["gamma"]) ** (1.0 / p.get("n", 1.0))
            over = F - F_law - (tau * 1e-9 + 1e-8 * scale + 1e-12 + force_tol * run_scale)
            assert not (stuck_above & (over > 0.0)).any(), f"{el.name} stuck above its yield force"
            continue
        # Newton accepts the law's row when |R| <= rtol S + atol (NewtonOptions: 1e-10,
        # 1e-12; S = law_scale, the magnitude of the row's terms, the rate's being the
        # velocities it is the difference of, |v_a| + |v_b|, as the step system's).
        # Where dR/dF vanishes at the yield force (Herschel-Bulkley n > 1) a stuck
        # element may thus carry |F| - tau up to about ((rtol Q + atol) / gamma)^(1/n)
        # (3e-7 for n = 2, gamma = 9, Q = 0): the method's own tolerance, not an error.
        # Beside a stuck dashpot that holds the rate at exactly zero (a free split) it
        # slips at that rate on its branch at tau + (rtol Q / gamma)^(1/n) (seed 24004 of
        # bdf1's property: n = 1.5, Q = 3.7, 1.75e-7 above tau at the step of the event).
        # Flag only a state whose law residual exceeds twice that acceptance tolerance.
        Q = _rate_terms(v, el, F)
        for i in np.nonzero(stuck_above)[0]:
            Fi = float(sol.F[el.name][i])
            R, Rq, RF = el.law.kernel(float(q_signed[i]), Fi)
            S = law_scale(el.law.kernel, float(q_signed[i]), Fi, R, Rq, RF, float(Q[i]))
            stuck_above[i] = abs(R) > 2.0 * (1e-10 * S + 1e-12)
        assert not stuck_above.any(), f"{el.name} stuck above its yield force"


def _rate_terms(v: dict, el, like: np.ndarray) -> np.ndarray:
    """``|v_a| + |v_b|`` sample by sample (a ground end has ``v = 0``): the terms a rate
    ``v_b - v_a`` is computed from, whose rounding it carries (``eps`` of them)."""
    return np.abs(v.get(el.a, 0.0)) + np.abs(v.get(el.b, 0.0)) + np.zeros_like(like)


def run_checked(scene: Scene, method: str, dt: float, t_end: float):
    """``simulate(scene, method=method, dt=dt, t_end=t_end)``, checked against the laws:
    it completes, every value is finite and no stuck dashpot carries more than its yield
    force (:func:`check_yield`, strict). Returns the solution."""
    from lumped import simulate

    sol = simulate(scene, method=method, dt=dt, t_end=t_end)
    assert sol.ok, sol.message
    assert np.all(np.isfinite(sol.data))
    check_yield(scene, sol)
    return sol
