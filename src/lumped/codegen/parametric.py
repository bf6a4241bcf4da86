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
the order sympy gives the floats ``+-v_j`` and the law's own constants (by value, and by
their binary digits: that order decides the order of the terms of a sum in the code),
and leaves out the values sympy takes apart (an integral float becomes an integer,
``+-1/2`` a square root). What the class does not fix is decided per law from its
numbers: the steepness of each affine branch against
:data:`~lumped.codegen.stage_forms.STEEP_SPAN` (Bingham's ``gamma tau``; a law whose
branch would be steep is derived from scratch). :func:`admitted` refuses a law that
compares numbers alone other than lone parameters (``gamma*tau > 1``, folded by sympy
without a trace). The first two laws of a class are derived from scratch, as before;
the class is made when the second has the same code with the recipes' numbers, the
same expressions, branches and bounds with its floats swapped in, and neither a steep
branch (:meth:`LawClass.check`). A class that combines numbers (Herschel-Bulkley's
``n - 1``, a string's ``1/k``) fails the check, and after three failures its laws are
derived law by law. Every decision is read from the law's expression and numbers,
never its name.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import fields, replace

import sympy as sp

from .branches import BranchInfo, LawBranches
from .rebinding import LazyExpressions, Lifted, fill, float_ids, lift_source, lift_text, slots, swap
from .stage_forms import STEEP_SPAN, affine_steepness, affine_steepness_function

__all__ = ["LawClass", "LazyBranchInfo", "Rebound", "ReboundBranches", "admitted", "class_key",
           "derivations", "law_class"]

_DERIVATIONS = [0]
_CLASSES: dict[tuple, LawClass | None] = {}
_FAILURES: dict[tuple, int] = {}
_ADMITTED: dict[object, bool] = {}
_LAW_CONSTANTS: dict[object, tuple] = {}
_REBOUND: dict[object, Rebound | None] = {}
#: A class's first law, waiting for a second to be checked against.
_PENDING: dict[tuple, LawClass] = {}
#: How many failed checks of a class before its laws are derived law by law.
_TRIES = 3
#: Bound laws remembered with their rebound results (the oldest half forgotten past it).
_REMEMBERED = 4096


def derivations() -> int:
    """How many classes (:class:`LawClass`) this process has derived."""
    return _DERIVATIONS[0]


def admitted(law) -> bool:
    """Whether every comparison ``law``'s residual makes of numbers alone (an argument of
    ``Min``, ``Max``, ``Abs``, ``sign``, ``Heaviside`` or of a relation without ``q`` and
    ``F``) is of a number or ``+-`` a lone parameter, which the class's order of floats
    decides (see the module notes)."""
    hit = _ADMITTED.get(law)
    if hit is None:
        hit = _ADMITTED[law] = _lone_comparisons(law)
    return hit


def _lone_comparisons(law) -> bool:
    kinds = (sp.Min, sp.Max, sp.Abs, sp.sign, sp.Heaviside, sp.core.relational.Relational)
    params = set(law.symbols.values())
    for node in sp.preorder_traversal(law.residual):
        if not isinstance(node, kinds):
            continue
        for arg in node.args:
            if arg.has(law.q, law.F) or arg.is_Number:
                continue
            if (-arg if arg.could_extract_minus_sign() else arg) not in params:
                return False
    return True


def _special(value: float) -> bool:
    """A value sympy or the printer takes apart from the rest of its sign class (or not
    finite: derived from scratch)."""
    return not math.isfinite(value) or float(value).is_integer() or abs(value) == 0.5


def _constants(law) -> tuple[sp.Float, ...]:
    hit = _LAW_CONSTANTS.get(law)
    if hit is None:
        hit = _LAW_CONSTANTS[law] = tuple(
            sp.Float(c) for c in law.residual.atoms(sp.Number) if not c.is_Integer)
    return hit


_CONSTANT_KEYS: dict[object, tuple[list, list]] = {}


def _constant_keys(law) -> tuple[list, list]:
    """The law's constants (:func:`_constants`) by value and by sympy's order (once)."""
    hit = _CONSTANT_KEYS.get(law)
    if hit is None:
        consts = _constants(law)
        hit = _CONSTANT_KEYS[law] = ([float(c) for c in consts],
                                     [c._hashable_content() for c in consts])
    return hit


def float_content(x: float) -> tuple:
    """``sympy.Float(x)._hashable_content()`` of a finite nonzero float ``x``, in plain
    Python: ``((sign, man, exp, bc), 53)``, ``|x| = man 2^exp`` with ``man`` odd of ``bc``
    bits (mpmath's normal form at the 53 bits of a double), what sympy orders its floats
    by (:func:`class_key`)."""
    n, d = abs(x).as_integer_ratio()  # d a power of 2
    tz = (n & -n).bit_length() - 1
    man = n >> tz
    return (int(x < 0.0), man, tz - (d.bit_length() - 1), man.bit_length()), 53


def _key(law, values: tuple[float, ...]) -> tuple | None:
    """:func:`class_key` of ``law`` bound to ``values``, in plain floats (no sympy)."""
    if not admitted(law) or any(_special(v) for v in values):
        return None
    pm = [s * v for v in values for s in (1.0, -1.0)]
    by_value, by_sympy = _constant_keys(law)
    return (law, tuple(math.copysign(1.0, v) for v in values), _dense_ranks(pm + by_value),
            _dense_ranks([float_content(x) for x in pm] + by_sympy))


def sympy_float(x: float) -> sp.Float:
    """``sympy.Float(x)`` of a finite nonzero float ``x``, made from its content
    (:func:`float_content`) without sympy's parsing of the number (about 10 times
    faster; the same object content)."""
    mpf, prec = float_content(x)
    return _FLOAT._new(mpf, prec, zero=False)


_FLOAT = sp.Float


def _floats(values: tuple[float, ...]) -> list:
    """The sympy floats ``+v_j, -v_j`` of the parameters' ``values``, in the key's order
    (finite and nonzero: :func:`_special` values have no class)."""
    return [sympy_float(s * v) for v in values for s in (1.0, -1.0)]


def class_key(bound) -> tuple | None:
    """The class of a bound law's numbers, ``None`` when it is derived from scratch.

    ``(law, signs, order by value, order by sympy)`` of the floats ``+-v_j`` and the
    law's non-integral constants, equal floats in one place; ``None`` for a law not
    :func:`admitted`, a value :func:`_special`, or a law not given as a sympy residual.
    """
    law = getattr(bound, "law", None)
    if law is None or not isinstance(getattr(law, "residual", None), sp.Expr):
        return None
    params = bound.params
    return _key(law, tuple(params[p] for p in law.parameters))


def _dense_ranks(keys: list) -> tuple[int, ...]:
    """Each key's place among the distinct keys (equal keys share a place)."""
    order = {k: r for r, k in enumerate(sorted(set(keys)))}
    return tuple(order[k] for k in keys)


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
        self.selector = lift_source(lb.branch.__source__, values)
        self.kernels = {key: self._pair(fn) for key, fn in lb._kernels.items()
                        if key[0] != "law"}
        self.flats = {i: lift_source(fn.__source__, values)
                      for i, fn in lb._flats.items() if fn is not None}
        self.guards = {key: (lift_source(fn.__source__, values),
                             tuple(lift_text(code, values) for code in fn.codes))
                       for key, fn in lb._guards.items()}
        self.template = template_from_scratch(law.bind(**named), lb)
        self.template_recipes = lift_text(
            " ".join(repr(v) for v in self.template.values), values)[1]

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
        self._ids = float_ids(trees, _floats(values))
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


class Rebound:
    """A bound law's results made from its :class:`LawClass` (see the module notes)."""

    def __init__(self, cls: LawClass, values: tuple[float, ...]) -> None:
        self.cls, self.values, self._atoms = cls, values, None

    def atoms(self) -> dict:
        """The class's float nodes -> this law's sympy floats (made when first asked)."""
        if self._atoms is None:
            self._atoms = self.cls.atoms(_floats(self.values))
        return self._atoms

    def kernel(self) -> Callable:
        """The law's :func:`~lumped.codegen.compile_kernel` (guarded)."""
        kernel = _with_magnitude(self.cls._d.kernel, self.values)
        kernel.expressions = LazyExpressions(self.cls._d.expressions, self.atoms)
        return kernel

    def branches(self):
        """The law's :class:`~lumped.codegen.branches.LawBranches` (its kernels and guard
        functions made when first asked for)."""
        return ReboundBranches(self)

    def template(self):
        """The law's :class:`~lumped.codegen.templates.LawTemplate`."""
        d = self.cls._d
        return replace(d.template, values=slots(d.template_recipes, self.values))


class ReboundBranches(LawBranches):
    """:class:`~lumped.codegen.branches.LawBranches` of a rebound law: the same methods,
    its functions made from its class's when first asked for (see the module notes)."""

    def __init__(self, rebound: Rebound) -> None:  # no derivation: made from the class
        d = rebound.cls._d
        self._rebound = rebound
        swapped = _Swapped(rebound.atoms)
        self.info = tuple(LazyBranchInfo.of(info, swapped) for info in d.lb.info)
        self.count = d.lb.count
        self.branch = d.selector.build(rebound.values)
        self._kernels, self._guards, self._flats = {}, {}, {}

    def _kernel(self, i: int, *, guard: bool, stage: bool = False) -> Callable:
        key = (i, guard, stage and self.info[i].stage is not None)
        hit = self._kernels.get(key)
        if hit is None:
            d = self._rebound.cls._d
            hit = self._kernels[key] = _with_magnitude(d.kernels[key], self._rebound.values)
            hit.lock_value = d.lb._kernels[key].lock_value
        return hit

    def guards_for(self, i: int) -> Callable:
        return self._guard(self._check(i))

    def flat_start_for(self, i: int) -> Callable | None:
        i = self._check(i)
        if i not in self._flats:
            lifted = self._rebound.cls._d.flats.get(i)
            self._flats[i] = None if lifted is None else lifted.build(self._rebound.values)
        return self._flats[i]

    def stage_guards_for(self, i: int) -> Callable:
        # the class's law has its own stage guards where LawBranches.stage_guards_for
        # made them (a steep branch's inverse form, a branch flat at its end)
        i = self._check(i)
        return self._guard(-1 - i if -1 - i in self._rebound.cls._d.guards else i)

    def _guard(self, key: int) -> Callable:
        hit = self._guards.get(key)
        if hit is None:
            lifted, codes = self._rebound.cls._d.guards[key]
            values = self._rebound.values
            hit = self._guards[key] = lifted.build(values)
            hit.codes = tuple(fill(text, slots(r, values)) for text, r in codes)
        return hit


class _Swapped:
    """One rebound law's :func:`~lumped.codegen.rebinding.swap` of its class's
    expressions, with one memo for all of its branches (as :meth:`LawClass.infos`)."""

    def __init__(self, atoms: Callable[[], dict]) -> None:
        self.atoms, self.memo = atoms, {}

    def __call__(self, expr: sp.Basic) -> sp.Basic:
        return swap(expr, self.atoms(), self.memo)


_LAZY = ("residual", "dR_dq", "dR_dF", "path")
_FIELDS = tuple(f.name for f in fields(BranchInfo))


class LazyBranchInfo(BranchInfo):
    """A rebound law's :class:`~lumped.codegen.branches.BranchInfo`: ``index``,
    ``locks``, ``lock_value``, ``steep`` and ``stage`` are its class's (the class fixes
    them), and its sympy expressions ``residual``, ``dR_dq``, ``dR_dF`` and ``path`` are
    the class's with the law's floats swapped in when first read (a run reads the
    branches' flags and compiled functions, rarely their expressions; no sympy runs for
    new numbers until then). Equal to the :class:`BranchInfo` of a derivation from
    scratch where :meth:`LawClass.infos` is."""

    @classmethod
    def of(cls, info: BranchInfo, swapped: _Swapped) -> LazyBranchInfo:
        out = object.__new__(cls)
        for name in ("index", "locks", "lock_value", "steep", "stage"):
            object.__setattr__(out, name, getattr(info, name))
        object.__setattr__(out, "_source", info)
        object.__setattr__(out, "_swapped", swapped)
        return out

    def __getattr__(self, name: str):  # only for attributes not set: the lazy ones
        if name not in _LAZY or "_source" not in self.__dict__:
            raise AttributeError(name)
        value, swapped = getattr(self._source, name), self._swapped
        value = tuple((swapped(c), w) for c, w in value) if name == "path" else swapped(value)
        object.__setattr__(self, name, value)
        return value

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, BranchInfo):
            return NotImplemented
        return all(getattr(self, f) == getattr(other, f) for f in _FIELDS)

    def __hash__(self) -> int:
        return hash(tuple(getattr(self, f) for f in _FIELDS))


