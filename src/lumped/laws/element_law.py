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

A string is parsed by :func:`lumped.laws.parser.parse_expression` (never evaluated as
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

import re
from collections.abc import Iterable, Mapping, Sequence
from types import MappingProxyType
from typing import Literal

import sympy as sp

from .._validate import as_finite, as_nonnegative, as_positive
from ..codegen import Kernel, check_supported, compile_kernel
from ..codegen.parametric import law_class
from .parser import check_symbol_name, parse_expression

__all__ = ["BoundLaw", "ElementLaw", "KINDS"]

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
        "_hash",
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
            ("_hash", None),  # (made when first asked: the law is immutable)
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
        h = self._hash
        if h is None:
            h = hash(self._key())
            object.__setattr__(self, "_hash", h)
        return h

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
        (once per law and parameter values, see :func:`lumped.codegen.compile_kernel`; a
        law :mod:`lumped.codegen.parametric` derives once per class of numbers gets the
        class's kernel with its own numbers).

    Examples
    --------
    >>> from lumped.laws import get_law
    >>> bound = get_law("linear_spring").bind(k=100.0)
    >>> bound.residual(0.01, 1.0)
    0.0
    >>> bound.kernel(0.02, 1.0)
    (-1.0, -100.0, 1.0)
    """

    __slots__ = ("law", "_params", "_kernel", "_hash")

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
        object.__setattr__(self, "_hash", None)  # (made when first asked: immutable)

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
            parametric = law_class(self)
            kernel = parametric.kernel() if parametric is not None else \
                compile_kernel(self.law.residual, self.law.q, self.law.F,
                               {self.law.symbols[p]: v for p, v in self._params.items()})
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

    def latex(self) -> str:
        """The law with its parameter values as LaTeX, ``R(q, F) = 0``."""
        return f"{sp.latex(self.expression())} = 0"

    def _repr_latex_(self) -> str:
        return f"$\\displaystyle {self.latex()}$"

    def _key(self) -> tuple:
        return (self.law, tuple(self._params.items()))

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BoundLaw):
            return NotImplemented
        return self._key() == other._key()

    def __hash__(self) -> int:
        h = self._hash
        if h is None:
            h = hash(self._key())
            object.__setattr__(self, "_hash", h)
        return h

    def _args(self) -> str:
        return ", ".join(f"{p}={v!r}" for p, v in self._params.items())

    def __repr__(self) -> str:
        return f"get_law({self.law.name!r}).bind({self._args()})"

    def __str__(self) -> str:
        return f"{self.law} with {self._args() or 'no parameters'}"
