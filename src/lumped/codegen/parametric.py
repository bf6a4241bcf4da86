r"""Parametric binding: a law's generated code derived once per class of numbers.

Binding a law to new numbers used to derive everything again in sympy (the prepared
residual and its derivatives, the branches, the kernels' code, the template of the
compiled module): 5-35 ms a law, more than a short run itself. Here a law's derivation
is done once per *class* of its numbers (:func:`class_key`), at the class's first bound
law, and every later law of the class gets those results with its own numbers in place
of the first's (:class:`LawClass`): each float literal of the generated code
(:func:`lift_text`) and each float of the sympy expressions (:meth:`LawClass.atoms`) is
either a constant of the law or the magnitude of one parameter, read from the bound law
(a *recipe*); the functions are made by factories compiled once, so the same source
evaluates the same floats, bit for bit.

That is exact, the code and the numbers a derivation from scratch gives, when no step of
the derivation combines a parameter with another number and no decision in it (a leaf's
feasibility, a steep branch, a sign, an exponent of 2 or 1/2, the order sympy gives the
terms of a sum) depends on a parameter's value beyond its class. :func:`admitted` takes
the laws for which this is shown from the expression alone, read from the law's residual
and never its name: ``R = a F + b q`` with ``a`` and ``b`` each a nonzero number or
``+-`` one parameter (the linear spring ``F - k q``, the Newtonian dashpot ``F - c q``, a
user's law of that shape). Its derivation has one smooth branch, no guard, no lock, no
stage form (its steepness is 0: the force at ``q = 0`` is 0), and its expressions hold
each parameter once, as a coefficient. The class fixes each parameter's sign and how
sympy orders the floats, and leaves out the values sympy takes apart (an integral float
becomes an integer, ``+-1/2`` a square root); a class is also checked once against a
second derivation a few ulps away. Any other law, or value, is derived from scratch as
before; so is every law when the check fails.
"""

from __future__ import annotations

import math
import re
from collections.abc import Callable
from dataclasses import dataclass, replace

import sympy as sp

__all__ = ["LawClass", "admitted", "derivations", "law_class", "lift_source"]

#: A float literal of the generated code (as :mod:`lumped.codegen.templates` reads them).
_FLOAT_LITERAL = re.compile(r"(?<![\w.])(?:\d+\.\d*(?:[eE][+-]?\d+)?|\d+[eE][+-]?\d+)(?![\w.])")
_SLOT = re.compile(r"\b_c(\d+)\b")
_NAMESPACE = {"ArithmeticError": ArithmeticError, "ValueError": ValueError, "max": max,
              "min": min}
_DERIVATIONS = [0]
_CLASSES: dict[tuple, LawClass | None] = {}
_ADMITTED: dict[object, bool] = {}
_LAW_CONSTANTS: dict[object, tuple] = {}


def derivations() -> int:
    """How many parametric derivations (one per law and class) this process has done."""
    return _DERIVATIONS[0]


def admitted(law) -> bool:
    """Whether ``law``'s residual is ``a F + b q`` with ``a``, ``b`` each a nonzero number
    or ``+-`` one parameter, each parameter at most once (see the module notes)."""
    hit = _ADMITTED.get(law)
    if hit is None:
        hit = _ADMITTED[law] = _linear_form(law)
    return hit


def _linear_form(law) -> bool:
    R, q, F = law.residual, law.q, law.F
    params = set(law.symbols.values())
    a, b = R.coeff(F, 1), R.coeff(q, 1)
    if a * F + b * q != R:
        return False
    used = []
    for c in (a, b):
        if c.is_Number:
            if c == 0 or not c.is_finite:
                return False
            continue
        sym = -c if c.could_extract_minus_sign() else c
        if sym not in params:
            return False
        used.append(sym)
    return len(used) == len(set(used))


def _special(value: float) -> bool:
    """A value that sympy or the printer takes apart from the rest of its sign class."""
    return float(value).is_integer() or abs(value) == 0.5


def _constants(law) -> tuple[sp.Float, ...]:
    hit = _LAW_CONSTANTS.get(law)
    if hit is None:
        hit = _LAW_CONSTANTS[law] = tuple(
            sp.Float(c) for c in law.residual.atoms(sp.Number) if not c.is_Integer)
    return hit