def _with_magnitude(pair: tuple[Lifted, Lifted], values: tuple[float, ...]) -> Callable:
    kernel, magnitude = pair
    fn = kernel.build(values)
    fn.magnitude = magnitude.build(values)
    return fn


def law_class(bound) -> Rebound | None:
    """``bound``'s results from its class (:class:`Rebound`), or ``None`` when it is
    derived from scratch (see the module notes); remembered per bound law."""
    try:
        hit = _REBOUND[bound]
    except (KeyError, TypeError):
        hit = _rebound(bound)
        try:
            if len(_REBOUND) >= _REMEMBERED:
                for old in list(_REBOUND)[:_REMEMBERED // 2]:
                    del _REBOUND[old]
            _REBOUND[bound] = hit
        except TypeError:  # unhashable
            pass
    return hit


def _rebound(bound) -> Rebound | None:
    law = getattr(bound, "law", None)
    if law is None or not isinstance(getattr(law, "residual", None), sp.Expr):
        return None
    params = bound.params
    values = tuple(params[p] for p in law.parameters)
    key = _key(law, values)
    if key is None:
        return None
    cls = _CLASSES.get(key)
    if cls is not None:
        return Rebound(cls, values) if cls.forward(values) else None
    if key in _CLASSES:  # given up: derived law by law
        return None
    try:
        own = LawClass(law, values)  # this law's derivation, exact for it
    except Exception:  # noqa: BLE001 - derived law by law, where it fails as it did before
        _fail(key)
        return None
    first = _PENDING.get(key)
    if not own.steep:
        if first is None:
            _PENDING[key] = own
        elif any(abs(a) == abs(b) for a, b in zip(first.values, values, strict=True)):
            # a number shared by both laws cannot tell a parameter's recipe from a
            # number made of it (1/k, n - 1) or from a constant: not a check; the first
            # law waits for one that differs in every number
            pass
        else:
            try:
                first.check(own, _floats(values))
            except ValueError:  # the next law is checked against this one, _TRIES times
                _PENDING[key] = own
                _fail(key)
            else:
                _CLASSES[key] = first
                del _PENDING[key]
    return Rebound(own, values)


def _fail(key: tuple) -> None:
    """One more failure of ``key``'s class; past :data:`_TRIES` its laws are derived law
    by law."""
    _FAILURES[key] = _FAILURES.get(key, 0) + 1
    if _FAILURES[key] >= _TRIES:
        _CLASSES[key] = None
        _PENDING.pop(key, None)
