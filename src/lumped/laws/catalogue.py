r"""The built-in law catalogue: one factory per law, :data:`BUILTIN_LAWS` and :func:`get_law`.

Each factory returns a fresh :class:`~lumped.laws.element_law.ElementLaw` with its
residual, parameters and sign convention documented (``F > 0`` in tension resists
``q > 0``; see :mod:`lumped.laws.element_law`).
"""

from __future__ import annotations

import math

from .._validate import as_finite, as_positive
from .element_law import ElementLaw

__all__ = [
    "BUILTIN_LAWS",
    "bingham",
    "coulomb",
    "get_law",
    "herschel_bulkley",
    "implicit_spring",
    "linear_spring",
    "newtonian",
    "s_shaped",
    "s_shaped_point",
    "s_shaped_turning_points",
    "string_spring",
]


def linear_spring() -> ElementLaw:
    r"""Linear spring (paper eq. 5): ``F - k q = 0``, ``k > 0``.

    ``q`` is the elongation and ``F`` the tension, ``F = k q``.  The residual is a
    force, so ``dR/dF = 1`` and ``dR/dq = -k``.

    Examples
    --------
    >>> law = linear_spring()
    >>> print(law)
    linear_spring (spring): F - k*q = 0
    >>> law.bind(k=100.0).kernel(0.005, 0.5)
    (0.0, -100.0, 1.0)
    """
    return ElementLaw(
        "linear_spring", "spring", "F - k*q", ["k"],
        description="linear spring F = k q (eq. 5)", domains={"k": "positive"},
    )


def string_spring() -> ElementLaw:
    r"""Spring with an inextensible string in parallel (paper Figure 2).

    .. math:: q = \min(F/k, L),\qquad R = q - \min(F/k,\ L)

    with ``k > 0`` the spring stiffness and ``L >= 0`` the length at which the string
    becomes taut.  Below ``F = k L`` the spring alone carries the load (``q = F / k``,
    also in compression); at ``q = L`` the string is taut and the force is
    *set-valued*, any ``F >= k L``.  The elongation never exceeds ``L``.  Written as
    ``q`` in terms of ``F`` because ``F`` is not a function of ``q``; the residual is
    an elongation with ``dR/dq = 1`` on both branches.  At the kink ``F = k L`` the
    Jacobian is that of the spring branch (``dR/dF = -1/k``).

    Examples
    --------
    >>> bound = string_spring().bind(k=100.0, L=0.1)
    >>> bound.residual(0.05, 5.0), bound.residual(0.1, 50.0)
    (0.0, 0.0)
    >>> bound.kernel(0.1, 50.0)
    (0.0, 1.0, -0.0)
    """
    return ElementLaw(
        "string_spring", "spring", "q - Min(F/k, L)", ["k", "L"],
        description="spring with an inextensible string in parallel, q = min(F/k, L) (Fig. 2)",
        domains={"k": "positive", "L": "nonnegative"},
    )


def newtonian() -> ElementLaw:
    r"""Newtonian (linear viscous) dashpot: ``F - c q = 0``, ``c >= 0``.

    ``q`` is the elongation rate; ``F = c q``.  Force-valued residual, ``dR/dF = 1``.

    Examples
    --------
    >>> newtonian().bind(c=2.0).kernel(1.5, 3.0)
    (0.0, -2.0, 1.0)
    """
    return ElementLaw(
        "newtonian", "dashpot", "F - c*q", ["c"],
        description="Newtonian dashpot F = c q", domains={"c": "nonnegative"},
    )


