r"""numba code generation for a whole scene, cached on disk.

:func:`scene_module` turns a :class:`~lumped.scene.Scene` into ONE generated Python
module of ``@njit(cache=True)`` functions, written to the disk cache and imported from
there, so that a second process loads the machine code numba cached beside it and does
not compile again. :func:`jit_scene` wraps that module with the scene's arrays.

API of a generated module (for the compiled solvers: fixed-step BDF, Radau IIA)
-------------------------------------------------------------------------------
Elements are numbered ``e = 0 .. E-1`` in scene order, nodes ``i = 0 .. N-1``; the
unknowns of an implicit step are ``u = (v_0 .. v_{N-1}, F_0 .. F_{E-1})``. All scalar
functions take and return floats; ``q`` is the element's elongation (spring) or its
rate (dashpot), ``F`` its force (sign convention of :mod:`lumped.scene`).

One module per *structure*. Every float literal of a law's generated functions (the code
of :func:`lumped.codegen.compile_kernel` with ``guard=False``, and of the branch
machinery) is lifted into a trailing argument (:mod:`lumped.codegen.templates`: the
literal's text is the ``repr`` of a float, so the value passed is the very double it
stood for and the compiled code computes the same numbers bit for bit). The module's text
is then the
same for every value of the laws' numbers; it is named by its hash, so new numbers load
the module their structure compiled. The scene's values are the array ``c``
(:attr:`JitScene.consts`, element after element, from :attr:`JitScene.offsets`), which
every entry point below takes last:

``law_<j>(q, F, c_0, ...) -> (R, dR/dq, dR/dF)``, ``mag_<j>(q, F, c_0, ...) -> M``
    Kernel and term magnitude of the scene's ``j``-th distinct law template.
``element_law(e, q, F, c) -> (R, dR/dq, dR/dF)``, ``element_magnitude(e, q, F, c) -> M``
    The same, by element index.
``scene_laws(q, F, out_R, out_Rq, out_RF, c)``
    All elements at once: ``q, F`` arrays of length ``E``, results written in place.
``evaluate(u, p, G, J, S, roundoff)``
    The residual ``G``, generalised Jacobian ``J`` (``n x n``, structural zeros left
    untouched) and row scales ``S`` of the BDF step system of
    :mod:`lumped.solvers.bdf.fixed_step` in ``u``, with ``p = [h, m_i / h (N), v_hat (N),
    x_hat (N), f(t) (N), c]`` (the constants after the ``1 + 4 N`` step parameters):
    momentum rows ``(m_i / h)(v_i - v_hat_i) - f_i - sum_{a_e = i} F_e + sum_{b_e = i}
    F_e``, junction rows without the first term, law rows ``R_e(q_e, F_e)`` with ``q_e =
    x_hat_b + h v_b - (x_hat_a + h v_a)`` (springs) or ``v_b - v_a`` (dashpots).
    ``roundoff`` selects the law rows' scale ``max(|R_q| (|q_b| + |q_a|) + |R_F F|, M)``
    (the terms ``q = q_b - q_a`` is computed from;
    :func:`lumped.solvers.implicit.step_system.law_scale`), else ``|R_q q| + |R_F F|``.
``active_branch(e, q, F, c) -> int``
    The index of element ``e``'s active smooth branch at ``(q, F)``, by the kernel's own
    rules (:meth:`lumped.codegen.branches.LawBranches.branch`; -1 where none holds).
``branch_count(e) -> int``, ``branch_law(e, i, q, F, c) -> (R, dR/dq, dR/dF)``
    Element ``e``'s law on its smooth branch ``i`` alone (``i < branch_count(e)``;
    :meth:`~lumped.codegen.branches.LawBranches.stage_kernel_for`: a steep branch in its
    inverse form ``F - G(q)``), smooth wherever defined.
``branch_guards(e, i, q, F, out, c) -> int``
    The branch's guard values (:meth:`~lumped.codegen.branches.LawBranches.stage_guards_for`:
    all ``> 0`` strictly inside branch ``i``, some ``< 0`` outside; an event is a sign
    change) written to ``out[0 .. k-1]``; returns ``k`` (0 for a smooth law).

``radau5``'s compiled loop takes these last three from :mod:`lumped.codegen.dispatch`
instead: the same functions compiled once for every scene, over one module per law
template, so that a new structure of known laws compiles nothing.

The solvers are compiled once for all scenes (:mod:`lumped.solvers.bdf.core_jit`) and
take ``evaluate`` and ``element_law`` as function pointers (numba's first-class
function types), and new numbers compile nothing. With numba, ``jit-bdf1``/``jit-bdf2``
take those two from :mod:`lumped.codegen.step_dispatch` instead (compiled once for
every scene, over one law module per law: a new structure of known laws compiles
nothing); a scene module's run without numba (plain Python) and in tests.

The scene's structure (arrays, runtime data, not baked into the code) is on
:class:`JitScene` (:mod:`lumped.codegen.scene_numbers`): ``masses`` (``m_i``, 0 for a
junction), ``ea, eb`` (element ends, -1 for ground), ``spring`` (True for a spring-like
law), ``law_index`` (element -> ``j``), ``consts`` and ``offsets``. A number changes the
code only where it changes the generated source: a parameter equal to 0 (sympy drops the
term), a sign, an exponent whose power or derivative is written otherwise (1 drops the
power, 2 and 3 write a product, 0.5 and 1.5 a square root), a steep branch's inverse
form. A factor of 1 is not dropped (:func:`~lumped.codegen.rewrite.constant_of`):
``gamma = 1`` shares the module of every other ``gamma``.

Without numba, or with ``NUMBA_DISABLE_JIT=1``, the same module runs as plain Python:
correct and slow. The disk cache the modules live in is :mod:`lumped.codegen.module_cache`'s.
"""

