r"""A compiled scene's arrays: its structure (shared by every scene of that structure)
and its numbers (read per scene).

:func:`structure_arrays` makes the arrays that depend only on a scene's *structure* (the
element ends, which elements are springs, each element's law template and where its
constants start, where the springs' locking branches are); :func:`with_numbers` puts a
scene's numbers on them (its masses, its laws' constants, the values its locking
branches lock) as a :class:`JitScene`; :func:`kept_values` reads the laws' constants of a
scene whose laws have a kept structure's templates, without making anything anew.
:func:`lumped.codegen.jit.jit_scene` (a structure's generated module) and
:func:`lumped.codegen.dispatch.dispatch_scene` (the structure-generic kernels) share them.
"""

from __future__ import annotations

from dataclasses import dataclass
from types import ModuleType

import numpy as np

from .templates import law_template

__all__ = ["JitScene", "kept_values", "with_numbers", "structure_arrays", "position_locks"]


@dataclass(frozen=True)
class JitScene:
    """A scene's generated module (:mod:`lumped.codegen.jit`) and structure arrays; ``module``
    is ``None`` for the structure-generic kernels of :mod:`lumped.codegen.dispatch`."""

    module: ModuleType | None
    masses: np.ndarray
    ea: np.ndarray
    eb: np.ndarray
    spring: np.ndarray
    law_index: np.ndarray
    lock_q: np.ndarray
    consts: np.ndarray
    offsets: np.ndarray



def kept_values(scene, functions: tuple) -> list[float] | None:
    """The laws' constants of ``scene``, element after element, if each element's law
    template has the kept ``functions`` (those of the structure's first scene); else
    ``None`` (another template: the structure's parts are made anew)."""
    values: list[float] = []
    for el, f in zip(scene.elements, functions, strict=True):
        t = law_template(el.law)
        if t.functions is not f and t.functions != f:
            return None
        values += t.values
    return values


def with_numbers(scene, module: ModuleType | None, arrays: tuple,
                 consts: np.ndarray) -> JitScene:
    """The :class:`JitScene` of ``scene``'s numbers (its masses, law constants ``consts``
    and lock values) on its structure's ``module`` and ``arrays``
    (:func:`structure_arrays`)."""
    ea, eb, spring, law_index, offsets, locking, blank = arrays
    lock_q = blank.copy()
    if locking:
        from lumped.codegen.branches import law_branches

        for e, i in locking:
            lock_q[e, i] = law_branches(scene.elements[e].law).info[i].lock_value
    return JitScene(module=module, masses=np.array(scene.masses, dtype=float), ea=ea, eb=eb,
                    spring=spring, law_index=law_index, lock_q=lock_q, consts=consts,
                    offsets=offsets)


def structure_arrays(scene, law_index: list[int], offsets: list[int]) -> tuple:
    """``(ea, eb, spring, law_index, offsets, locking, blank)`` of ``scene``'s structure:
    ``locking`` the ``(e, i)`` of every spring's branch that locks a position (its
    :attr:`~lumped.codegen.branches.BranchInfo.lock_value` a number), ``blank`` an array
    of ``nan`` the shape of :func:`position_locks` (a scene's is a copy with its lock
    values written in). Branches, their locking and whether the lock
    value is a constant are a law's code, which the module text holds."""
    lock_q = position_locks(scene)
    locking = tuple((int(e), int(i)) for e, i in zip(*np.nonzero(~np.isnan(lock_q)),
                                                    strict=True))
    return (np.array(scene.elem_a, dtype=np.int64), np.array(scene.elem_b, dtype=np.int64),
            np.array([el.kind == "spring" for el in scene.elements], dtype=np.bool_),
            np.array(law_index, dtype=np.int64),
            np.array(offsets, dtype=np.int64), locking,
            np.full(lock_q.shape, np.nan))


def position_locks(scene) -> np.ndarray:
    """``lock_q[e, i]``: the elongation that branch ``i`` of spring ``e`` locks
    (:attr:`~lumped.codegen.branches.BranchInfo.lock_value`, e.g. ``L`` of a taut string),
    ``nan`` for other branches and for dashpots; one column per branch of the law with the
    most. ``radau5`` holds such a lock on the velocity level (see
    :meth:`lumped.solvers.radau.stage.StageSystem.evaluate`)."""
    from lumped.codegen.branches import law_branches

    lbs = [law_branches(el.law) for el in scene.elements]
    out = np.full((len(lbs), max([lb.count for lb in lbs] + [1])), np.nan)
    for e, (el, lb) in enumerate(zip(scene.elements, lbs, strict=True)):
        if el.kind != "spring":
            continue
        for i, info in enumerate(lb.info):
            if info.locks and info.lock_value is not None:
                out[e, i] = info.lock_value
    return out
