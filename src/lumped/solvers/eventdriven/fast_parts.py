r"""The compiled loop's parts of a ``radau5`` scene (:mod:`lumped.solvers.eventdriven.fast`):
whether its laws' compiled code exists, its kernels' addresses, its forcing's arrays and
whether it runs in Python instead (and why).

The loop reaches the laws through the structure-generic kernels of
:mod:`lumped.codegen.dispatch` (compiled once per machine), which call each element's
law template module (:mod:`lumped.codegen.template_module`, compiled once per template)
through the header the scene's constants carry: a new structure whose laws' templates
are compiled compiles nothing.
"""

from __future__ import annotations

import numpy as np

from ...codegen.dispatch import active_branch_address, dispatch_addresses, dispatch_scene
from ...codegen.function_types import branch_type, guards_type, law_type
from ...codegen.jit import numba_enabled
from ...codegen.templates import GUARD_ROOM, law_template
from ...scene import Scene

__all__ = ["Pointer", "branch_pointer", "dispatch_pointers", "loaded", "locks_in_parallel",
           "loop_forcing", "loop_parts", "pointer"]


def loaded(scene: Scene, plan) -> bool:
    """The modules of the scene's law templates exist already, loaded in this process or
    in the disk cache (an earlier run of the same laws, on any topology and with any
    numbers, compiled them): nothing left to compile but, on a machine that never ran
    ``radau5`` compiled, the shared code. Checked once per plan, and a yes kept per
    structure (``plan.structure``, with the cache directory it holds for): a scene with
    new numbers makes no module text to ask."""
    from ...codegen import module_cache
    from ...codegen.jit import scene_templates
    from ...codegen.template_module import template_module_cached

    if getattr(plan, "module_loaded", None) is None:
        where = str(module_cache.cache_dir())
        if plan.structure.get("module_loaded_in") == where:
            plan.module_loaded = True
            return True
        try:
            templates = scene_templates(scene)[0]
        except ValueError:  # a hand-written kernel: loop_parts says why
            plan.module_loaded = True
        else:
            plan.module_loaded = all(template_module_cached(t) for t in templates)
            if plan.module_loaded:
                plan.structure["module_loaded_in"] = where
    return plan.module_loaded


def loop_parts(scene: Scene, plan) -> tuple | str:
    """The compiled loop's per-scene parts, or why the scene runs in Python. What depends
    on the structure alone is made once per structure (``plan.structure``: the elements
    whose forces can be free on cycles, the fold-checked elements' array, the arrays and
    the header of :func:`~lumped.codegen.dispatch.dispatch_scene` with ``kept``), the
    forcing's arrays once per forcing objects (:func:`loop_forcing`); the scene's numbers
    are :func:`~lumped.codegen.dispatch.dispatch_scene`'s. The kernels are the
    structure-generic ones, as pointers (:class:`Pointer`: ``branch_law``, ``branch_guards``;
    ``active_branch`` as :func:`branch_pointer`, made when first asked)."""
    if not numba_enabled():
        return "python: numba is not available (or NUMBA_DISABLE_JIT is set)"
    structure = plan.structure
    if locks_in_parallel(plan):
        return "python: locked elements in parallel (minimum-norm forces)"
    fkind, fpar, timed = _forcing(scene)
    if timed >= 0:
        node = scene.nodes[timed].name
        return (f"python: the forcing on node {node!r} is a function of t (compiled: "
                f"constants, sine bursts and tables)")
    try:
        js = dispatch_scene(scene, structure)
    except ValueError as err:  # a hand-written kernel: no generated code
        return f"python: {err}"
    most = structure.get("guards")
    if most is None:
        most = structure["guards"] = max((law_template(el.law).guards
                                          for el in scene.elements), default=0)
    if most > GUARD_ROOM:
        return (f"python: a law with {most} guards on one branch (the compiled loop has "
                f"room for {GUARD_ROOM})")
    checked = structure.get("checked_array")
    if checked is None:
        checked = structure["checked_array"] = np.array(plan.checked, dtype=np.int64)
    law, guards = dispatch_pointers()
    return js, law, guards, fkind, fpar, checked, branch_pointer


_DISPATCH: list = []
_BRANCH: list = []


