r"""Element laws: implicit constitutive relations ``R(q, F; params) = 0``.

An element joins two nodes.  Its law is one scalar residual in two variables:

* ``q``: the elongation of the element for a ``"spring"`` (alpha, paper eq. 3a), or
  its elongation *rate* for a ``"dashpot"`` (beta, eq. 3b);
* ``F``: the force in the element, positive in tension, so ``F > 0`` resists ``q > 0``
  (a stretched linear spring has ``F = k q > 0``).  For one mass on ground this is the
  paper's convention ``m v' = F(t) - F_s - F_d``.

Neither variable needs to be a function of the other: the law is only the set of
pairs ``(q, F)`` where ``R = 0``.

Declaring a law
---------------
>>> drag = ElementLaw("quadratic_drag", "dashpot", "F - c*q*Abs(q)", ["c"],
...                   domains={"c": "positive"})
>>> print(drag)
quadratic_drag (dashpot): F - c*q*Abs(q) = 0
>>> drag.bind(c=2.0).kernel(3.0, 18.0)
(0.0, -12.0, 1.0)

A string is parsed by :func:`lumped.expressions.parse_expression` (never evaluated as
Python); ``"lhs = rhs"`` means ``lhs - rhs``.  A sympy expression (or ``sympy.Eq``) is
accepted too; its symbols are matched by name.

Scaling of the built-in residuals
---------------------------------
Multiplying a residual by a non-zero constant changes neither its zero set nor the
Newton iterates, but it does change residual-based convergence tests and line-search
merit functions, and a residual whose derivatives blow up or vanish misleads both.
The built-in residuals are written so that, on every branch, the derivative with
respect to the variable that branch determines is a constant of order one in the
law's natural unit (``dR/dF = 1`` for force-valued residuals, ``dR/dq = 1`` for
elongation- or rate-valued ones), and so that no derivative grows without bound as a
parameter goes to a limit (hence the separate Coulomb law instead of Bingham with a
huge ``gamma``).
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable, Mapping, Sequence
from types import MappingProxyType
from typing import Literal

import sympy as sp

from ._validate import as_finite, as_nonnegative, as_positive
from .codegen import Kernel, check_supported, compile_kernel
from .expressions import check_symbol_name, parse_expression

__all__ = [
    "BUILTIN_LAWS",
    "BoundLaw",
    "ElementLaw",
    "KINDS",
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

#: The two kinds of element: ``q`` is an elongation (spring) or an elongation rate (dashpot).
KINDS = ("spring", "dashpot")
_DOMAINS = ("real", "positive", "nonnegative")
_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]*\Z")
_EQUALS = re.compile(r"(?<![<>=!])=(?!=)")


def _canonical(expr: sp.Basic, allowed: dict[str, sp.Symbol], law: str) -> sp.Expr:
    """Match the free symbols of a user's sympy expression to ours, by name."""
    if isinstance(expr, sp.Equality):
        expr = expr.lhs - expr.rhs
    if not isinstance(expr, sp.Expr):
        raise ValueError(
            f"law {law!r}: residual must be a scalar expression or an equation, got {expr}"
        )
    mapping = {}
    unknown = []
    for s in expr.free_symbols:
        if s.name in allowed:
            mapping[s] = allowed[s.name]
        else:
            unknown.append(s.name)
    if unknown:
        raise ValueError(
            f"law {law!r}: unknown symbol(s) {', '.join(sorted(unknown))} in the residual "
            f"(use q, F and the listed parameters: {', '.join(sorted(allowed)) })"
        )
    return expr.xreplace(mapping)


