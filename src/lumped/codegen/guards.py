r"""Guard functions of a law's branch: where a smooth branch holds and where it ends.

A branch of a law (:mod:`lumped.codegen.branches`) is selected by a *path*: conditions of
the law's ``Piecewise`` arms, each required true or false.  :func:`compile_guards` turns a
path into continuous functions ``g_j(q, F)``: all ``g_j > 0`` strictly inside the branch's
region, ``g_j = 0`` on its boundary and some ``g_j < 0`` outside it.  An event of the
adaptive method is a sign change of a guard.

Guards from conditions (``a``, ``b`` the two sides of a relation)::

    a < b,  a <= b   required true  ->  g = b - a       required false -> g = a - b
    a > b,  a >= b   required true  ->  g = a - b       required false -> g = b - a
    And(c1, c2)      required true  ->  the guards of c1 and the guards of c2
    Or(c1, c2)       required true  ->  one guard  max(min(guards of c1), min(guards of c2))
    Not(c)           the guards of c with the requirement flipped
    ITE(c, a, b)     as Or(And(c, a), And(Not(c), b))

``Eq``/``Ne`` conditions hold on sets of measure zero and give no guard.  Branches whose
conditions contradict each other (the same condition required true and false, or
bounds on one variable with an empty intersection, e.g. ``F >= 0`` false and ``F > 0``
true) are dropped.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import sympy as sp

from .emit import KernelPrinter

__all__ = ["affine_bound", "compile_guards", "feasible_path"]

_Q, _F = sp.Symbol("q"), sp.Symbol("F")

#: ``(condition, required truth value)`` pairs that select a branch.
_Path = tuple[tuple[sp.Basic, bool], ...]


def _guard_codes(cond: sp.Basic, want: bool, printer: KernelPrinter) -> list[str] | None:
    """Guard code strings for ``cond == want``: all must be ``> 0``; ``None`` when it
    always holds, ``["-1.0"]`` when it never does."""
    if cond is sp.true or cond is sp.false:
        return None if (cond is sp.true) == want else ["-1.0"]
    if isinstance(cond, sp.Not):
        return _guard_codes(cond.args[0], not want, printer)
    if isinstance(cond, sp.ITE):
        c, a, b = cond.args
        cond = sp.Or(sp.And(c, a, evaluate=False), sp.And(sp.Not(c), b, evaluate=False),
                     evaluate=False)
    if isinstance(cond, sp.And | sp.Or):
        parts = [_guard_codes(a, want, printer) for a in cond.args]
        if isinstance(cond, sp.And) == want:  # conjunction: every part must hold
            out = [g for p in parts if p is not None for g in p]
            return out or None
        if any(p is None for p in parts):  # disjunction with an always-true part
            return None
        alts = [p[0] if len(p) == 1 else f"min({', '.join(p)})" for p in parts]
        return [f"max({', '.join(alts)})"]
    if isinstance(cond, sp.core.relational.Relational):
        if cond.rel_op in ("==", "!="):
            return None
        lhs, rhs = (f"({printer.doprint(side)})" for side in (cond.lhs, cond.rhs))
        less = cond.rel_op in ("<", "<=")
        return [f"{rhs} - {lhs}" if less == want else f"{lhs} - {rhs}"]
    raise ValueError(f"unsupported condition {cond} ({type(cond).__name__})")


def _root_guard(code: str, base: sp.Expr, w: sp.Expr, printer: KernelPrinter) -> str:
    """``code`` (a guard), or the code of ``w`` when the guard is ``c * base``, ``c > 0``,
    and of ``-w`` when ``c < 0`` (``base`` and ``w`` have the same sign on the branch:
    ``base = w^(1/p)`` continued oddly; a Bingham dashpot slipping backwards, ``F < -tau``,
    has the guard ``-(F + tau)`` and ``base = gamma (F + tau) = w = q``)."""
    try:
        g = sp.sympify(code, locals={"q": _Q, "F": _F, "max": sp.Max, "min": sp.Min})
    except (sp.SympifyError, TypeError, SyntaxError):
        return code
    ratio = sp.simplify(g / base)
    if ratio.is_number and ratio.is_positive:
        return printer.doprint(w)
    # the guard's numbers are read back from its code (17 digits), the base's are the
    # law's floats: the same numbers at two precisions, whose ratio sympy keeps symbolic
    # (a yield force 0.024694132280711368 was not replaced: issue 11); the test is on the
    # guard's scale (c d is its constant: an affine base |beta| (F - F_0) is 1e12 F_0)
    c = sp.diff(g, _F) / sp.diff(base, _F)
    if c.is_number and c != 0:
        rest = sp.expand(g - c * base)
        d = base.subs(_F, 0)
        if rest.is_number and d.is_number and abs(float(rest)) <= 1e-12 * (
                1.0 + abs(float(c * d))):
            return printer.doprint(w if c.is_positive else -w)
    return code


def compile_guards(path: _Path, root: tuple[sp.Expr, sp.Expr] | None = None
                    ) -> Callable[[float, float], tuple[float, ...]]:
    """Compile ``guards(q, F) -> tuple`` for a branch's path (``nan`` where undefined);
    with ``root = (base, w)`` a guard that is a positive multiple of ``base`` becomes
    ``w`` (:meth:`~lumped.codegen.branches.LawBranches.stage_guards_for`)."""
    printer = KernelPrinter()
    codes: list[str] = []
    for cond, want in path:
        codes.extend(_guard_codes(cond, want, printer) or [])
    if root is not None:
        codes = [_root_guard(code, *root, printer) for code in codes]
    body = "(" + "".join(f"{c}, " for c in codes) + ")"
    nans = "(" + "math.nan, " * len(codes) + ")"
    source = (f"def guards(q, F):\n    try:\n        return {body}\n"
              f"    except (ArithmeticError, ValueError):\n        return {nans}\n")
    namespace: dict[str, object] = {
        "math": math, "__builtins__": {"max": max, "min": min, "ArithmeticError":
                                       ArithmeticError, "ValueError": ValueError}}
    exec(compile(source, "<lumped guards>", "exec"), namespace)  # noqa: S102 (our own source)
    fn = namespace["guards"]
    fn.__source__ = source  # type: ignore[attr-defined]
    fn.codes = tuple(codes)  # type: ignore[attr-defined]
    return fn  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------
# Pruning: paths whose conditions contradict each other


def affine_bound(cond: sp.Basic, want: bool):
    """``(symbol, lo, lo_closed, hi, hi_closed)`` when ``cond == want`` is an interval of
    one symbol (``a s + b  op  0`` with numbers ``a != 0, b``); else ``None``."""
    if not isinstance(cond, sp.core.relational.Relational) or cond.rel_op in ("==", "!="):
        return None
    diff = sp.expand(cond.lhs - cond.rhs)
    syms = diff.free_symbols
    if len(syms) != 1:
        return None
    (s,) = syms
    a, b = diff.coeff(s, 1), diff.xreplace({s: sp.S.Zero})
    if not (a.is_Number and b.is_Number) or a == 0 or sp.expand(diff - a * s - b) != 0:
        return None
    op = cond.rel_op
    if not want:
        op = {"<": ">=", "<=": ">", ">": "<=", ">=": "<"}[op]
    if a < 0:
        op = {"<": ">", "<=": ">=", ">": "<", ">=": "<="}[op]
    c = -b / a  # s op c
    inf = sp.oo
    if op in ("<", "<="):
        return s, -inf, False, c, op == "<="
    return s, c, op == ">=", inf, False


def feasible_path(path: _Path) -> bool:
    """``False`` when the path's conditions contradict each other: one condition required
    both true and false, or bounds on one variable with an empty intersection (e.g.
    ``F >= 0`` false and ``F > 0`` true); such a branch can never be active."""
    seen: dict[sp.Basic, bool] = {}
    box: dict[sp.Symbol, list] = {}
    for cond, want in path:
        if seen.setdefault(cond, want) != want:
            return False
        bound = affine_bound(cond, want)
        if bound is None:
            continue
        s, lo, loc, hi, hic = bound
        cur = box.setdefault(s, [-sp.oo, False, sp.oo, False])
        if lo > cur[0] or (lo == cur[0] and not loc):
            cur[0], cur[1] = lo, loc
        if hi < cur[2] or (hi == cur[2] and not hic):
            cur[2], cur[3] = hi, hic
        if cur[0] > cur[2] or (cur[0] == cur[2] and not (cur[1] and cur[3])):
            return False
    return True