def class_key(bound) -> tuple | None:
    """The class of a bound law's numbers, ``None`` when it is derived from scratch.

    ``(law, signs, numeric order, sympy order)``: the sign of each parameter and how
    sympy orders the floats ``+-v_j`` and the law's own non-integral constants, by value
    and by :meth:`sympy.Basic.compare` (which decides the order of the terms of a sum,
    and so the generated code, from the floats' binary digits: ``0.3 |F| + 2.7 |q|`` and
    ``2.7 |F| + 0.3 |q|`` are printed in different orders). ``None`` for a law not
    :func:`admitted`, a special value (:func:`_special`) or two of those floats equal.
    """
    law = getattr(bound, "law", None)
    if law is None or not isinstance(getattr(law, "residual", None), sp.Expr) \
            or not admitted(law):
        return None
    params = bound.params
    values = [params[p] for p in law.parameters]
    if any(_special(v) for v in values):
        return None
    atoms = [sp.Float(s * v) for v in values for s in (1.0, -1.0)] + list(_constants(law))
    if len({float(a) for a in atoms}) < len(atoms):
        return None
    ranks = range(len(atoms))
    return (law, tuple(math.copysign(1.0, v) for v in values),
            tuple(sorted(ranks, key=lambda i: float(atoms[i]))),
            tuple(sorted(ranks, key=lambda i: atoms[i]._hashable_content())))


@dataclass(frozen=True)
class Lifted:
    """One generated function with its float literals lifted: ``text`` names them
    ``_c0, _c1, ...``; ``recipes[k]`` is ``j`` (the magnitude of parameter ``j``) or the
    constant itself (a float); ``make(*values)`` returns the function."""

    text: str
    recipes: tuple
    make: Callable

    def build(self, values: tuple[float, ...]) -> Callable:
        slots = _slots(self.recipes, values)
        fn = self.make(*slots)
        fn.__source__ = _fill(self.text, slots)
        return fn


def _fill(text: str, slots: tuple[float, ...]) -> str:
    """``text`` with each ``_c<k>`` written as the literal of ``slots[k]``."""
    return _SLOT.sub(lambda m: repr(slots[int(m.group(1))]), text)


def _slots(recipes: tuple, values: tuple[float, ...]) -> tuple[float, ...]:
    return tuple(abs(values[r]) if isinstance(r, int) else r for r in recipes)


def lift_text(text: str, values: tuple[float, ...]) -> tuple[str, tuple]:
    """``text`` with its ``k``-th float literal named ``_c<k>`` and the recipes: ``j``
    where the literal is ``|values[j]|``, else the literal's value."""
    recipes: list = []

    def slot(m: re.Match) -> str:
        v = float(m.group(0))
        recipes.append(next((j for j, p in enumerate(values) if abs(p) == v), v))
        return f"_c{len(recipes) - 1}"

    return _FLOAT_LITERAL.sub(slot, text), tuple(recipes)


def lift_source(source: str, values: tuple[float, ...]) -> Lifted:
    """A generated function (its ``source``) lifted against the numbers it was made
    with (:func:`lift_text`), with a factory compiled once that makes it for others."""
    text, recipes = lift_text(source, values)
    head = text.split("\n", 1)[0]
    name = head[len("def "):head.index("(")]
    args = ", ".join(f"_c{k}" for k in range(len(recipes)))
    body = "\n".join("    " + line for line in text.rstrip("\n").split("\n"))
    factory = f"def _make({args}):\n{body}\n    return {name}\n"
    namespace: dict[str, object] = {"math": math, "__builtins__": dict(_NAMESPACE)}
    exec(compile(factory, f"<lumped parametric {name}>", "exec"), namespace)  # noqa: S102
    return Lifted(text, recipes, namespace["_make"])  # type: ignore[arg-type]


class _Derivation:
    """A law derived from scratch at ``values``, every function lifted against them."""

    def __init__(self, law, values: tuple[float, ...]) -> None:
        from .branches import LawBranches
        from .emit import compile_kernel
        from .templates import template_from_scratch

        self.values = values
        named = dict(zip(law.parameters, values, strict=True))
        kernel = compile_kernel(law.residual, law.q, law.F,
                                {law.symbols[p]: v for p, v in named.items()})
        self.expressions = kernel.expressions
        lb = self.lb = LawBranches(kernel.expressions[0])
        for i in range(lb.count):  # every function a run may ask for
            for guard in (True, False):
                lb.source_for(i, guard=guard)
                lb.stage_source_for(i, guard=guard)
            lb.guards_for(i)
            lb.stage_guards_for(i)
        self.kernel = self._pair(kernel)
        self.selector = lift_source(lb.branch.__source__, values)
        self.kernels = {key: self._pair(fn) for key, fn in lb._kernels.items()
                        if key[0] != "law"}
        self.guards = {key: (lift_source(fn.__source__, values),
                             tuple(lift_text(code, values) for code in fn.codes))
                       for key, fn in lb._guards.items()}
        self.template = template_from_scratch(law.bind(**named), lb)
        self.template_recipes = tuple(
            next((j for j, p in enumerate(values) if abs(p) == v), v)
            for v in self.template.values)

    def _pair(self, fn: Callable) -> tuple[Lifted, Lifted]:
        return lift_source(fn.__source__, self.values), lift_source(
            fn.magnitude.__source__, self.values)

    def signature(self) -> tuple:
        """What must not change with the numbers: every text and recipe."""
        def sig(lifted: Lifted) -> tuple:
            return lifted.text, lifted.recipes

        return (sig(self.kernel[0]), sig(self.kernel[1]), sig(self.selector),
                {k: (sig(a), sig(b)) for k, (a, b) in self.kernels.items()},
                {k: (sig(a), codes) for k, (a, codes) in self.guards.items()},
                self.template.functions, self.template_recipes)


