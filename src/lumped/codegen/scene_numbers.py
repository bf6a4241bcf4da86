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
:func:`structure_record` is what a process keeps per structure for the structure-generic
kernels of :mod:`lumped.codegen.dispatch` and :mod:`lumped.codegen.step_dispatch`: the
arrays, each one's header and the port's tally, under :func:`structure_key`.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from types import ModuleType

import numpy as np

from .module_cache import cache_dir
from .templates import LawTemplate, law_template

__all__ = ["JitScene", "Structure", "kept_values", "with_numbers", "structure_arrays",
           "position_locks", "structure_key", "structure_record"]


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


def structure_key(scene, templates: list[LawTemplate], law_index: list[int]) -> tuple:
    """Everything a structure's code reads from ``scene`` and its templates: each
    template's functions (their texts and value counts, which fix the offsets), the
    element -> template map, which nodes have a mass, each element's kind and ends."""
    return (tuple(t.functions for t in templates), tuple(law_index),
            tuple(m != 0.0 for m in scene.masses),
            tuple(el.kind for el in scene.elements), scene.elem_a, scene.elem_b)


@dataclass
class Structure:
    """What a process keeps of one structure for the structure-generic kernels.

    Attributes
    ----------
    arrays : tuple
        :func:`structure_arrays` (only read).
    headers : dict
        The header of each kind of kernel, made when first asked (it compiles or loads
        the laws' modules): ``"dispatch"``, :func:`lumped.codegen.dispatch.header`;
        ``"step"``, :func:`lumped.codegen.step_dispatch.step_header`.
    tally : list of int
        One element: the steps this process ran the structure on the faithful port
        (:func:`lumped.solvers.bdf.fixed_step_jit.takes_fast_path`).
    """

    arrays: tuple
    headers: dict[str, list[float]] = field(default_factory=dict)
    tally: list[int] = field(default_factory=lambda: [0])


#: :func:`structure_record`'s records, per (cache directory, :func:`structure_key`): the
#: last :data:`_STRUCTURES_KEPT` structures asked.
_STRUCTURES: dict[tuple, Structure] = {}
_STRUCTURES_KEPT = 256


def structure_record(scene, templates: list[LawTemplate], law_index: list[int],
                     offsets: list[int]) -> Structure:
    """The :class:`Structure` of ``scene`` (``templates, law_index, offsets`` from
    :func:`lumped.codegen.jit.scene_templates`), made the first time the process asks
    for its structure with the current cache directory."""
    key = (str(cache_dir()), structure_key(scene, templates, law_index))
    got = _STRUCTURES.get(key)
    if got is None:
        got = Structure(structure_arrays(scene, law_index, offsets))
        if len(_STRUCTURES) >= _STRUCTURES_KEPT:
            _STRUCTURES.clear()
        _STRUCTURES[key] = got
    return got