from __future__ import annotations

import weakref
from collections.abc import Callable
from types import ModuleType
from typing import NamedTuple

import numpy as np

from .module_cache import (
    LOADED_MODULES,
    MODULE_LOCK,
    cache_dir,
    import_generated,
    loaded_key,
    module_name,
)
from .scene_numbers import (
    JitScene,
    kept_values,
    position_locks,
    structure_arrays,
    structure_key,
    with_numbers,
)
from .templates import LawTemplate, law_template

__all__ = ["njit", "numba_enabled", "cache_dir", "scene_source", "scene_module", "jit_scene",
           "JitScene", "refuse_moving_supports", "structure_key", "structure_arrays",
           "with_numbers", "kept_values", "position_locks"]

try:  # numba is a runtime dependency, but the package still works without it
    import numba as numba_module
except ImportError:  # pragma: no cover - exercised only on a machine without numba
    numba_module = None


def numba_enabled() -> bool:
    """True when numba is importable and not disabled by ``NUMBA_DISABLE_JIT``."""
    return numba_module is not None and not numba_module.config.DISABLE_JIT


def njit(*args, **kwargs):
    """``numba.njit`` with ``error_model="numpy"`` (a division by zero gives inf/nan, as
    the kernels expect); the identity decorator when numba is absent."""
    if numba_module is None:
        if args and callable(args[0]):
            return args[0]
        return lambda fn: fn
    kwargs.setdefault("error_model", "numpy")
    return numba_module.njit(*args, **kwargs)


class SceneSource(NamedTuple):
    """A scene's generated module: ``source`` (its text, the same for every value of the
    scene's numbers), ``law_index`` (element -> law ``j`` of the module), ``consts`` (the
    run-time constants of the laws, element after element) and ``offsets`` (where
    element ``e``'s constants start in ``consts``; its law kernel's come first)."""

    source: str
    law_index: list[int]
    consts: np.ndarray
    offsets: list[int]


def scene_templates(scene) -> tuple[list[LawTemplate], list[int], np.ndarray, list[int]]:
    """The distinct law templates of ``scene``, the element -> template map, the run-time
    constants and each element's offset into them (see :class:`SceneSource`)."""
    templates: list[LawTemplate] = []
    law_index: list[int] = []
    offsets: list[int] = []
    values: list[float] = []
    for el in scene.elements:
        t = law_template(el.law)
        keys = [u.functions for u in templates]
        if t.functions not in keys:
            templates.append(t)
            keys.append(t.functions)
        law_index.append(keys.index(t.functions))
        offsets.append(len(values))
        values += t.values
    return templates, law_index, np.array(values + [0.0], dtype=float), offsets


#: :func:`scene_source` per scene object (a scene is immutable once built).
_SOURCES: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def scene_source(scene) -> SceneSource:
    """The generated module of ``scene`` (see :class:`SceneSource`); kept per scene
    object, its text per structure (:func:`structure_key`: one text for every value of
    the numbers, made once)."""
    try:
        hit = _SOURCES.get(scene)
    except TypeError:  # not weakly referenceable: no memo
        hit = None
    if hit is None:
        hit = _scene_source(scene)
        try:
            _SOURCES[scene] = hit
        except TypeError:
            pass
    return hit


#: The text of a structure's module (:func:`_module_text`) per :func:`structure_key`,
#: the last :data:`_STRUCTURES_KEPT` structures asked.
_STRUCTURES: dict[tuple, str] = {}
_STRUCTURES_KEPT = 256


def _scene_source(scene) -> SceneSource:
    templates, law_index, consts, offsets = scene_templates(scene)
    key = structure_key(scene, templates, law_index)
    text = _STRUCTURES.get(key)
    if text is None:
        text = _module_text(scene, templates, law_index, offsets)
        if len(_STRUCTURES) >= _STRUCTURES_KEPT:
            _STRUCTURES.clear()
        _STRUCTURES[key] = text
    return SceneSource(text, law_index, consts, offsets)


