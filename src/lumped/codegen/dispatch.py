r"""Structure-generic branch kernels: compiled once per machine, dispatched per element.

``radau5``'s compiled loop reaches a scene's laws through three functions of the element
index (:mod:`lumped.codegen.function_types`): ``branch_law(e, i, q, F, c)``,
``branch_guards(e, i, q, F, out, c)`` and ``active_branch(e, q, F, c)``. A scene module
(:mod:`lumped.codegen.jit`) defines them per *structure*, with an ``if e == k`` case per
element; here they are defined once for every scene: element ``e``'s law template
dispatchers (:mod:`lumped.codegen.template_module`) and where its constants start are
read from a *header* at the start of the constants array ``c``::

    c = [law_0, guards_0, select_0, o_0,  law_1, guards_1, select_1, o_1,  ...,
         law constants, element after element, 0.0]

with ``law_e``, ``guards_e``, ``select_e`` the jit entries of element ``e``'s template's
``t_law``, ``t_guards`` and ``t_select`` and ``o_e`` where its constants start
(``4 E`` plus its offset in :attr:`JitScene.offsets <lumped.codegen.jit.JitScene>`;
integers below 2**53, exact in a double). Each function reads its element's row and
calls the template's dispatcher at its address (one direct-convention call more than a
scene module's) with pointers to the element's constants and to ``out``: the same
kernels on the same doubles, so the same numbers bit for bit.

The reads go through raw pointers (:func:`~lumped.codegen.function_types.data_at`), which
read nothing of an array but its data pointer: an index into ``c`` that numba cannot
prove non-negative reads the array's shape as well, and the shared loop passes ``c``
through a C wrapper, whose copy of the array's fields then costs about 12 ns a call
(measured: a law call through the header took 47 ns with ``c[...]``, against 13-14 ns
for a scene module's).

:func:`dispatch_scene` is :func:`~lumped.codegen.jit.jit_scene` for these functions: the
scene's arrays, its constants with the header appended, and no generated module of its
own (``module`` is ``None``). A new structure whose laws' templates are compiled
compiles nothing; a new template compiles its own module only.
"""

from __future__ import annotations

import numpy as np

from .function_types import (
    branch_type,
    call_jit_at,
    compiled_address,
    data_at,
    guards_type,
    law_type,
    template_guards_type,
    template_law_type,
    template_select_type,
)
from .jit import cache_dir, numba_module, refuse_moving_supports, scene_templates
from .scene_numbers import JitScene, kept_values, structure_record, with_numbers
from .template_module import template_addresses
from .templates import LawTemplate, law_template

__all__ = ["HEADER_WIDTH", "branch_law", "branch_guards", "active_branch", "header",
           "dispatch_addresses", "active_branch_address", "dispatch_scene"]

#: Header values per element: its template's three addresses and its offset.
HEADER_WIDTH = 4

if numba_module is not None:
    _at = data_at()
    _law_call = call_jit_at(template_law_type())
    _guards_call = call_jit_at(template_guards_type())
    _select_call = call_jit_at(template_select_type())


def branch_law(e: int, i: int, q: float, F: float, c: np.ndarray) -> tuple[float, float, float]:
    """Element ``e``'s law on its smooth branch ``i``: ``(R, dR/dq, dR/dF)`` (its template's
    ``t_law`` at the address in the header of ``c``)."""
    row = _at(c, 4 * e)
    return _law_call(int(row[0]), i, q, F, _at(c, int(row[3])))


def branch_guards(e: int, i: int, q: float, F: float, out: np.ndarray, c: np.ndarray) -> int:
    """Element ``e``'s guard values on branch ``i`` written to ``out``; their count."""
    row = _at(c, 4 * e)
    return _guards_call(int(row[1]), i, q, F, _at(out, 0), _at(c, int(row[3])))


def active_branch(e: int, q: float, F: float, c: np.ndarray) -> int:
    """The index of element ``e``'s active smooth branch at ``(q, F)``, or -1."""
    row = _at(c, 4 * e)
    return _select_call(int(row[2]), q, F, _at(c, int(row[3])))


#: The compiled functions, ``[(address, dispatcher)]`` each (:func:`compiled_address`).
_KEPT: dict[str, list] = {"law": [], "guards": [], "branch": []}


def dispatch_addresses() -> tuple[int, int]:
    """The addresses of :func:`branch_law` and :func:`branch_guards` compiled for the
    types of :mod:`lumped.codegen.function_types` (once per machine: numba's disk cache;
    looked up once per process)."""
    return (compiled_address(_KEPT["law"], branch_law, law_type()),
            compiled_address(_KEPT["guards"], branch_guards, guards_type()))


def active_branch_address() -> int:
    """The address of :func:`active_branch` compiled (as :func:`dispatch_addresses`; apart,
    for the callers that need it: the mode probe)."""
    return compiled_address(_KEPT["branch"], active_branch, branch_type())


def header(templates: list[LawTemplate], law_index: list[int],
           offsets: list[int]) -> list[float]:
    """The header of a structure (see the module notes): each template's module compiled
    or loaded (:func:`~lumped.codegen.template_module.template_addresses`)."""
    addresses = [template_addresses(t) for t in templates]
    out: list[float] = []
    start = HEADER_WIDTH * len(law_index)
    for e, j in enumerate(law_index):
        out += [float(a) for a in addresses[j]] + [float(start + offsets[e])]
    if any(int(v) != v or v >= 2.0 ** 53 for v in out):  # pragma: no cover - 64-bit only
        raise RuntimeError("a compiled function's address is not exact in a double")
    return out


def dispatch_scene(scene, kept: dict | None = None) -> JitScene:
    """The :class:`~lumped.codegen.jit.JitScene` of ``scene`` for the structure-generic
    kernels: its structure's arrays, its numbers, its law constants after the header,
    and ``module=None`` (no module of its own is made, imported or compiled).

    ``kept`` (optional) is a dictionary the caller keeps per structure, as for
    :func:`~lumped.codegen.jit.jit_scene`: a scene whose laws' templates have the kept
    functions reads only its numbers. A scene with moving supports is refused
    (``ValueError``), and so is a law with a hand-written kernel."""
    refuse_moving_supports(scene)
    where = str(cache_dir())
    if kept is not None:
        got = kept.get("dispatch_scene")
        if got is not None and got[0] == where:
            _, arrays, head, functions = got
            values = kept_values(scene, functions)
            if values is not None:
                return with_numbers(scene, None, arrays,
                                    np.array(head + values + [0.0], dtype=float))
    templates, law_index, consts, offsets = scene_templates(scene)
    record = structure_record(scene, templates, law_index, offsets)
    arrays, head = record.arrays, record.headers.get("dispatch")
    if head is None:
        head = record.headers["dispatch"] = header(templates, law_index, offsets)
    if kept is not None:
        kept["dispatch_scene"] = (where, arrays, head,
                                  tuple(law_template(el.law).functions
                                        for el in scene.elements))
    return with_numbers(scene, None, arrays, np.concatenate([head, consts]))