class ElementLaw:
    r"""An implicit element law ``R(q, F; params) = 0`` (immutable).

    Parameters
    ----------
    name
        Identifier of the law (letters, digits, ``_`` or ``-``, starting with a letter).
    kind
        ``"spring"`` (``q`` is the elongation) or ``"dashpot"`` (``q`` is the
        elongation rate).
    residual
        ``R`` as a string (parsed safely; ``"lhs = rhs"`` allowed) or a sympy
        expression or ``sympy.Eq``, in the symbols ``q``, ``F`` and the parameters.
    parameters
        Names of the parameters.  A parameter listed but unused is allowed; a symbol
        used but not listed is an error.
    description
        One line for humans.
    domains
        Optional ``{parameter: "positive" | "nonnegative" | "real"}`` checked by
        :meth:`bind` (default ``"real"``: any finite value).

    Attributes
    ----------
    name, kind, residual, parameters, description, domains
        As given (``residual`` as a sympy expression, ``parameters`` as a tuple).
    q, F : sympy.Symbol
        The symbols of the kinematic variable and of the force.
    symbols : dict
        Parameter name to its sympy symbol.

    Raises
    ------
    ValueError
        Bad name or kind, an unknown symbol (named in the message), a residual that
        involves neither ``q`` nor ``F``, unsupported functions, a bad domain.

    Examples
    --------
    >>> law = ElementLaw("cubic", "spring", "F = k*q + k3*q**3", ["k", "k3"])
    >>> print(law)
    cubic (spring): F - k*q - k3*q**3 = 0
    >>> law.latex()
    'F - k q - k_{3} q^{3} = 0'
    """

    __slots__ = (
        "name",
        "kind",
        "residual",
        "parameters",
        "description",
        "domains",
        "q",
        "F",
        "symbols",
    )

    name: str
    kind: Literal["spring", "dashpot"]
    residual: sp.Expr
    parameters: tuple[str, ...]
    description: str
    domains: Mapping[str, str]
    q: sp.Symbol
    F: sp.Symbol
    symbols: Mapping[str, sp.Symbol]

    def __init__(
        self,
        name: str,
        kind: Literal["spring", "dashpot"],
        residual: str | sp.Expr,
        parameters: Sequence[str],
        *,
        description: str = "",
        domains: Mapping[str, str] | None = None,
    ) -> None:
        if not isinstance(name, str) or not _NAME.match(name):
            raise ValueError(
                f"law name must start with a letter and hold only letters, digits, '_' "
                f"or '-', got {name!r}"
            )
        if kind not in KINDS:
            raise ValueError(f"law {name!r}: `kind` must be 'spring' or 'dashpot', got {kind!r}")
        if isinstance(parameters, str) or not isinstance(parameters, Iterable):
            raise TypeError(
                f"law {name!r}: `parameters` must be a sequence of names, got {parameters!r}"
            )
        params = tuple(parameters)
        for p in params:
            check_symbol_name(p, f"law {name!r}: parameter")
            if p in ("q", "F"):
                raise ValueError(f"law {name!r}: parameter name {p!r} is reserved for the law")
        duplicates = sorted({p for p in params if params.count(p) > 1})
        if duplicates:
            raise ValueError(f"law {name!r}: parameter(s) listed twice: {', '.join(duplicates)}")
        if not isinstance(description, str):
            raise TypeError(f"law {name!r}: `description` must be a string")
        doms = dict(domains or {})
        for p, d in doms.items():
            if p not in params:
                raise ValueError(f"law {name!r}: domain given for unknown parameter {p!r}")
            if d not in _DOMAINS:
                raise ValueError(
                    f"law {name!r}: domain of {p!r} must be one of {_DOMAINS}, got {d!r}"
                )

        q, F = sp.Symbol("q"), sp.Symbol("F")
        table = {"q": q, "F": F} | {p: sp.Symbol(p) for p in params}
        if isinstance(residual, str):
            expr = self._parse(name, residual, list(table))
        elif isinstance(residual, sp.Basic):
            expr = _canonical(residual, table, name)
        else:
            raise TypeError(
                f"law {name!r}: `residual` must be a string or a sympy expression, "
                f"got {type(residual).__name__}"
            )
        try:
            check_supported(expr)
        except ValueError as exc:
            raise ValueError(f"law {name!r}: {exc}") from None
        if not ({q, F} & expr.free_symbols):
            raise ValueError(f"law {name!r}: the residual {expr} involves neither q nor F")

        for attr, value in (
            ("name", name),
            ("kind", kind),
            ("residual", expr),
            ("parameters", params),
            ("description", description),
            ("domains", MappingProxyType({p: doms.get(p, "real") for p in params})),
            ("q", q),
            ("F", F),
            ("symbols", MappingProxyType({p: table[p] for p in params})),
        ):
            object.__setattr__(self, attr, value)

    @staticmethod
    def _parse(name: str, text: str, symbols: list[str]) -> sp.Expr:
        sides = _EQUALS.split(text)
        try:
            if len(sides) == 1:
                return parse_expression(text, symbols)
            if len(sides) == 2:
                return parse_expression(sides[0], symbols) - parse_expression(sides[1], symbols)
        except ValueError as exc:
            raise ValueError(f"law {name!r}: {exc}") from None
        raise ValueError(f"law {name!r}: residual may hold at most one '=', got {text!r}")

    # -- immutability and identity --------------------------------------------------------
    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"ElementLaw is immutable (cannot set {key!r})")

    def __delattr__(self, key: str) -> None:
        raise AttributeError(f"ElementLaw is immutable (cannot delete {key!r})")

    def _key(self) -> tuple:
        return (self.name, self.kind, self.residual, self.parameters, tuple(self.domains.items()))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, ElementLaw):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def __reduce__(self):  # pickling: rebuild through the checks
        return (
            _rebuild,
            (self.name, self.kind, self.residual, self.parameters,
             self.description, dict(self.domains)),
        )

    # -- display ---------------------------------------------------------------------------
    def equation(self) -> str:
        """The law as text, ``"R = 0"``."""
        return f"{sp.sstr(self.residual, order='none')} = 0"

    def __str__(self) -> str:
        return f"{self.name} ({self.kind}): {self.equation()}"

    def __repr__(self) -> str:
        return (
            f"ElementLaw({self.name!r}, {self.kind!r}, "
            f"{sp.sstr(self.residual, order='none')!r}, {list(self.parameters)!r})"
        )

    def latex(self) -> str:
        """The law as LaTeX, ``R = 0`` (Greek parameter names become Greek letters)."""
        return f"{sp.latex(self.residual)} = 0"

    def _repr_latex_(self) -> str:
        return f"$\\displaystyle {self.latex()}$"

    # -- derivatives and binding ----------------------------------------------------------
    def derivatives(self) -> tuple[sp.Expr, sp.Expr]:
        """``(dR/dq, dR/dF)`` as sympy expressions (kinks not yet resolved)."""
        return sp.diff(self.residual, self.q), sp.diff(self.residual, self.F)

    def bind(self, **params: float) -> BoundLaw:
        """Give every parameter a value; return a :class:`BoundLaw`.

        Raises
        ------
        ValueError
            A parameter missing or unknown, a non-finite value, or a value outside the
            parameter's domain; the message names the law and the parameter.
        TypeError
            A value that is not a real number.
        """
        missing = [p for p in self.parameters if p not in params]
        unknown = sorted(p for p in params if p not in self.parameters)
        if unknown:
            raise ValueError(
                f"law {self.name!r}: unknown parameter(s) {', '.join(unknown)} "
                f"(parameters: {', '.join(self.parameters) or 'none'})"
            )
        if missing:
            raise ValueError(f"law {self.name!r}: missing parameter(s) {', '.join(missing)}")
        values: dict[str, float] = {}
        checks = {"real": as_finite, "positive": as_positive, "nonnegative": as_nonnegative}
        for p in self.parameters:
            try:
                values[p] = checks[self.domains[p]](p, params[p])
            except (ValueError, TypeError) as exc:
                raise type(exc)(f"law {self.name!r}: {exc}") from None
        return BoundLaw(self, values)