def _module_text(scene, templates: list[LawTemplate], law_index: list[int],
                 offsets: list[int]) -> str:
    """The text of the scene's generated module (made once per structure,
    :func:`_scene_source`)."""
    E = len(scene.elements)
    L = ['"""Generated by lumped.codegen.jit for one scene: do not edit."""',
         "import math", "", "from lumped.codegen.jit import njit", ""]
    for j, t in enumerate(templates):
        for text in t.source(j):
            L += ["", text]

    def call(e: int, stem: str, args: str, array: str = "c", base: int = 0) -> str:
        return templates[law_index[e]].call(stem, law_index[e], args, array,
                                            base + offsets[e])

    for name, stem, nan in (("element_law", "law", "math.nan, math.nan, math.nan"),
                            ("element_magnitude", "mag", "math.nan")):
        L += ["", "@njit(cache=True)", f"def {name}(e, q, F, c):"]
        L += [f"    if e == {e}:\n        return {call(e, stem, 'q, F')}" for e in range(E)]
        L += [f"    return {nan}", ""]
    L += ["@njit(cache=True)", "def scene_laws(q, F, out_R, out_Rq, out_RF, c):"]
    for e in range(E):
        L += [f"    out_R[{e}], out_Rq[{e}], out_RF[{e}] = {call(e, 'law', f'q[{e}], F[{e}]')}"]
    L += ["    return None", ""]
    L += _evaluate_source(scene, call)
    L += _branch_section(templates, law_index, call)
    return "\n".join(L)


def end_values_source(kind: str, a: int, b: int, x: Callable[[int], str],
                      u: Callable[[int], str]) -> tuple[str, str, str]:
    """Source of an element's end values in the implicit step and of ``dq/du``.

    The elongation is ``q = q_b - q_a``: for a spring the end positions after the step,
    ``x_i + h u_i`` (``x(i)`` and ``u(i)`` name the history and the unknown velocity of
    node ``i`` in the emitted code), for a dashpot the velocities ``u_i``; ground
    (``-1``) is ``0.0``. Returns ``(q_b, q_a, dq)`` with ``dq = "h"`` or ``"1.0"``.
    """
    def end(i: int) -> str:
        if i < 0:
            return "0.0"
        return f"({x(i)} + h * {u(i)})" if kind == "spring" else u(i)

    return end(b), end(a), ("h" if kind == "spring" else "1.0")


def _evaluate_source(scene, call: Callable[..., str]) -> list[str]:
    """The unrolled step system (the twin of the reference's generated ``evaluate``); the
    laws' constants are read from ``p`` after its ``1 + 4 N`` step parameters."""
    N = len(scene.nodes)
    masses = scene.masses
    xh = 1 + 2 * N
    L = ["@njit(cache=True)", "def evaluate(u, p, G, J, S, roundoff):", "    h = p[0]"]
    for i in range(N):
        fi = f"p[{1 + 3 * N + i}]"
        if masses[i] != 0.0:
            L += [f"    c = p[{1 + i}]", f"    pp = c * u[{i}]", f"    r = c * p[{1 + N + i}]",
                  f"    fi = {fi}", f"    G{i} = (pp - r) - fi",
                  f"    S{i} = abs(pp) + abs(r) + abs(fi)", f"    J[{i}, {i}] = c"]
        else:
            L += [f"    fi = {fi}", f"    G{i} = -fi", f"    S{i} = abs(fi)"]
    for e, el in enumerate(scene.elements):
        k, a, b = N + e, scene.elem_a[e], scene.elem_b[e]
        qb, qa, dq = end_values_source(el.kind, a, b, lambda i: f"p[{xh + i}]",
                                       lambda i: f"u[{i}]")
        L += [f"    qb = {qb}", f"    qa = {qa}", "    q = qb - qa", f"    Fe = u[{k}]",
              f"    R, Rq, RF = {call(e, 'law', 'q, Fe', 'p', 1 + 4 * N)}",
              f"    G{k} = R", "    if roundoff:",
              "        lin = abs(Rq) * (abs(qb) + abs(qa)) + abs(RF * Fe)",
              f"        M = {call(e, 'mag', 'q, Fe', 'p', 1 + 4 * N)}",
              f"        S{k} = M if (M > lin and M != math.inf) else lin", "    else:",
              f"        S{k} = abs(Rq * q) + abs(RF * Fe)", f"    g = Rq * {dq}",
              f"    J[{k}, {k}] = RF"]
        if a >= 0:
            L += [f"    G{a} -= Fe", f"    S{a} += abs(Fe)", f"    J[{a}, {k}] = -1.0",
                  f"    J[{k}, {a}] = -g"]
        if b >= 0:
            L += [f"    G{b} += Fe", f"    S{b} += abs(Fe)", f"    J[{b}, {k}] = 1.0",
                  f"    J[{k}, {b}] = g"]
    n = N + len(scene.elements)
    L += [f"    G[{r}] = G{r}\n    S[{r}] = S{r}" for r in range(n)]
    L += ["    return None", ""]
    return L