def bingham() -> ElementLaw:
    r"""Bingham dashpot (paper eq. 6), ``gamma > 0``, ``tau = mu_s N_f >= 0``.

    .. math:: R = q - \gamma\,\bigl(F - \operatorname{clip}(F, -\tau, \tau)\bigr)

    with ``clip(F, -tau, tau) = Min(Max(F, -tau), tau)``: ``q = 0`` while
    ``|F| <= tau`` (stuck; ``F`` is then fixed by the rest of the system), otherwise
    ``q = gamma (F - sgn(F) tau)``, so ``sgn(q) = sgn(F)`` (eq. 7a).  The residual is a
    rate with ``dR/dq = 1``; ``dR/dF`` is ``0`` (stuck) or ``-gamma`` (slipping).  At
    ``|F| = tau`` the stuck branch's Jacobian is returned.  For very large ``gamma``
    use :func:`coulomb` instead.

    Examples
    --------
    >>> law = bingham()
    >>> print(law)
    bingham (dashpot): q - gamma*(F - Min(tau, Max(F, -tau))) = 0
    >>> bound = law.bind(gamma=2.0, tau=1.0)
    >>> bound.residual(2.0, 2.0), bound.residual(0.0, 0.5)
    (0.0, 0.0)
    >>> bound.kernel(-2.0, -2.0)
    (0.0, 1.0, -2.0)
    """
    return ElementLaw(
        "bingham", "dashpot", "q - gamma*(F - clip(F, -tau, tau))", ["gamma", "tau"],
        description="Bingham dashpot q = gamma (F - clip(F, -tau, tau)) (eq. 6)",
        domains={"gamma": "positive", "tau": "nonnegative"},
    )


def coulomb() -> ElementLaw:
    r"""Coulomb friction, the ``gamma -> infinity`` limit of Bingham (Remark 2.1).

    .. math:: R = F - \operatorname{clip}(F + r\,q,\ -\tau,\ \tau),
              \qquad \tau = \mu_s N_f \ge 0,\ r > 0.

    The solution set is the Coulomb graph for *every* ``r > 0``: if ``|F + r q| <= tau``
    then ``R = -r q`` so ``q = 0`` and ``|F| <= tau`` (stuck); if ``F + r q > tau``
    then ``F = tau`` and ``q > 0`` (slipping forward), and symmetrically.  So
    ``F = sgn(q) tau`` while slipping and ``|F| <= tau``, ``q = 0`` while stuck, the
    limit of :func:`bingham` as ``gamma -> infinity``.

    Writing the limit as ``q - gamma (F - clip(F))`` with a huge ``gamma`` would give
    Jacobian entries of size ``gamma``; this projection form (the natural map of the
    complementarity problem) has bounded derivatives: ``(dR/dq, dR/dF) = (-r, 0)``
    stuck and ``(0, 1)`` slipping.  ``r`` only decides which branch a Newton iterate
    tries first; a good value is the stiffness the element sees during a step, e.g.
    ``r = m / h + h k`` for one mass on a spring (``h`` the effective step): wherever
    the step's linear equations (momentum, spring) hold, ``F + r q`` is then exactly
    the paper's predictor ``F~`` (Algorithm 1), so after one Newton step (which makes
    the linear equations hold) the right branch is known, and semismooth Newton
    converges in at most two iterations.  At ``|F + r q| = tau`` the stuck branch's
    Jacobian is returned.

    Examples
    --------
    >>> bound = coulomb().bind(tau=1.0, r=10.0)
    >>> bound.residual(0.0, 0.3), bound.residual(2.0, 1.0), bound.residual(-2.0, -1.0)
    (0.0, 0.0, 0.0)
    >>> bound.kernel(0.0, 0.3)
    (0.0, -10.0, 0.0)
    """
    return ElementLaw(
        "coulomb", "dashpot", "F - clip(F + r*q, -tau, tau)", ["tau", "r"],
        description="Coulomb friction F = clip(F + r q, -tau, tau) (gamma -> oo, Remark 2.1)",
        domains={"tau": "nonnegative", "r": "positive"},
    )