def dispatch_pointers() -> tuple[Pointer, Pointer]:
    """The structure-generic ``branch_law`` and ``branch_guards``
    (:func:`~lumped.codegen.dispatch.dispatch_addresses`) as pointers (:class:`Pointer`), made
    once per process."""
    if not _DISPATCH:
        from ...codegen import dispatch

        law, guards = dispatch_addresses()
        _DISPATCH.extend((Pointer(law, law_type(), dispatch),
                          Pointer(guards, guards_type(), dispatch)))
    return _DISPATCH[0], _DISPATCH[1]


def branch_pointer() -> Pointer:
    """The structure-generic ``active_branch`` as a :class:`Pointer`, compiled (or loaded)
    the first time a process asks: only the mode probe calls it."""
    if not _BRANCH:
        from ...codegen import dispatch

        _BRANCH.append(Pointer(active_branch_address(), branch_type(), dispatch))
    return _BRANCH[0]


#: ids of a scene's forcing objects -> (those objects, :func:`loop_forcing`'s arrays, the
#: first node whose forcing is a function of t or -1), the last few hundred asked (the
#: objects are immutable; the compiled loop only reads the arrays).
_FORCING: dict[tuple, tuple] = {}


def loop_forcing(scene: Scene) -> tuple[np.ndarray, np.ndarray]:
    """``(fkind, fpar)`` of the compiled loop's forcing
    (:func:`~lumped.scene.forcing_jit.forcing_arrays` with ``linear=True``, a
    :func:`~lumped.scene.forcing.zero_forcing` read as none), made once per forcing
    objects: a scene with new law numbers and the same forcing objects shares them."""
    return _forcing(scene)[:2]


def _forcing(scene: Scene) -> tuple[np.ndarray, np.ndarray, int]:
    """:func:`loop_forcing`'s arrays and the first node whose forcing the compiled loop
    does not take (a function of t, kind 3), or -1; kept per forcing objects."""
    key = tuple(map(id, scene.forcing))
    got = _FORCING.get(key)
    if got is not None and all(a is b for a, b in zip(got[0], scene.forcing, strict=True)):
        return got[1], got[2], got[3]
    from ...scene.forcing import zero_forcing
    from ...scene.forcing_jit import forcing_arrays

    fkind, fpar, _ = forcing_arrays(scene, 1.0, 0, linear=True)
    for i, fn in enumerate(scene.forcing):
        if fn is zero_forcing:  # f = 0.0, as no forcing
            fkind[i] = 0
    timed = int(np.argmax(fkind == 3)) if (fkind == 3).any() else -1
    if len(_FORCING) >= 256:
        _FORCING.clear()
    _FORCING[key] = (tuple(scene.forcing), fkind, fpar, timed)
    return fkind, fpar, timed


def locks_in_parallel(plan) -> bool:
    """Some elements that can be force-free (a branch whose ``dR/dF`` is not a nonzero
    constant) close a cycle: their forces can become indeterminate
    (:mod:`lumped.solvers.nonsmooth.locks`); the plan's structure's ``free_cycles``, made
    once per structure."""
    return bool(plan.structure["free_cycles"])


_POINTERS: dict = {}


def pointer(dispatcher, ftype):
    """``dispatcher`` as a first-class function of numba type ``ftype`` whose address and
    type are looked up once (cached per dispatcher).

    numba converts a dispatcher passed for a function-type argument to its address on
    every call, and types an object of its *wrapper address protocol* anew on every call
    (each about 0.1 ms); :class:`Pointer` carries both, ready."""
    key = id(dispatcher)
    got = _POINTERS.get(key)
    if got is None or got.keep is not dispatcher:
        from numba.experimental.function_type import _get_wrapper_address

        addr = _get_wrapper_address(dispatcher, ftype.signature)
        got = _POINTERS[key] = Pointer(addr, ftype, dispatcher)
    return got


class Pointer:
    """A compiled function's address and numba type (``_numba_type_``, read by numba's
    ``typeof``; ``__wrapper_address__``, read when the argument is unboxed); it keeps
    the dispatcher, hence the code, alive."""

    def __init__(self, addr: int, ftype, keep) -> None:
        self.addr, self._numba_type_, self.keep = addr, ftype, keep

    def __wrapper_address__(self) -> int:
        return self.addr

    def signature(self):
        return self._numba_type_.signature
