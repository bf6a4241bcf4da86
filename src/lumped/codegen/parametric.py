r"""Parametric binding: a law's code derived once per class of its numbers.

Binding a law to new numbers used to derive everything again in sympy (the prepared
residual and its derivatives, the branches, the kernels' code, the template of the
compiled module): 5-35 ms a law, more than a short run itself. Here a law is derived
once per *class* of its numbers (:func:`class_key`), at the class's first bound law, and
every other law of the class gets those results remade with its own numbers
(:mod:`lumped.codegen.rebinding`): each float literal of the generated code and each
float of the sympy expressions is a constant of the law or the magnitude of one
parameter, read from the bound law. No sympy runs then, and no code is compiled.

That is exact, the code and the numbers a derivation from scratch gives, where the
derivation's shape does not depend on the numbers within the class: no step combines a
parameter with another number into a number of the output, and no decision depends on
a parameter's value beyond what the class fixes. The class fixes each parameter's sign,
the order sympy gives the floats ``+-v_j`` and the law's own constants (its non-integral
numbers and the numbers its comparisons of numbers alone read, ``k > 1``; by value, and
by their binary digits: that order decides the order of the terms of a sum in the code),
and leaves out the values sympy takes apart (zero, whose terms it drops; in an
exponent, an integral value, a product or no power, and ``+-1/2``, a square root;
elsewhere ``1``, ``2`` or ``100`` is a float like any other,
:func:`~lumped.codegen.rewrite.constant_of`). What the class does not fix is decided per
law from its numbers: the steepness of each affine branch against
:data:`~lumped.codegen.stage_forms.STEEP_SPAN` (Bingham's ``gamma tau``; a law whose
branch would be steep is derived from scratch). :func:`admitted` refuses a law that
compares numbers alone other than lone parameters (``gamma*tau > 1``, folded by sympy
without a trace).

A class's first law is derived from scratch. The class is made when a second law has
the same code with the recipes' numbers, the same expressions, branches and bounds with
its floats swapped in, and neither a steep branch (:meth:`LawClass.check`). The recipes
are read by value, so the two laws must differ in every number and have none a
derivation's own constants often equal (an integral value or ``+-1/2``, :func:`plain`:
lifted against ``r = 1``, a Coulomb law's derivative ``1.0`` would pass for ``r``).
Where the second law cannot check the first (a user who edits one number, or the
paper's ``gamma = tau = 1``), the class is made from two laws of our own in it
(:func:`near_in_class`: each number moved by ``1e-9`` to ``1e-7`` of itself), and the second
law made from the class: two derivations, once per class. A class that combines numbers
(Herschel-Bulkley's ``n - 1``, a string's ``1/k``, ``2*gamma``) fails the check; its laws
are derived law by law (at once where its own pair fails, after three failed checks
otherwise; every class of a law once three are given up). Every decision is read from
the law's expression and numbers, never its name. The class key is
:mod:`lumped.codegen.float_keys`; a law remade from its class is
:mod:`lumped.codegen.rebound`.
"""

from __future__ import annotations

import math
import random
from collections.abc import Callable
from dataclasses import replace

import sympy as sp

from .bounded_cache import remember
from .branches import LawBranches
from .float_keys import (
    admitted,
    class_key,
    constant_magnitudes,
    float_content,
    numbers_key,
    parameter_floats,
    sympy_float,
)
from .rebinding import Lifted, codes_of, float_ids, lift_source, lift_text, source_of, swap
from .rebound import LazyBranchInfo, Rebound, ReboundBranches
from .stage_forms import STEEP_SPAN, affine_steepness, affine_steepness_function

__all__ = ["LawClass", "LazyBranchInfo", "Rebound", "ReboundBranches", "admitted", "class_key",
           "derivations", "float_content", "law_class", "sympy_float"]