def herschel_bulkley() -> ElementLaw:
    r"""Herschel-Bulkley dashpot, ``q = gamma sgn(F) max(|F| - tau, 0)^n``.

    ``gamma > 0``, ``tau = mu_s N_f >= 0``, ``n > 0`` (``n < 1`` shear thinning,
    ``n > 1`` shear thickening).  Written branch by branch so that the power is only
    taken of a non-negative number::

        R = q - Piecewise((gamma*(F - tau)**n,   F > tau),
                          (-gamma*(-F - tau)**n, F < -tau),
                          (0, True))

    (plus a tie-break for ``tau = 0``, below).  A rate-valued residual with
    ``dR/dq = 1``.  For ``n != 1`` the step equation is truly nonlinear in ``F``
    (Newton needed).  At ``|F| = tau > 0`` the stuck branch is taken, so ``dR/dF = 0``
    there even for ``n < 1``, where the slip branch's slope ``gamma n (|F| - tau)^(n-1)``
    is unbounded as ``|F| -> tau``.  With ``tau = 0`` and ``n >= 1`` the stuck set is the
    single point ``F = 0``, where the law is differentiable, so the slip branch is taken
    there (``dR/dF = -gamma`` for ``n = 1``; the conditions on ``tau`` and ``n`` are
    resolved when the parameters are bound and vanish from the generated code).  With
    ``n = 1`` it is :func:`bingham` exactly: same values and same Jacobian, kinks
    included.

    Examples
    --------
    >>> bound = herschel_bulkley().bind(gamma=2.0, tau=1.0, n=0.5)
    >>> bound.residual(4.0, 5.0), bound.residual(0.0, -0.7)
    (0.0, 0.0)
    >>> bound.kernel(0.0, 1.0)
    (0.0, 1.0, -0.0)
    """
    return ElementLaw(
        "herschel_bulkley",
        "dashpot",
        "q - Piecewise("
        "(gamma*(F - tau)**n, F > tau or (F >= tau and tau <= 0 and n >= 1)),"
        " (-gamma*(-F - tau)**n, F < -tau or (F <= -tau and tau <= 0 and n >= 1)),"
        " (0, True))",
        ["gamma", "tau", "n"],
        description="Herschel-Bulkley dashpot q = gamma sgn(F) max(|F| - tau, 0)^n",
        domains={"gamma": "positive", "tau": "nonnegative", "n": "positive"},
    )


def implicit_spring() -> ElementLaw:
    r"""A softening spring known only implicitly: ``q = F/k + L0 sinh(F/F0)``.

    ``k > 0``, ``L0 >= 0``, ``F0 > 0``.  ``q`` is a strictly increasing function of
    ``F`` (``dq/dF = 1/k + (L0/F0) cosh(F/F0) > 0``), so ``F`` is a function of ``q``
    too, but not in closed form: the solver has to iterate.  Residual in length units,
    ``dR/dq = 1``.  It overflows (the kernel returns ``nan``) for ``|F/F0| > ~710``.

    Examples
    --------
    >>> import math
    >>> bound = implicit_spring().bind(k=100.0, L0=0.01, F0=2.0)
    >>> F = 3.0
    >>> q = F / 100.0 + 0.01 * math.sinh(F / 2.0)
    >>> abs(bound.residual(q, F)) < 1e-15
    True
    """
    return ElementLaw(
        "implicit_spring", "spring", "q - F/k - L0*sinh(F/F0)", ["k", "L0", "F0"],
        description="softening spring q = F/k + L0 sinh(F/F0), F(q) not in closed form",
        domains={"k": "positive", "L0": "nonnegative", "F0": "positive"},
    )


