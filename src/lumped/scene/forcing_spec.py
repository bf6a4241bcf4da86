r"""What a user may give as the external force on a node, made a plain float callable.

:func:`as_forcing` takes a callable (such as :class:`lumped.scene.SineBurst`), a real
number (:class:`ConstantForce`), a sympy expression in ``t`` or a string parsed safely
(an allowlist, never ``eval``), and returns ``f(t: float) -> float``. Positive forces
push the node towards positive ``x`` (the sign convention of :mod:`lumped.scene.network`).
"""

from __future__ import annotations

import numbers
from collections.abc import Callable
from typing import Any

from .._validate import as_finite

__all__ = ["Forcing", "ConstantForce", "as_forcing"]

#: A forcing: time in, force out, on Python floats.
Forcing = Callable[[float], float]


def as_forcing(spec: object, *, where: str = "forcing") -> Forcing:
    """Turn a forcing specification into a callable ``f(t: float) -> float``.

    Accepts a callable (e.g. :class:`lumped.scene.SineBurst`), a real number (a constant
    force), a sympy expression whose only free symbol is ``t``, or a string, which is
    parsed *safely* by :func:`lumped.laws.parser.parse_expression` (an allowlist; strings
    are data, never code).
    """
    if isinstance(spec, numbers.Real) and not isinstance(spec, bool):
        value = as_finite(where, spec)
        return ConstantForce(value)
    if isinstance(spec, str):
        from ..laws.parser import parse_expression

        try:
            spec = parse_expression(spec, ["t"])
        except ValueError as err:
            raise ValueError(f"{where}: {err}") from None
    import sympy

    if isinstance(spec, sympy.Basic):
        free = {sym.name for sym in spec.free_symbols}
        if not free <= {"t"}:
            raise ValueError(
                f"{where}: expression {spec} may only depend on `t`, found {sorted(free - {'t'})}"
            )
        from ..codegen import compile_function

        t_sym = next(iter(spec.free_symbols)) if free else sympy.Symbol("t")
        return _Expression(compile_function(spec, [t_sym]), spec, where)
    if callable(spec):
        return spec  # type: ignore[return-value]
    raise TypeError(
        f"{where} must be a callable, a number, a sympy expression or a string, got {spec!r}"
    )


class ConstantForce:
    __slots__ = ("value",)

    def __init__(self, value: float) -> None:
        self.value = value

    def __call__(self, t: float) -> float:
        return self.value

    def __repr__(self) -> str:
        return f"constant({self.value!r})"


class _Expression:
    """A sympy expression in ``t`` compiled to plain float code (:mod:`lumped.codegen`)."""

    __slots__ = ("fn", "expr", "where")

    def __init__(self, fn: Callable[[float], Any], expr: Any, where: str) -> None:
        self.fn, self.expr, self.where = fn, expr, where

    def __call__(self, t: float) -> float:
        return float(self.fn(t))

    def __repr__(self) -> str:
        return f"expression({self.expr})"

    def breakpoints(self, t0: float, t1: float) -> list[float]:
        """Times in ``(t0, t1)`` where the expression may jump or kink: the real roots of
        the sides of every condition of its kinks (``Piecewise``, ``Abs``, ``Max``, ...)
        that sympy solves in closed form. An adaptive method steps exactly to them."""
        import sympy

        from ..codegen.rewrite import rewrite_kinks

        out: set[float] = set()
        for pw in rewrite_kinks(self.expr).atoms(sympy.Piecewise):
            for _, cond in pw.args:
                for rel in cond.atoms(sympy.core.relational.Relational):
                    gap = rel.lhs - rel.rhs
                    if len(gap.free_symbols) != 1:
                        continue
                    try:
                        roots = sympy.solve(gap, next(iter(gap.free_symbols)))
                    except (NotImplementedError, ValueError):  # pragma: no cover
                        continue
                    out.update(float(r) for r in roots if r.is_real and t0 < float(r) < t1)
        return sorted(out)