_DERIVATIONS = [0]
_CLASSES: dict[tuple, LawClass | None] = {}
_FAILURES: dict[tuple, int] = {}
_REBOUND: dict[object, Rebound | None] = {}
#: A class's first law, waiting for a second to be checked against.
_PENDING: dict[tuple, LawClass] = {}
#: Classes whose first law had a number not :func:`plain` (the next law makes the class).
_SEEN: set[tuple] = set()
#: Classes whose own pair was steep (made near a law that is not, :func:`_own_pair`).
_STEEP: set[tuple] = set()
#: Classes given up per law, and the laws given up (every class derived law by law).
_LAW_FAILURES: dict[object, int] = {}
_GIVEN_UP: set = set()
#: How many failed checks of a class before its laws are derived law by law.
_TRIES = 3
#: Bound laws remembered with their rebound results (the oldest half forgotten past it).
_REMEMBERED = 4096


def derivations() -> int:
    """How many classes (:class:`LawClass`) this process has derived."""
    return _DERIVATIONS[0]


class _Derivation:
    """A law derived from scratch at ``values``, every function lifted against them."""

    def __init__(self, law, values: tuple[float, ...]) -> None:
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
            lb.flat_start_for(i)
        self.kernel = self._pair(kernel)
        self.selector = lift_source(source_of(lb.branch), values)
        self.kernels = {key: self._pair(fn) for key, fn in lb._kernels.items()
                        if key[0] != "law"}
        self.flats = {i: lift_source(source_of(fn), values)
                      for i, fn in lb._flats.items() if fn is not None}
        self.guards = {key: (lift_source(source_of(fn), values),
                             tuple(lift_text(code, values) for code in codes_of(fn)))
                       for key, fn in lb._guards.items()}
        self.template = template_from_scratch(law.bind(**named), lb)
        self.template_recipes = lift_text(
            " ".join(repr(v) for v in self.template.values), values)[1]

    def _pair(self, fn: Callable) -> tuple[Lifted, Lifted]:
        return lift_source(source_of(fn), self.values), lift_source(
            source_of(fn.magnitude), self.values)

    def signature(self) -> tuple:
        """What must not change with the numbers: every text and recipe."""
        def sig(lifted: Lifted) -> tuple:
            return lifted.text, lifted.recipes

        return (sig(self.kernel[0]), sig(self.kernel[1]), sig(self.selector),
                {k: (sig(a), sig(b)) for k, (a, b) in self.kernels.items()},
                {k: (sig(a), codes) for k, (a, codes) in self.guards.items()},
                {k: sig(a) for k, a in self.flats.items()},
                self.template.functions, self.template_recipes)

    def bounds(self) -> list:
        """Each leaf's feasibility and the bound of each of its conditions on one
        variable (:func:`~lumped.codegen.guards.feasible_path` compares them) as
        recipes."""
        from .branches import leaves
        from .guards import affine_bound, feasible_path

        out: list = []
        for _, path in leaves(self.expressions[0]):
            out.append(feasible_path(path))
            for cond, want in path:
                bound = affine_bound(cond, want)
                if bound is not None:
                    c = float(bound[1] if bound[1] != -sp.oo else bound[3])
                    j = next((j for j, v in enumerate(self.values) if abs(v) == abs(c)), None)
                    out.append((c,) if j is None else
                               (j, math.copysign(1.0, c * self.values[j])))
        return out


