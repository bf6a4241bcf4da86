r"""The smooth branches of a law: which one is active, its kernel, and where it ends.

A law ``R(q, F) = 0`` with kinks is, after :func:`~lumped.codegen.rewrite_kinks`, a tree of
``Piecewise`` nodes.  Choosing one arm of every ``Piecewise`` that matters gives a *branch*:
a smooth residual ``R_i(q, F)`` that holds on the region where the conditions that led to
it hold.  The branches partition the ``(q, F)`` plane exactly as the compiled kernel does
(first true condition wins, ties as in :mod:`lumped.codegen`), so the kernel's value and
Jacobian at a point are those of the branch :meth:`LawBranches.branch` returns there.

What the event model and the adaptive method use:

* :meth:`LawBranches.branch` -- the index of the active branch at ``(q, F)``;
* :meth:`LawBranches.kernel_for` -- the kernel of one branch alone, smooth everywhere it
  is defined, so a step can hold a law on one branch (a *mode*) and stay high order;
* :meth:`LawBranches.guards_for` -- the branch's conditions as continuous *guard
  functions* ``g_j(q, F)``: all ``g_j > 0`` strictly inside the branch's region,
  ``g_j = 0`` on its boundary (where the kernel's tie rule decides), and some
  ``g_j < 0`` outside it.  An event is a sign change of a guard;
* :attr:`BranchInfo.locks` -- the branch fixes ``q`` and leaves ``F`` free
  (``dR_i/dF == 0`` identically, ``R_i`` depends on ``q``): a position lock for a spring
  (a taut string, ``q = L``), a rate lock for a dashpot (sticking, ``q = 0``).  Such an
  element's force is set by the rest of the system.  Detected from the law's expression,
  never from its name.

The leaves and the selector come from the law's ``Piecewise`` tree
(:mod:`lumped.codegen.piecewise_tree`); the guards are built from the branch's conditions
in :mod:`lumped.codegen.guards`, which also drops branches whose conditions contradict
each other; the inverse form of a steep branch comes from
:mod:`lumped.codegen.stage_forms`.

Examples
--------
>>> from lumped.laws import get_law
>>> lb = law_branches(get_law("bingham").bind(gamma=2.0, tau=1.0))
>>> lb.count
3
>>> [lb.info[i].locks for i in range(lb.count)]
[False, False, True]
>>> i = lb.branch(0.0, 0.5)            # stuck: |F| <= tau
>>> lb.info[i].lock_value, lb.guards_for(i)(0.0, 0.5)
(0.0, (1.5, 0.5))
>>> lb.kernel_for(i)(0.0, 0.5)
(0.0, 1.0, 0.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import sympy as sp
from sympy.core.parameters import distribute

from .bounded_cache import remember
from .emit import build_kernel
from .guards import compile_guards, feasible_path
from .piecewise_tree import build_selector, decision_tree, leaves
from .rebinding import source_of
from .rewrite import magnitude_expression
from .stage_forms import (
    affine_inverse_form,
    flat_inverse,
    flat_root,
    inverse_form,
    odd_continuation,
)

__all__ = ["BranchInfo", "LawBranches", "law_branches", "leaves"]

#: ``(condition, required truth value)`` pairs that select a branch.
_Path = tuple[tuple[sp.Basic, bool], ...]

_Q, _F = sp.Symbol("q"), sp.Symbol("F")


@dataclass(frozen=True)
class BranchInfo:
    """One smooth branch of a law.

    Attributes
    ----------
    index : int
        Its index in :attr:`LawBranches.info` (the order of the law's ``Piecewise`` arms).
    residual, dR_dq, dR_dF : sympy.Expr
        ``R_i`` and its derivatives in ``Symbol("q")``, ``Symbol("F")``, parameters
        substituted.
    path : tuple of (condition, bool)
        The conditions, and the truth value each must have, that select this branch.
    locks : bool
        ``R_i`` does not depend on ``F`` but does depend on ``q``: the branch fixes ``q``
        and leaves the force free.
    lock_value : float or None
        The ``q`` a locking branch fixes when ``R_i`` is affine in ``q`` with constant
        coefficients (``q = L``, ``q = 0``); else ``None``.
    steep : bool
        ``dR_i/dF`` holds a negative power of an expression in ``F``: it is unbounded
        where that expression vanishes, e.g. Herschel-Bulkley with ``n < 1`` at its yield
        force (``dq/dF -> infinity``), or a pole. Or the branch is affine in ``F``,
        ``R_i = A(q) + beta F``, with ``dR_i/dF`` large against ``dR_i/dq``: its
        steepness ``S = |beta| |F_0| / |A'(0)|`` (``F_0 = -A(0)/beta``, the force at
        ``q = 0``; :func:`~lumped.codegen.stage_forms.affine_steepness`) is at least
        :data:`~lumped.codegen.stage_forms.STEEP_SPAN` ``= 16``, so that the forward
        form resolves rates no finer than ``S`` ulps: Bingham slipping with ``gamma tau
        >= 16`` (up to the Coulomb limit), a user's law of the same shape. Read from the
        bound law's expression and numbers, never from its name.
    stage : tuple of sympy.Expr or None
        For a steep branch that can be solved for ``F``
        (:func:`~lumped.codegen.stage_forms.inverse_form`,
        :func:`~lumped.codegen.stage_forms.affine_inverse_form`), the residual in its
        *inverse form* ``F - G(q)`` with its derivatives in ``q`` and ``F``: the same
        zero set on the branch, smooth where the forward form is steep
        (Herschel-Bulkley ``n < 1``: ``F = tau + (q/gamma)^(1/n)``, ``dG/dq -> 0`` at
        ``q = 0``; Bingham: ``F = tau + q/gamma``), then the steep power's base ``s F +
        d`` and its value ``w(q)`` on the branch (``base = w^(1/p)``, continued oddly;
        ``p = 1`` for an affine branch, ``base = c (F - F_0)``, ``w = c (G(q) - F_0)``,
        ``c = |beta| / |A'(0)|``: ``w = q`` for Bingham). ``None`` otherwise;
        :meth:`LawBranches.stage_kernel_for` then uses the residual itself.
    """

    index: int
    residual: sp.Expr
    dR_dq: sp.Expr
    dR_dF: sp.Expr
    path: _Path
    locks: bool
    lock_value: float | None
    steep: bool = False
    stage: tuple[sp.Expr, sp.Expr, sp.Expr, sp.Expr, sp.Expr] | None = None


class LawBranches:
    """The branches of one bound law; build with :func:`law_branches` (cached).

    Attributes
    ----------
    count : int
        Number of branches (``1`` for a smooth law).
    info : tuple of BranchInfo
    """

    def __init__(self, residual: sp.Expr) -> None:
        found = leaves(residual)
        keep = [feasible_path(path) for _, path in found]
        if not any(keep):
            raise ValueError(f"no branch of {residual} is admissible")
        infos, number = [], []
        for (expr, path), ok in zip(found, keep, strict=True):
            number.append(len(infos) if ok else -1)
            if not ok:
                continue
            path = tuple(dict.fromkeys(path))  # a condition met twice on the way counts once
            with distribute(False):
                dq, dF = sp.diff(expr, _Q), sp.diff(expr, _F)
            locks = sp.simplify(dF) == 0 and sp.simplify(dq) != 0
            steep = any(isinstance(p, sp.Pow) and p.exp.is_negative and p.base.has(_F)
                        for p in sp.preorder_traversal(dF))
            stage = inverse_form(expr) if steep else (
                None if locks else affine_inverse_form(expr))
            infos.append(BranchInfo(len(infos), expr, dq, dF, path, bool(locks),
                                    _lock_value(expr) if locks else None,
                                    steep or stage is not None, stage))
        self.info: tuple[BranchInfo, ...] = tuple(infos)
        self.count = len(infos)
        self.branch: Callable[[float, float], int] = build_selector(
            decision_tree(residual), number)
        self._kernels: dict[tuple, Callable | None] = {}
        self._guards: dict[int, Callable] = {}
        #: branch -> its stage root or None, read once (:meth:`stage_guards_for`)
        self._stage_roots: dict[int, tuple | None] = {}
        #: branch -> its flat start or None (:meth:`flat_start_for`)
        self._flats: dict[int, Callable | None] = {}

    def kernel_for(self, i: int) -> Callable[[float, float], tuple[float, float, float]]:
        """``kernel(q, F) -> (R_i, dR_i/dq, dR_i/dF)`` of branch ``i`` alone.

        Plain ``math`` code like :func:`~lumped.codegen.compile_kernel` (``nan`` where
        undefined), with ``.magnitude(q, F)`` (the terms' scale, for Newton's residual
        test); its text is :meth:`source_for` (or
        :func:`~lumped.codegen.rebinding.source_of` of it: a law made from its class
        writes the text when first asked).
        """
        return self._kernel(self._check(i), guard=True)

    def source_for(self, i: int, *, guard: bool = False) -> str:
        """The Python source of :meth:`kernel_for` ``(i)``; ``guard=False`` (default) gives
        the bare body without ``try``, the form to hand to numba."""
        return source_of(self._kernel(self._check(i), guard=guard))

    def stage_kernel_for(self, i: int) -> Callable[[float, float], tuple[float, float, float]]:
        """:meth:`kernel_for` ``(i)`` in the form a stage solve takes it: for a steep
        branch with an inverse form (:attr:`BranchInfo.stage`) the kernel of ``F - G(q)``,
        else the branch's own kernel. The two have the same zeros on the branch."""
        return self._kernel(self._check(i), guard=True, stage=True)

    def stage_source_for(self, i: int, *, guard: bool = False) -> str:
        """The Python source of :meth:`stage_kernel_for` ``(i)`` (bare body by default,
        the form to hand to numba)."""
        return source_of(self._kernel(self._check(i), guard=guard, stage=True))

    def stage_guards_for(self, i: int) -> Callable[[float, float], tuple[float, ...]]:
        """:meth:`guards_for` ``(i)`` for the stage solve: on a steep branch with an
        inverse form, a guard that is a positive multiple of the steep power's base
        ``s F + d`` is replaced by ``w(q)`` (:attr:`BranchInfo.stage`), which has the
        same sign on the branch and crosses zero with a nonzero slope in ``q``: the force
        ``F - F_end = w^(1/p) / s`` is flat there (``1/p > 1``), so a located end in
        ``F`` would leave a rate of ``(round-off)^p``, far above the tolerance. So is a
        branch flat at its end (``p > 1``, :func:`~lumped.codegen.stage_forms.flat_root`),
        whose force a stage solve fixes only to its Newton tolerance."""
        i = self._check(i)
        if i in self._stage_roots:
            root = self._stage_roots[i]
        else:
            info = self.info[i]
            root = self._stage_roots[i] = info.stage[3:] if info.stage is not None else (
                None if info.locks else flat_root(info.residual))
        if root is None:
            return self.guards_for(i)
        hit = self._guards.get(-1 - i)
        if hit is None:
            hit = self._guards[-1 - i] = compile_guards(self.info[i].path, root)
        return hit

    def flat_start_for(self, i: int) -> Callable[[float, float], tuple[float, float]] | None:
        """``start(q, F) -> (s F + d, G(q))`` of branch ``i`` when it is flat at its end
        (:func:`~lumped.codegen.stage_forms.flat_inverse`: ``dR/dF = 0`` where the base
        ``s F + d`` vanishes, the force ``G(q)`` on the branch at rate ``q``), else
        ``None``. Read from the branch's expression (a locking branch has none)."""
        i = self._check(i)
        if i not in self._flats:
            info = self.info[i]
            form = None if info.locks or info.stage is not None else flat_inverse(
                info.residual)
            with distribute(False):
                self._flats[i] = None if form is None else build_kernel(
                    "flat_start", ["q", "F"], list(form), guard=True)
        return self._flats[i]

    def guards_for(self, i: int) -> Callable[[float, float], tuple[float, ...]]:
        """``guards(q, F) -> (g_1, ...)``: all ``> 0`` strictly inside branch ``i``, some
        ``< 0`` outside it (see the module notes); ``()`` for a smooth law. The code of
        each guard is :func:`~lumped.codegen.rebinding.codes_of` of the function."""
        i = self._check(i)
        hit = self._guards.get(i)
        if hit is None:
            hit = self._guards[i] = compile_guards(self.info[i].path)
        return hit

    def _kernel(self, i: int, *, guard: bool, stage: bool = False) -> Callable:
        info = self.info[i]
        stage = stage and info.stage is not None
        hit = self._kernels.get((i, guard, stage))
        if hit is None:
            if stage:
                exprs = list(info.stage[:3])
            else:
                with distribute(False):
                    odd = odd_continuation(info.residual, info.path)
                    exprs = ([info.residual, info.dR_dq, info.dR_dF] if odd is info.residual
                             else [odd, sp.diff(odd, _Q), sp.diff(odd, _F)])
            with distribute(False):
                hit = build_kernel("kernel", ["q", "F"], exprs, guard=guard)
                hit.magnitude = build_kernel(  # type: ignore[attr-defined]
                    "magnitude", ["q", "F"], [magnitude_expression(exprs[0])], guard=guard)
            # the q a locking branch holds (q = L): radau5 holds it on the velocity level
            hit.lock_value = info.lock_value if info.locks else None  # type: ignore[attr-defined]
            self._kernels[(i, guard, stage)] = hit
        return hit

    def stage_law_for(self, law_kernel: Callable) -> Callable | None:
        """The whole law in the form a step solve takes it: ``kernel(q, F)`` that picks
        the branch as the law does (:attr:`branch`) and evaluates it by
        :meth:`stage_kernel_for`, so each steep branch with an inverse form in that form
        and every other branch by ``law_kernel`` (the law's own kernel). The same zeros as
        the law; ``None`` when no branch has an inverse form (the law's kernel is the
        answer). Herschel-Bulkley ``n = 0.3`` just past its yield force: the forward form
        ``q = gamma (|F| - tau)^n`` has its root between two floating-point forces once
        ``|F| - tau`` is below ``ulp(tau)`` (rates below ``gamma ulp(tau)^n``, ``1e-5``
        here), so no Newton iterate meets its residual test; the inverse form gives the
        force to its rounding. Has ``.magnitude`` like the kernels."""
        key = ("law", law_kernel)
        if key in self._kernels:
            return self._kernels[key]
        hit = None
        if any(info.stage is not None for info in self.info):
            forms = tuple(self.stage_kernel_for(i) if info.stage is not None else law_kernel
                          for i, info in enumerate(self.info))
            branch = self.branch
            law_mag = getattr(law_kernel, "magnitude", None)

            def kernel(q: float, F: float) -> tuple[float, float, float]:
                return forms[branch(q, F)](q, F)

            def magnitude(q: float, F: float) -> float:
                form = forms[branch(q, F)]
                mag = law_mag if form is law_kernel else form.magnitude
                return math.inf if mag is None else mag(q, F)

            kernel.magnitude = magnitude  # type: ignore[attr-defined]
            hit = kernel
        self._kernels[key] = hit
        return hit

    def _check(self, i: object) -> int:
        if isinstance(i, bool) or not isinstance(i, int) or not 0 <= i < self.count:
            raise ValueError(f"branch index must be an int in [0, {self.count}), got {i!r}")
        return i

    def __repr__(self) -> str:
        parts = ", ".join(f"{b.index}: {b.residual}" + (" [locks]" if b.locks else "")
                          for b in self.info)
        return f"LawBranches({parts})"


_CACHE: dict[object, LawBranches] = {}
#: How many bound laws :data:`_CACHE` keeps (the oldest half is dropped beyond: a sweep
#: of new numbers binds a law per point, whose branches were kept for good).
_REMEMBERED = 4096


def law_branches(bound) -> LawBranches:
    """The :class:`LawBranches` of a bound law (anything with a compiled ``kernel`` whose
    ``expressions[0]`` is the prepared residual, e.g. :class:`lumped.laws.BoundLaw`);
    cached per bound law. A law of a class :mod:`lumped.codegen.parametric` derives once
    gets the class's branches with its own numbers."""
    try:
        hit = _CACHE.get(bound)
    except TypeError:  # unhashable: no cache
        hit = None
    if hit is not None:
        return hit
    parametric = _law_class()(bound)
    if parametric is not None:
        out = parametric.branches()
    else:
        try:
            residual = bound.kernel.expressions[0]
        except AttributeError:
            raise TypeError(
                f"`bound` must be a bound law with a compiled kernel, got "
                f"{type(bound).__name__}") from None
        out = LawBranches(residual)
    try:
        remember(_CACHE, bound, out, _REMEMBERED)
    except TypeError:
        pass
    return out


def _law_class():
    """:func:`lumped.codegen.parametric.law_class` (which imports this module), imported
    once: an import inside a function costs about a microsecond a call."""
    global _LAW_CLASS
    if _LAW_CLASS is None:
        from .parametric import law_class

        _LAW_CLASS = law_class
    return _LAW_CLASS


_LAW_CLASS = None


# ---------------------------------------------------------------------------------------
# Branch data


def _lock_value(expr: sp.Expr) -> float | None:
    with distribute(False):
        slope = sp.diff(expr, _Q)
        if slope.free_symbols or slope == 0:
            return None
        value = -expr.xreplace({_Q: sp.S.Zero}) / slope
    if value.free_symbols:
        return None
    try:
        out = float(value)
    except (TypeError, ValueError):
        return None
    return out + 0.0  # no negative zero