def s_shaped() -> ElementLaw:
    r"""An S-shaped law where neither variable is a function of the other.

    In the scaled variables ``u = q/q0``, ``w = F/F0`` (``q0, F0 > 0``) and with
    ``t = w - u``::

        R = (F/F0 - q/q0)**3 + 3 q/q0 - 5 F/F0 = t**3 + 3 u - 5 w

    a cubic in rotated coordinates.  The curve ``R = 0`` is parametrised by ``t``::

        u(t) = (t**3 - 5 t) / 2,    w(t) = (t**3 - 3 t) / 2

    (see :func:`s_shaped_point`).  Along it ``w`` turns where ``dR/dq = 0``
    (``t = -1, +1``: local force extrema ``F = +F0`` at ``q = 2 q0`` and ``F = -F0``
    at ``q = -2 q0``) and ``u`` turns where ``dR/dF = 0`` (``t = -+sqrt(5/3)``: local
    elongation extrema ``q = +-(5/3) sqrt(5/3) q0 ~ +-2.152 q0`` at
    ``F = +-(2/3) sqrt(5/3) F0 ~ +-0.861 F0``); see :func:`s_shaped_turning_points`.
    So ``F`` is not a function of ``q`` (three forces for ``|q| < 2.152 q0``) and
    ``q`` is not a function of ``F`` (three elongations for ``|F| < F0``).  Branches,
    in order of increasing ``t``: the outer branch ``t < -sqrt(5/3)`` (both increase),
    a fold segment, the middle branch ``|t| < 1`` through the origin (slope
    ``dF/dq = 3/5 F0/q0`` at ``q = 0``), a fold segment, and the outer branch
    ``t > sqrt(5/3)``.  A solver following it under increasing ``q`` or ``F`` must
    either stay on the branch continuous with the past or stop at a fold.
    The residual is dimensionless.

    Examples
    --------
    >>> bound = s_shaped().bind(q0=1.0, F0=1.0)
    >>> q, F = s_shaped_point(0.3, q0=1.0, F0=1.0)
    >>> abs(bound.residual(q, F)) < 1e-15
    True
    >>> [bound.residual(q, F) for q, F in ((0.0, 0.0), (2.0, 1.0), (-2.0, -1.0))]
    [0.0, 0.0, 0.0]
    """
    return ElementLaw(
        "s_shaped", "spring", "(F/F0 - q/q0)**3 + 3*q/q0 - 5*F/F0", ["q0", "F0"],
        description="S-shaped rotated cubic: neither q(F) nor F(q) is a function",
        domains={"q0": "positive", "F0": "positive"},
    )


def s_shaped_point(t: float, q0: float = 1.0, F0: float = 1.0) -> tuple[float, float]:
    """The point ``(q, F)`` with parameter ``t`` on the :func:`s_shaped` curve.

    ``q = q0 (t**3 - 5 t) / 2``, ``F = F0 (t**3 - 3 t) / 2``; every point of the curve
    is reached exactly once as ``t`` runs over the real line.
    """
    t = as_finite("t", t)
    q0 = as_positive("q0", q0)
    F0 = as_positive("F0", F0)
    return q0 * (t**3 - 5.0 * t) / 2.0, F0 * (t**3 - 3.0 * t) / 2.0


def s_shaped_turning_points(q0: float = 1.0, F0: float = 1.0) -> dict[str, tuple[float, float]]:
    """Folds of the :func:`s_shaped` curve, as ``{name: (q, F)}``.

    ``"F_max"`` / ``"F_min"``: local extrema of the force along the curve, where
    ``dR/dq = 0`` (a load-controlled path must leave its branch there);
    ``"q_max"`` / ``"q_min"``: local extrema of the elongation, where ``dR/dF = 0``
    (a displacement-controlled path must leave its branch there).

    Examples
    --------
    >>> s_shaped_turning_points(q0=1.0, F0=1.0)["F_max"]
    (2.0, 1.0)
    """
    s = math.sqrt(5.0 / 3.0)
    return {
        "F_max": s_shaped_point(-1.0, q0, F0),
        "F_min": s_shaped_point(1.0, q0, F0),
        "q_max": s_shaped_point(-s, q0, F0),
        "q_min": s_shaped_point(s, q0, F0),
    }


_FACTORIES = (
    linear_spring,
    string_spring,
    newtonian,
    bingham,
    coulomb,
    herschel_bulkley,
    implicit_spring,
    s_shaped,
)

#: The built-in laws by name.
BUILTIN_LAWS: dict[str, ElementLaw] = {law.name: law for law in (f() for f in _FACTORIES)}


def get_law(name: str) -> ElementLaw:
    """Return the built-in law called ``name``.

    Raises
    ------
    ValueError
        If there is no such law; the message lists the known names.

    Examples
    --------
    >>> get_law("bingham").parameters
    ('gamma', 'tau')
    """
    try:
        return BUILTIN_LAWS[name]
    except (KeyError, TypeError):
        raise ValueError(
            f"unknown law {name!r}; known laws: {', '.join(sorted(BUILTIN_LAWS))}"
        ) from None