class LawClass:
    """A law derived for one set of its numbers (``values``), every function lifted
    against them: exact for those numbers, and, once :meth:`check` ed against the
    derivation of a second law of the class, for every law of its class (see the module
    notes).

    Attributes
    ----------
    checked : bool
        Made a class by :meth:`check`.
    steep : bool
        The law has a steep branch: its form is chosen by its numbers, no class.
    """

    def __init__(self, law, values: tuple[float, ...]) -> None:
        self.law, self.values = law, values
        d = self._d = _Derivation(law, values)
        trees = list(d.expressions) + [e for info in d.lb.info for e in (
            info.residual, info.dR_dq, info.dR_dF, *(c for c, _ in info.path))]
        self._ids = float_ids(trees, parameter_floats(values))
        self.steep = any(info.steep or info.stage is not None for info in d.lb.info)
        self.checked, self._steepness = False, []

    def check(self, other: LawClass, floats: list) -> None:
        """Make this a class if ``other`` (a law of the same :func:`class_key`, its floats
        ``floats``) has the same code with the recipes' numbers and the same expressions,
        branches and bounds with its floats swapped in; ``ValueError`` if not."""
        law, d, e = self.law, self._d, other._d
        if self.steep or other.steep:
            raise ValueError(f"law {law.name!r}: a steep branch, its form chosen by the "
                             f"numbers")
        if e.signature() != d.signature():
            raise ValueError(f"law {law.name!r}: its code changes with its numbers")
        atoms = self.atoms(floats)
        if tuple(swap(x, atoms) for x in d.expressions) != e.expressions \
                or self.infos(atoms) != e.lb.info or d.bounds() != e.bounds():
            raise ValueError(f"law {law.name!r}: its expressions change with its numbers")
        symbols = [law.symbols[p] for p in law.parameters]
        back = {}
        for p, sym in zip(self.values, symbols, strict=True):
            back[sp.Float(p)], back[sp.Float(-p)] = sym, -sym
        self._steepness = [affine_steepness_function(info.residual.xreplace(back), symbols)
                           for info in d.lb.info
                           if not info.locks and affine_steepness(info.residual) > 0.0]
        self.checked = True
        _DERIVATIONS[0] += 1

    def forward(self, values: tuple[float, ...]) -> bool:
        """Whether every affine branch of the law with ``values`` is not steep, as for the
        class's first law: its steepness below ``STEEP_SPAN (1 - 1e-9)`` (the margin
        covers the rounding of the steepness computed here against a derivation's)."""
        return all(s(*values) < STEEP_SPAN * (1.0 - 1e-9) for s in self._steepness)

    def atoms(self, floats: list) -> dict:
        """The first law's float nodes ``+-v_j`` (by ``id``) -> ``floats``, another law's
        in the same order (:func:`~lumped.codegen.rebinding.swap`)."""
        return {node: floats[i] for node, i in self._ids.items()}

    def infos(self, atoms: dict) -> tuple:
        """The first law's :class:`~lumped.codegen.branches.BranchInfo` with ``atoms``."""
        memo: dict = {}
        return tuple(replace(info, residual=swap(info.residual, atoms, memo),
                             dR_dq=swap(info.dR_dq, atoms, memo),
                             dR_dF=swap(info.dR_dF, atoms, memo),
                             path=tuple((swap(c, atoms, memo), w) for c, w in info.path))
                     for info in self._d.lb.info)


def law_class(bound) -> Rebound | None:
    """``bound``'s results from its class (:class:`Rebound`), or ``None`` when it is
    derived from scratch (see the module notes); remembered per bound law."""
    try:
        hit = _REBOUND[bound]
    except (KeyError, TypeError):
        hit = _rebound(bound)
        try:
            remember(_REBOUND, bound, hit, _REMEMBERED)
        except TypeError:  # unhashable
            pass
    return hit


def _rebound(bound) -> Rebound | None:
    law = getattr(bound, "law", None)
    if law is None or not isinstance(getattr(law, "residual", None), sp.Expr):
        return None
    params = bound.params
    values = tuple(params[p] for p in law.parameters)
    key = numbers_key(law, values)
    if key is None:
        return None
    cls = _CLASSES.get(key)
    if cls is None and key not in _CLASSES and law not in _GIVEN_UP:
        first = _PENDING.get(key)
        if first is None and key not in _SEEN:  # the class's first law
            own = _derived(law, values, key)
            if own is not None and not own.steep:
                if plain(values):
                    _PENDING[key] = own
                else:
                    _SEEN.add(key)
            return None if own is None else Rebound(own, values)
        if first is not None and plain(values) and _apart(first.values, values):
            own = _derived(law, values, key)
            if own is None or own.steep:
                return None if own is None else Rebound(own, values)
            try:
                first.check(own, parameter_floats(values))
            except ValueError:  # the next law is checked against this one, _TRIES times
                _PENDING[key] = own
                _fail(key, law)
            else:
                _CLASSES[key] = first
                del _PENDING[key]
            return Rebound(own, values)
        # a second law of the class that cannot check the first: it shares a number
        # (which cannot tell a parameter's recipe from a number made of it, 1/k, n - 1,
        # or from a constant) or has one a derivation's constants may equal (1, 2, 1/2).
        # The class is made from two laws of our own in it, numbers apart from each
        # other's and from every such value, and this law is made from it
        _PENDING.pop(key, None)
        if key not in _STEEP:
            _own_pair(law, key, values)
        cls = _CLASSES.get(key)
    if cls is not None and cls.forward(values):
        return Rebound(cls, values)
    if cls is not None or key in _CLASSES or law in _GIVEN_UP:
        return None  # steep (derived law by law), or the class given up
    own = _derived(law, values, key)
    if own is not None and not own.steep and key in _STEEP:
        _STEEP.discard(key)  # (one more try, near a law that is not steep)
        _own_pair(law, key, values)
    return None if own is None else Rebound(own, values)


