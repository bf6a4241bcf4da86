r"""A bound law's results remade from its class, no sympy until an expression is read.

:class:`Rebound` is what :func:`lumped.codegen.parametric.law_class` gives for a law of
a checked class: its kernel, branches and template built from the class's lifted code
with the law's numbers (:mod:`lumped.codegen.rebinding`). The branches' flags are the
class's; their sympy expressions are swapped when first read (:class:`LazyBranchInfo`),
and their functions' texts written when first read (:class:`ReboundBranches`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import fields, replace
from typing import TYPE_CHECKING

import sympy as sp

from .branches import BranchInfo, LawBranches
from .float_keys import parameter_floats
from .rebinding import LazyExpressions, Lifted, slots, swap

if TYPE_CHECKING:
    from .parametric import LawClass

__all__ = ["LazyBranchInfo", "Rebound", "ReboundBranches"]


class Rebound:
    """A bound law's results made from its :class:`LawClass` (see the module notes)."""

    def __init__(self, cls: LawClass, values: tuple[float, ...]) -> None:
        self.cls, self.values, self._atoms, self._kernel = cls, values, None, None

    def atoms(self) -> dict:
        """The class's float nodes -> this law's sympy floats (made when first asked)."""
        if self._atoms is None:
            self._atoms = self.cls.atoms(parameter_floats(self.values))
        return self._atoms

    def kernel(self) -> Callable:
        """The law's :func:`~lumped.codegen.compile_kernel` (guarded), made once: a law
        bound anew to the same numbers (a scene rebuilt with one number changed) is
        given this object by :func:`~lumped.codegen.parametric.law_class`, and so the
        same kernel (a pure function of the numbers)."""
        kernel = self._kernel
        if kernel is None:
            kernel = with_magnitude(self.cls._d.kernel, self.values)
            kernel.expressions = LazyExpressions(self.cls._d.expressions, self.atoms)
            self._kernel = kernel
        return kernel

    def branches(self):
        """The law's :class:`~lumped.codegen.branches.LawBranches` (its kernels and guard
        functions made when first asked for)."""
        return ReboundBranches(self)

    def template(self):
        """The law's :class:`~lumped.codegen.templates.LawTemplate`."""
        t = self.cls._d.template  # (its class's, with this law's values)
        return replace(t, values=slots(self.cls._d.template_recipes, self.values))


class ReboundBranches(LawBranches):
    """:class:`~lumped.codegen.branches.LawBranches` of a rebound law: the same methods,
    its functions made from its class's when first asked for (see the module notes). Their
    texts (``__source__``, a guard function's ``codes``) are written only when read
    through :func:`~lumped.codegen.rebinding.source_of` and
    :func:`~lumped.codegen.rebinding.codes_of` (:meth:`source_for` reads them so): a run
    with new numbers calls its branch functions and writes no source text."""

    def __init__(self, rebound: Rebound) -> None:  # no derivation: made from the class
        d = rebound.cls._d
        self._rebound = rebound
        swapped = _Swapped(rebound.atoms)
        self.info = tuple(LazyBranchInfo.of(info, swapped) for info in d.lb.info)
        self.count = d.lb.count
        self.branch = d.selector.build(rebound.values, source=False)
        self._kernels, self._guards, self._flats = {}, {}, {}

    def _kernel(self, i: int, *, guard: bool, stage: bool = False) -> Callable:
        key = (i, guard, stage and self.info[i].stage is not None)
        hit = self._kernels.get(key)
        if hit is None:
            d = self._rebound.cls._d
            hit = self._kernels[key] = with_magnitude(d.kernels[key], self._rebound.values,
                                                      source=False)
            hit.lock_value = d.lb._kernels[key].lock_value
        return hit

    def guards_for(self, i: int) -> Callable:
        return self._guard(self._check(i))

    def flat_start_for(self, i: int) -> Callable | None:
        i = self._check(i)
        if i not in self._flats:
            lifted = self._rebound.cls._d.flats.get(i)
            self._flats[i] = None if lifted is None else lifted.build(self._rebound.values,
                                                                       source=False)
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
            hit = self._guards[key] = lifted.build(values, source=False)
            hit.__lifted_codes__ = (codes, values)  # (written when asked: codes_of)
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
        out.__dict__.update(index=info.index, locks=info.locks, lock_value=info.lock_value,
                            steep=info.steep, stage=info.stage, _source=info,
                            _swapped=swapped)  # (one update: a frozen dataclass's fields)
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


def with_magnitude(pair: tuple[Lifted, Lifted], values: tuple[float, ...], *,
                   source: bool = True) -> Callable:
    """A kernel and its ``.magnitude`` built for ``values`` (their texts written when
    first asked with ``source=False``, :func:`~lumped.codegen.rebinding.source_of`)."""
    kernel, magnitude = pair
    fn = kernel.build(values, source=source)
    fn.magnitude = magnitude.build(values, source=source)
    return fn
