r"""The ``Piecewise`` tree of a prepared law residual, walked arm by arm.

A residual with kinks is, after :func:`~lumped.codegen.rewrite_kinks`, a tree of
``Piecewise`` nodes. Choosing one arm of every node on the way down gives a *leaf*: a
smooth piece and the *path* of ``(condition, truth value)`` pairs that selects it, with the
kernel's rule that the first true condition of a node wins. :func:`leaves` lists every
leaf in the order of the law's arms, feasible or not; :func:`decision_tree` and
:func:`build_selector` turn the same walk into ``branch(q, F) -> int``, plain Python source
that returns the number of the leaf that holds at a point (``-1`` where no condition
does). :mod:`lumped.codegen.branches` numbers the feasible leaves and builds the branches
on them.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable, Iterator

import sympy as sp
from sympy.core.parameters import distribute

from .emit import KernelPrinter

__all__ = ["build_selector", "condition_code", "decision_tree", "leaves"]

#: ``(condition, required truth value)`` pairs that select a branch.
_Path = tuple[tuple[sp.Basic, bool], ...]



def _ready_piecewise(expr: sp.Basic) -> sp.Piecewise | None:
    """The first ``Piecewise`` in pre-order whose conditions hold no ``Piecewise``."""
    for node in sp.preorder_traversal(expr):
        if isinstance(node, sp.Piecewise) and not any(
            c.has(sp.Piecewise) for _, c in node.args
        ):
            return node
    return None


def _arms(pw: sp.Piecewise, path: _Path) -> Iterator[tuple[sp.Expr, _Path]]:
    """Each arm of ``pw`` with the path that selects it (first true condition wins)."""
    before: list[tuple[sp.Basic, bool]] = []
    for value, cond in pw.args:
        if cond is sp.false:
            continue
        if cond is sp.true:
            yield value, path + tuple(before)
            return
        yield value, path + tuple(before) + ((cond, True),)
        before.append((cond, False))


def leaves(residual: sp.Expr) -> list[tuple[sp.Expr, _Path]]:
    """Every leaf of a prepared residual (a smooth piece and the path that selects it,
    feasible or not), in the order of the law's ``Piecewise`` arms."""
    with distribute(False):
        return list(_leaves(residual, ()))


def _leaves(expr: sp.Expr, path: _Path) -> Iterator[tuple[sp.Expr, _Path]]:
    pw = _ready_piecewise(expr)
    if pw is None:
        yield expr, path
        return
    for value, sub in _arms(pw, path):
        yield from _leaves(expr.xreplace({pw: value}), sub)


def decision_tree(expr: sp.Expr):
    """``("leaf",)`` or ``("node", [(cond, subtree), ...], fallback_subtree | None)``."""
    pw = _ready_piecewise(expr)
    if pw is None:
        return ("leaf",)
    arms, fallback = [], None
    for value, cond in pw.args:
        if cond is sp.false:
            continue
        sub = decision_tree(expr.xreplace({pw: value}))
        if cond is sp.true:
            fallback = sub
            break
        arms.append((cond, sub))
    return ("node", arms, fallback)


def build_selector(tree, number: list[int]) -> Callable[[float, float], int]:
    """Compile the decision tree into ``branch(q, F) -> int``: the ``k``-th leaf (in the
    order :func:`leaves` yields them) returns ``number[k]``; ``-1`` where no condition
    holds."""
    printer = KernelPrinter()
    lines = ["def branch(q, F):"]
    counter = itertools.count()

    def emit(node, indent: int) -> None:
        pad = "    " * indent
        if node[0] == "leaf":
            lines.append(f"{pad}return {number[next(counter)]}")
            return
        _, arms, fallback = node
        for k, (cond, sub) in enumerate(arms):
            lines.append(f"{pad}{'if' if k == 0 else 'elif'} {condition_code(cond, printer)}:")
            emit(sub, indent + 1)
        if fallback is not None:
            if arms:
                lines.append(f"{pad}else:")
                emit(fallback, indent + 1)
            else:
                emit(fallback, indent)
        else:
            lines.append(f"{pad}return -1")

    emit(tree, 1)
    if next(counter) != len(number):  # pragma: no cover - the two walks agree by construction
        raise AssertionError("branch selector and leaves disagree")
    source = "\n".join(lines) + "\n"
    namespace: dict[str, object] = {"math": __import__("math"), "__builtins__": {}}
    exec(compile(source, "<lumped branch>", "exec"), namespace)  # noqa: S102 (our own source)
    fn = namespace["branch"]
    fn.__source__ = source  # type: ignore[attr-defined]
    return fn  # type: ignore[return-value]


def condition_code(cond: sp.Basic, printer: KernelPrinter) -> str:
    if cond is sp.true:
        return "True"
    if cond is sp.false:
        return "False"
    if isinstance(cond, sp.core.relational.Relational):
        if cond.rel_op not in ("<", "<=", ">", ">=", "==", "!="):
            raise ValueError(f"unsupported relation {cond}")
        return f"({printer.doprint(cond.lhs)}) {cond.rel_op} ({printer.doprint(cond.rhs)})"
    if isinstance(cond, sp.And | sp.Or):
        joint = " and " if isinstance(cond, sp.And) else " or "
        return "(" + joint.join(condition_code(a, printer) for a in cond.args) + ")"
    if isinstance(cond, sp.Not):
        return f"(not {condition_code(cond.args[0], printer)})"
    if isinstance(cond, sp.ITE):
        c, a, b = (condition_code(x, printer) for x in cond.args)
        return f"({a} if {c} else {b})"
    raise ValueError(f"unsupported condition {cond} ({type(cond).__name__})")