def _derived(law, values: tuple[float, ...], key: tuple) -> LawClass | None:
    """``law`` derived at ``values`` (exact for them), or ``None`` where the derivation
    fails (derived law by law, where it fails as it did before)."""
    try:
        return LawClass(law, values)
    except Exception:  # noqa: BLE001
        _fail(key, law)
        return None


def plain(values: tuple[float, ...]) -> bool:
    """Whether no number of ``values`` is integral or ``+-1/2``, values a derivation's own
    constants often take (``dR/dF = 1``, the 2 of a square's derivative): lifted against
    such a value, a constant would pass for the parameter
    (:func:`~lumped.codegen.rebinding.lift_text`)."""
    return not any(float(v).is_integer() or abs(v) == 0.5 for v in values)


def _apart(a: tuple[float, ...], b: tuple[float, ...]) -> bool:
    """Whether every number of ``a`` differs from ``b``'s in magnitude (a check needs it:
    a number shared by both laws cannot tell a parameter's recipe from a number made of
    it or from a constant)."""
    return all(abs(x) != abs(y) for x, y in zip(a, b, strict=True))


def near_in_class(law, key: tuple, values: tuple[float, ...], salt: int
                  ) -> tuple[float, ...] | None:
    """Numbers of the class ``key`` near ``values``, each magnitude moved by a relative
    ``1e-9`` to ``1e-7`` (a law constant's magnitude kept: the class ties them) and
    :func:`plain`; drawn from ``salt``, the same on every run and machine. ``None`` when
    no draw of 64 has the class's order of floats."""
    constants = constant_magnitudes(law)
    magnitudes = sorted({abs(v) for v in values} - constants)
    rng = random.Random(0x1A3B + salt)
    for _ in range(64):
        moved = {m: m * (1.0 + rng.uniform(1e-9, 1e-7)) for m in magnitudes}
        out = tuple(math.copysign(moved.get(abs(v), abs(v)), v) for v in values)
        if plain(tuple(moved.values())) and numbers_key(law, out) == key:
            return out
    return None


def _own_pair(law, key: tuple, values: tuple[float, ...]) -> None:
    """Make ``key``'s class from two laws of our own in it (:func:`near_in_class`), or
    give it up: numbers apart from each other's and from every constant's, so one checks
    the other as two such laws of a user would (:meth:`LawClass.check`)."""
    a, b = near_in_class(law, key, values, 1), near_in_class(law, key, values, 2)
    if a is None or b is None or not _apart(a, b):
        _fail(key, law)
        return
    try:
        first, second = LawClass(law, a), LawClass(law, b)
    except Exception:  # noqa: BLE001 - derived law by law, as a user's law would be
        _fail(key, law)
        return
    if first.steep or second.steep:  # (near a steep law: tried again near one that is not)
        _STEEP.add(key)
        return
    try:
        first.check(second, parameter_floats(b))
    except ValueError:  # two plain laws apart: the form changes with the numbers
        _CLASSES[key] = None
        _fail(key, law)
    else:
        _CLASSES[key] = first


def _fail(key: tuple, law) -> None:
    """One more failure of ``key``'s class; past :data:`_TRIES` its laws are derived law
    by law, and past :data:`_TRIES` classes given up, every class of ``law`` (a law that
    combines numbers fails in every class)."""
    _FAILURES[key] = _FAILURES.get(key, 0) + 1
    if _FAILURES[key] >= _TRIES:
        _CLASSES[key] = None
        _PENDING.pop(key, None)
    if _CLASSES.get(key, 0) is None:
        failed = _LAW_FAILURES[law] = _LAW_FAILURES.get(law, 0) + 1
        if failed >= _TRIES:
            _GIVEN_UP.add(law)