def _branch_section(templates: list[LawTemplate], law_index: list[int],
                    call: Callable[..., str]) -> list[str]:
    """``active_branch``, ``branch_count``, ``branch_law`` and ``branch_guards``."""
    E = len(law_index)
    counts = [templates[law_index[e]].branches for e in range(E)]
    L = ["", "@njit(cache=True)", "def active_branch(e, q, F, c):"]
    L += [f"    if e == {e}:\n        return {call(e, 'select', 'q, F')}" for e in range(E)]
    L += ["    return -1", "", "@njit(cache=True)", "def branch_count(e):"]
    L += [f"    if e == {e}:\n        return {counts[e]}" for e in range(E)]
    L += ["    return 0", "", "@njit(cache=True)", "def branch_law(e, i, q, F, c):"]
    for e in range(E):
        for i in range(counts[e]):
            L += [f"    if e == {e} and i == {i}:",
                  f"        return {call(e, f'branch_{i}', 'q, F')}"]
    L += ["    return math.nan, math.nan, math.nan", "", "@njit(cache=True)",
          "def branch_guards(e, i, q, F, out, c):"]
    for e in range(E):
        for i in range(counts[e]):
            L += [f"    if e == {e} and i == {i}:",
                  f"        return {call(e, f'guards_{i}', 'q, F, out')}"]
    L += ["    return 0", ""]
    return L


def scene_module(scene) -> tuple[ModuleType, SceneSource]:
    """The generated module of ``scene`` (from the disk cache, imported once per process)
    and its :class:`SceneSource`."""
    generated = scene_source(scene)
    name = module_name(generated.source)
    with MODULE_LOCK:
        key = loaded_key(name)
        module = LOADED_MODULES.get(key)
        if module is None:
            module = LOADED_MODULES[key] = import_generated(name, generated.source)
    return module, generated


#: :func:`jit_scene`'s arrays of a structure, per module text.
_ARRAYS: dict[str, tuple] = {}


def jit_scene(scene, kept: dict | None = None) -> JitScene:
    """Generate (or load) ``scene``'s compiled module and collect its arrays.

    The arrays of the structure (``ea``, ``eb``, ``spring``, ``law_index``, ``offsets``
    and where the springs' locking branches are) are made once per module text, the
    same for every value of the numbers, and shared (they are only read); ``masses``,
    ``consts`` and ``lock_q`` are the scene's numbers. A scene with moving supports is
    refused (``ValueError``): the compiled loops have no support offsets (the runners
    send such scenes to the Python loop).

    ``kept`` (optional) is a dictionary the caller keeps per *structure*, shared only by
    scenes with the same node kinds, element kinds and ends, and laws of the same
    branches apart from their numbers (``radau5``'s
    :func:`~lumped.solvers.eventdriven.setup.structure_parts`). The module, its arrays
    and each element's law functions are kept in it, with the cache directory they were
    loaded for: a scene of that structure whose laws' templates have those functions
    (the same module text) takes them from there, and only its numbers (the laws'
    constants, in the order of the module's :class:`SceneSource`, and the masses) are
    read; the module's text is not made, hashed or looked up again. The result is the
    one without ``kept``."""
    refuse_moving_supports(scene)
    if kept is not None:
        got = kept.get("jit_scene")
        if got is not None:
            where, module, arrays, functions = got
            values = kept_values(scene, functions)
            if values is not None and str(cache_dir()) == where:
                return with_numbers(scene, module, arrays,
                                    np.array(values + [0.0], dtype=float))
    module, generated = scene_module(scene)
    arrays = _ARRAYS.get(generated.source)
    if arrays is None:
        arrays = structure_arrays(scene, generated.law_index, generated.offsets)
        if len(_ARRAYS) >= _STRUCTURES_KEPT:
            _ARRAYS.clear()
        _ARRAYS[generated.source] = arrays
    if kept is not None:
        kept["jit_scene"] = (str(cache_dir()), module, arrays,
                             tuple(law_template(el.law).functions for el in scene.elements))
    return with_numbers(scene, module, arrays, generated.consts)


def refuse_moving_supports(scene) -> None:
    """``ValueError`` for a scene with moving supports: the compiled loops have no
    support offsets (the runners send such scenes to the Python loop)."""
    if getattr(scene, "support_ends", ()):
        raise ValueError(f"compiled loops do not take moving supports (scene supports: "
                         f"{', '.join(sorted(scene.supports))}); use 'bdf1' or 'bdf2'")