def _rebuild(name, kind, residual, parameters, description, domains) -> ElementLaw:
    return ElementLaw(
        name, kind, residual, parameters, description=description, domains=domains
    )


class BoundLaw:
    """An :class:`ElementLaw` with a value for every parameter (immutable).

    Attributes
    ----------
    law : ElementLaw
    params : dict[str, float]
        A copy of the parameter values.
    kernel : callable
        ``kernel(q, F) -> (R, dR/dq, dR/dF)`` on Python floats, compiled on first use
        (once per law and parameter values, see :func:`lumped.codegen.compile_kernel`).

    Examples
    --------
    >>> bound = get_law("linear_spring").bind(k=100.0)
    >>> bound.residual(0.01, 1.0)
    0.0
    >>> bound.kernel(0.02, 1.0)
    (-1.0, -100.0, 1.0)
    """

    __slots__ = ("law", "_params", "_kernel")

    law: ElementLaw

    def __init__(self, law: ElementLaw, params: Mapping[str, float]) -> None:
        if not isinstance(law, ElementLaw):
            raise TypeError(f"`law` must be an ElementLaw, got {type(law).__name__}")
        if set(params) != set(law.parameters):
            raise ValueError(f"law {law.name!r}: parameters must be exactly {law.parameters}")
        values = {p: as_finite(p, params[p]) for p in law.parameters}
        object.__setattr__(self, "law", law)
        object.__setattr__(self, "_params", values)
        object.__setattr__(self, "_kernel", None)

    def __setattr__(self, key: str, value: object) -> None:
        raise AttributeError(f"BoundLaw is immutable (cannot set {key!r})")

    def __reduce__(self):  # pickling: the compiled kernel is rebuilt on first use
        return (BoundLaw, (self.law, dict(self._params)))

    @property
    def params(self) -> dict[str, float]:
        return dict(self._params)

    @property
    def kernel(self) -> Kernel:
        kernel = self._kernel
        if kernel is None:
            kernel = compile_kernel(
                self.law.residual,
                self.law.q,
                self.law.F,
                {self.law.symbols[p]: v for p, v in self._params.items()},
            )
            object.__setattr__(self, "_kernel", kernel)
        return kernel

    def residual(self, q: float, F: float) -> float:
        """``R(q, F)`` with these parameter values."""
        return self.kernel(q, F)[0]

    def expression(self) -> sp.Expr:
        """The residual with the parameter values substituted (a sympy expression)."""
        return self.law.residual.xreplace(
            {self.law.symbols[p]: sp.Float(v) for p, v in self._params.items()}
        )

    def _key(self) -> tuple:
        return (self.law, tuple(self._params.items()))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BoundLaw):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        return hash(self._key())

    def _args(self) -> str:
        return ", ".join(f"{p}={v!r}" for p, v in self._params.items())

    def __repr__(self) -> str:
        return f"get_law({self.law.name!r}).bind({self._args()})"

    def __str__(self) -> str:
        return f"{self.law} with {self._args() or 'no parameters'}"


# ------------------------------------------------------------------------------------------
# Built-in laws
# ------------------------------------------------------------------------------------------


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
