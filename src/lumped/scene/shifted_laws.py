r"""Element laws read at ``q + o_e``: the view a solver takes of an element on a moving
support (:mod:`lumped.scene.supports`).

A :class:`SupportFrame <lumped.scene.supports.SupportFrame>` hands each element on a
support a :class:`ShiftedLaw`: the bound law with its kernel, magnitude and branches
(:class:`ShiftedBranches`: every kernel, guard and branch selector) evaluated at
``q + offsets[e]``, the offset ``o_e`` of the frame's clock. :func:`branches_of` gives the
branches of a law, shifted or not.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from typing import Any

__all__ = ["ShiftedLaw", "ShiftedBranches", "branches_of", "shifted_by"]


class _ShiftedKernel:
    """``kernel(q + offsets[e], F)``, with the ``magnitude`` of the residual's terms
    shifted the same way where the kernel has one.

    It has no sympy ``expressions``: the branch analysis
    (:func:`lumped.codegen.branches.law_branches`) declines it, so whatever reads
    branches off it falls back to the shifted kernel's values at the point (e.g.
    :func:`lumped.solvers.nonsmooth.impacts.lock_state`), never to the law's branches in
    the unshifted argument."""

    __slots__ = ("kernel", "offsets", "e", "magnitude")

    def __init__(self, kernel: Any, offsets: list[float], e: int) -> None:
        self.kernel, self.offsets, self.e = kernel, offsets, e
        mag = getattr(kernel, "magnitude", None)
        if mag is not None:
            self.magnitude = _shifted_magnitude(kernel, mag, offsets, e)

    def __call__(self, q: float, F: float) -> tuple[float, float, float]:
        return self.kernel(q + self.offsets[self.e], F)


class ShiftedLaw:
    """A bound law whose kernel reads ``q + o_e(t)`` (see the module notes)."""

    __slots__ = ("bound", "law", "params", "kernel", "offsets", "e", "_branches")

    def __init__(self, bound: Any, offsets: list[float], e: int) -> None:
        self.bound, self.law, self.params = bound, bound.law, bound.params
        self.kernel = _ShiftedKernel(bound.kernel, offsets, e)
        self.offsets, self.e = offsets, e
        self._branches: ShiftedBranches | None = None

    def branches(self) -> ShiftedBranches:
        """The law's branches in the shifted argument (:class:`ShiftedBranches`)."""
        if self._branches is None:
            from ..codegen.branches import law_branches

            self._branches = ShiftedBranches(law_branches(self.bound), self.bound,
                                             self.offsets, self.e)
        return self._branches

    def __repr__(self) -> str:
        return f"shifted({self.bound!r})"


def _shifted(fn: Callable, offsets: list[float], e: int) -> Callable:
    """``fn(q + offsets[e], F)``, with ``fn``'s ``magnitude`` shifted the same way."""
    def shifted(q: float, F: float):
        return fn(q + offsets[e], F)

    mag = getattr(fn, "magnitude", None)
    if mag is not None:
        shifted.magnitude = _shifted_magnitude(fn, mag, offsets, e)  # type: ignore[attr-defined]
    return shifted


def shifted_by(fn: Callable, offset: float) -> Callable:
    """``fn(q + offset, F)`` for a fixed ``offset`` (a kernel, guard or selector), with
    ``fn``'s ``magnitude`` shifted the same way (the rounding of the sum included)."""
    return _shifted(fn, [offset], 0)


def _shifted_magnitude(kernel: Callable, mag: Callable, offsets: list[float], e: int
                       ) -> Callable[[float, float], float]:
    """The magnitude of the terms of ``R(q + o_e, F)``: the law's at the shifted point
    plus ``|dR/dq| |o_e|``, the rounding of the sum ``q + o_e`` (a string taut on a
    support at ``x_s ~ 0.2`` has ``q + o_e = L`` only to ``ulp(0.2)``, beyond the round-off
    of ``L`` itself: Newton's round-off test must see it)."""
    def magnitude(q: float, F: float) -> float:
        o = offsets[e]
        M = mag(q + o, F)
        return M if o == 0.0 else M + abs(kernel(q + o, F)[1] * o)

    return magnitude


class ShiftedBranches:
    r"""The branches of an element's law on a support, in the node states: each kernel,
    guard and the branch selector of :class:`~lumped.codegen.branches.LawBranches` called
    at ``(q + o_e, F)``, ``o_e`` read from the frame's offsets at the call (the clock's
    time, :meth:`SupportFrame.at_time`; ``0`` when :meth:`SupportFrame.bare`).

    ``info`` and ``count`` are the law's, except that a locking branch has no
    ``lock_value`` (its lock ``q = L - o_e(t)`` in the node states moves with the
    support; see the module notes); its kernels keep it, with the law's own kernel as
    ``bare``, for ``radau5``'s stage system."""

    def __init__(self, lb: Any, bound: Any, offsets: list[float], e: int) -> None:
        self.lb, self.bound, self.offsets, self.e = lb, bound, offsets, e
        self.count = lb.count
        self.info = tuple(dataclasses.replace(info, lock_value=None) for info in lb.info)
        self.branch = _shifted(lb.branch, offsets, e)
        self._made: dict[tuple, Callable | None] = {}

    def _get(self, key: tuple, make: Callable[[], Callable | None]) -> Callable | None:
        if key not in self._made:
            fn = make()
            self._made[key] = None if fn is None else _shifted(fn, self.offsets, self.e)
            if getattr(fn, "lock_value", None) is not None:
                # a locking branch's kernel: radau5's stage system holds its lock on the
                # velocity level, q_n + o_e(t) = L read with the law's own kernel ``bare``
                self._made[key].lock_value = fn.lock_value  # type: ignore[union-attr]
                self._made[key].bare = fn  # type: ignore[union-attr]
        return self._made[key]

    def kernel_for(self, i: int) -> Callable:
        return self._get(("kernel", i), lambda: self.lb.kernel_for(i))

    def stage_kernel_for(self, i: int) -> Callable:
        return self._get(("stage", i), lambda: self.lb.stage_kernel_for(i))

    def guards_for(self, i: int) -> Callable:
        return self._get(("guards", i), lambda: self.lb.guards_for(i))

    def stage_guards_for(self, i: int) -> Callable:
        return self._get(("stage_guards", i), lambda: self.lb.stage_guards_for(i))

    def stage_law_for(self, law_kernel: Callable) -> Callable | None:
        """The law's :meth:`~lumped.codegen.branches.LawBranches.stage_law_for` on its own
        kernel, shifted; ``None`` as there (the caller's ``law_kernel``, the element's
        shifted kernel, is then the answer)."""
        return self._get(("law",), lambda: self.lb.stage_law_for(self.bound.kernel))

    def __repr__(self) -> str:
        return f"shifted({self.lb!r}, element {self.e})"


def branches_of(law: Any) -> Any:
    """:func:`~lumped.codegen.branches.law_branches` of ``law``, or the
    :class:`ShiftedBranches` of a law shifted by a :class:`SupportFrame`."""
    if isinstance(law, ShiftedLaw):
        return law.branches()
    if not _LAW_BRANCHES:  # (imported once: an import in a function costs ~1 us a call)
        from ..codegen.branches import law_branches

        _LAW_BRANCHES.append(law_branches)
    return _LAW_BRANCHES[0](law)


#: :func:`lumped.codegen.branches.law_branches`, once imported (codegen comes after
#: scene in the layers: imported on first use).
_LAW_BRANCHES: list[Callable[[Any], Any]] = []
