r"""Generated code and sympy expressions made for one law's numbers, remade for another's.

A law's derivation (:mod:`lumped.codegen.emit`, :mod:`lumped.codegen.branches`) prints its
numbers as float literals (``repr`` of a float). :func:`lift_source` names each literal
``_c<k>`` and records its *recipe*: ``j`` where the literal is the magnitude of the law's
``j``-th parameter (the sign stays in the text), else the literal's value, a constant;
a factory compiled once then makes the function for other numbers
(:meth:`Lifted.build`), whose literals are read from the recipes. The factory's closure
reads the same floats the literals stood for, so it computes the same numbers, bit for
bit, and its ``__source__`` is the text a derivation with those numbers prints (written
when first asked, :func:`source_of`, for the functions a run only calls).
:func:`swap` does the same for a sympy expression: its floats replaced, the tree rebuilt
as it is, unevaluated. :mod:`lumped.codegen.parametric` says when this is exact.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable, Iterator, Sequence
from dataclasses import dataclass

import sympy as sp

__all__ = ["Lifted", "LazyExpressions", "fill", "float_ids", "lift_source", "lift_text", "slots",
           "codes_of", "source_of", "swap"]

#: A float literal of the generated code (as :mod:`lumped.codegen.templates` reads them).
FLOAT_LITERAL = re.compile(r"(?<![\w.])(?:\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")
_SLOT = re.compile(r"\b_c(\d+)\b")
_NAMESPACE = {"ArithmeticError": ArithmeticError, "ValueError": ValueError, "max": max,
              "min": min}


def slots(recipes: tuple, values: tuple[float, ...]) -> tuple[float, ...]:
    """The literals' values for the parameters' ``values`` (see the module notes)."""
    return tuple([abs(values[r]) if type(r) is int else r for r in recipes])


def fill(text: str, literals: tuple[float, ...]) -> str:
    """``text`` with each ``_c<k>`` written as the literal of ``literals[k]``."""
    return _SLOT.sub(lambda m: repr(literals[int(m.group(1))]), text)


def lift_text(text: str, values: tuple[float, ...]) -> tuple[str, tuple]:
    """``text`` with its ``k``-th float literal named ``_c<k>``, and the recipes: ``j``
    where the literal is ``|values[j]|`` (the first such ``j``), else its value."""
    recipes: list = []

    def slot(m: re.Match) -> str:
        v = float(m.group(0))
        recipes.append(next((j for j, p in enumerate(values) if abs(p) == v), v))
        return f"_c{len(recipes) - 1}"

    return FLOAT_LITERAL.sub(slot, text), tuple(recipes)


@dataclass(frozen=True)
class Lifted:
    """One generated function lifted (:func:`lift_source`): ``text`` with ``_c<k>`` for
    its literals, their ``recipes``, and ``make(*literals)``, which returns the function."""

    text: str
    recipes: tuple
    make: Callable

    def build(self, values: tuple[float, ...], *, source: bool = True) -> Callable:
        """The function for the parameters' ``values``, with its ``__source__``; with
        ``source=False`` its text is written only when :func:`source_of` first asks (a
        run calls the function and rarely reads its text: writing it, the literals
        formatted by ``repr``, cost more than making the function)."""
        literals = slots(self.recipes, values)
        fn = self.make(*literals)
        if source:
            fn.__source__ = self.source(literals)
        else:
            fn.__lifted__ = (self, literals)
        return fn

    def source(self, literals: tuple[float, ...]) -> str:
        """The text of the function made from ``literals`` (each written by ``repr``)."""
        return _form(self.text).format(*literals)


def codes_of(guards: Callable) -> tuple[str, ...]:
    """``guards.codes``: the code of each guard of a generated guard function
    (:func:`~lumped.codegen.guards.compile_guards`), written now (and kept on it) for
    one made from its class without them, each ``_c<k>`` of the class's codes written
    as its literal (:class:`~lumped.codegen.rebound.ReboundBranches`)."""
    try:
        return guards.codes  # type: ignore[attr-defined]
    except AttributeError:
        codes, values = guards.__lifted_codes__  # type: ignore[attr-defined]
        out = guards.codes = tuple(  # type: ignore[attr-defined]
            fill(text, slots(r, values)) for text, r in codes)
        return out


def source_of(fn: Callable) -> str:
    """``fn.__source__``: the text of a generated function, written now (and kept on
    ``fn``) for one built without it (:meth:`Lifted.build` ``(source=False)``)."""
    try:
        return fn.__source__  # type: ignore[attr-defined]
    except AttributeError:
        lifted, literals = fn.__lifted__  # type: ignore[attr-defined]
        text = fn.__source__ = lifted.source(literals)  # type: ignore[attr-defined]
        return text


_FORMS: dict[str, str] = {}


def _form(text: str) -> str:
    """``text`` as a format string whose field ``k`` is ``_c<k>``, written by ``repr``
    (the text's braces doubled; made once per text)."""
    hit = _FORMS.get(text)
    if hit is None:
        pieces = _SLOT.split(text)
        hit = _FORMS[text] = "".join(
            p.replace("{", "{{").replace("}", "}}") if k % 2 == 0 else f"{{{p}!r}}"
            for k, p in enumerate(pieces))
    return hit


def lift_source(source: str, values: tuple[float, ...]) -> Lifted:
    """A generated function (its ``source``, made for the parameters' ``values``) lifted
    against those values, with its factory compiled once."""
    text, recipes = lift_text(source, values)
    head = text.split("\n", 1)[0]
    name = head[len("def "):head.index("(")]
    args = ", ".join(f"_c{k}" for k in range(len(recipes)))
    body = "\n".join("    " + line for line in text.rstrip("\n").split("\n"))
    factory = f"def _make({args}):\n{body}\n    return {name}\n"
    namespace: dict[str, object] = {"math": math, "__builtins__": dict(_NAMESPACE)}
    exec(compile(factory, f"<lumped rebound {name}>", "exec"), namespace)  # noqa: S102
    return Lifted(text, recipes, namespace["_make"])  # type: ignore[arg-type]


def float_ids(exprs, floats: list) -> dict[int, int]:
    """``id`` of each float node of ``exprs`` equal to one of ``floats`` -> its index
    (the index :func:`swap` reads; the trees must be kept alive)."""
    out: dict[int, int] = {}
    for expr in exprs:
        for node in sp.preorder_traversal(expr):
            if node.is_Float:
                i = next((i for i, f in enumerate(floats) if f == node), None)
                if i is not None:
                    out[id(node)] = i
    return out


def swap(expr: sp.Basic, atoms: dict[int, sp.Basic], memo: dict | None = None) -> sp.Basic:
    """``expr`` with each float node whose ``id`` is in ``atoms`` replaced (:func:`float_ids`),
    rebuilt node by node unevaluated: the tree a derivation with those floats builds where
    it has the same shape and order (:mod:`lumped.codegen.parametric` checks that).
    ``xreplace`` would evaluate each node again: distribute a number over a sum, merge
    ``Piecewise`` arms that :func:`~lumped.codegen.rewrite.diff_branchwise` keeps apart.
    (Nodes are told apart by ``id``: a float's hash is computed anew at each lookup.)"""
    if memo is None:
        memo = {}
    key = id(expr)
    hit = memo.get(key)
    if hit is not None:
        return hit
    args = expr.args
    if not args:
        out = atoms.get(key, expr)
    else:
        new = tuple(swap(a, atoms, memo) for a in args)
        if all(a is b for a, b in zip(new, args, strict=True)):
            out = expr
        elif isinstance(expr, sp.core.operations.AssocOp):
            out = expr._from_args(new, expr.is_commutative)
        else:
            out = sp.Basic.__new__(type(expr), *new)
            if isinstance(expr, sp.Pow):  # (the slot Pow's constructor sets: printing,
                out.is_commutative = expr.is_commutative  # as_terms read it)
    memo[key] = out
    return out


class LazyExpressions(Sequence):
    """``(R, dR/dq, dR/dF)`` of a rebound kernel (``kernel.expressions``), swapped
    (:func:`swap`) when first read: a run reads the kernel, rarely its expressions."""

    def __init__(self, expressions: tuple, atoms: Callable[[], dict]) -> None:
        self._source, self._atoms, self._swapped = expressions, atoms, None

    def _get(self) -> tuple:
        if self._swapped is None:
            atoms, memo = self._atoms(), {}
            self._swapped = tuple(swap(e, atoms, memo) for e in self._source)
        return self._swapped

    def __getitem__(self, i):
        return self._get()[i]

    def __len__(self) -> int:
        return len(self._source)

    def __iter__(self) -> Iterator:
        return iter(self._get())

    def __eq__(self, other: object) -> bool:
        return tuple(self._get()) == tuple(other) if isinstance(other, Sequence) \
            else NotImplemented

    def __hash__(self) -> int:
        return hash(self._get())

    def __repr__(self) -> str:
        return repr(self._get())