class LawClass:
    """A law derived once for a class of numbers (:func:`class_key`), ready to rebind.

    Made from the class's first bound law (values ``p0``) and checked against a second
    derivation at ``p1`` (each value a few ulps away, the same class): the same code with
    every literal that was a parameter's magnitude at ``p0`` that parameter's at ``p1``
    and every other literal unchanged, and the same sympy expressions with ``p0``'s floats
    replaced by ``p1``'s. ``ValueError`` when they differ (the class is then derived from
    scratch, law by law).
    """

    def __init__(self, key: tuple, values: tuple[float, ...]) -> None:
        law = self.law = key[0]
        d = self._d = _Derivation(law, values)
        other = None
        for step in (2.0**-40, -(2.0**-39), 2.0**-38):
            p1 = tuple(v * (1.0 + step) for v in values)
            if class_key(law.bind(**dict(zip(law.parameters, p1, strict=True)))) == key:
                other = _Derivation(law, p1)
                break
        if other is None or other.signature() != d.signature():
            raise ValueError(f"law {law.name!r}: its code changes with its numbers")
        if tuple(e.xreplace(self.atoms(p1)) for e in d.expressions) != other.expressions \
                or self._infos(p1) != other.lb.info:
            raise ValueError(f"law {law.name!r}: its expressions change with its numbers")
        _DERIVATIONS[0] += 1

    def atoms(self, values: tuple[float, ...]) -> dict:
        """The first law's floats -> those of ``values``, for the sympy expressions."""
        out = {}
        for p, v in zip(self._d.values, values, strict=True):
            out[sp.Float(p)] = sp.Float(v)
            out[sp.Float(-p)] = sp.Float(-v)
        return out

    def _infos(self, values: tuple[float, ...]) -> tuple:
        atoms = self.atoms(values)
        return tuple(replace(info, residual=info.residual.xreplace(atoms),
                             dR_dq=info.dR_dq.xreplace(atoms),
                             dR_dF=info.dR_dF.xreplace(atoms),
                             path=tuple((c.xreplace(atoms), w) for c, w in info.path))
                     for info in self._d.lb.info)

    def kernel(self, values: tuple[float, ...]) -> Callable:
        """The bound law's :func:`~lumped.codegen.compile_kernel` (guarded)."""
        kernel = _with_magnitude(self._d.kernel, values)
        atoms = self.atoms(values)
        kernel.expressions = tuple(e.xreplace(atoms) for e in self._d.expressions)
        return kernel

    def branches(self, values: tuple[float, ...]):
        """The bound law's :class:`~lumped.codegen.LawBranches`."""
        from .branches import LawBranches

        d = self._d
        out = LawBranches.__new__(LawBranches)
        out.info = self._infos(values)
        out.count = d.lb.count
        out.branch = d.selector.build(values)
        out._kernels = {}
        for key, pair in d.kernels.items():
            fn = _with_magnitude(pair, values)
            fn.lock_value = d.lb._kernels[key].lock_value
            out._kernels[key] = fn
        out._guards = {}
        for key, (lifted, codes) in d.guards.items():
            fn = lifted.build(values)
            fn.codes = tuple(_fill(text, _slots(r, values)) for text, r in codes)
            out._guards[key] = fn
        return out

    def template(self, values: tuple[float, ...]):
        """The bound law's :class:`~lumped.codegen.templates.LawTemplate`."""
        return replace(self._d.template, values=_slots(self._d.template_recipes, values))


def _with_magnitude(pair: tuple[Lifted, Lifted], values: tuple[float, ...]) -> Callable:
    kernel, magnitude = pair
    fn = kernel.build(values)
    fn.magnitude = magnitude.build(values)
    return fn


def law_class(bound) -> tuple[LawClass, tuple[float, ...]] | None:
    """The :class:`LawClass` of ``bound`` and its parameter values, or ``None`` when the
    law is derived from scratch (see the module notes)."""
    key = class_key(bound)
    if key is None:
        return None
    params = bound.params
    values = tuple(params[p] for p in key[0].parameters)
    hit = _CLASSES.get(key)
    if hit is None and key not in _CLASSES:
        _CLASSES[key] = None  # while its first law is derived, the class derives from scratch
        try:
            hit = _CLASSES[key] = LawClass(key, values)
        except ValueError:
            return None
    if hit is None:
        return None
    return hit, values
