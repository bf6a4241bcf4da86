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

``law_<j>(q, F) -> (R, dR/dq, dR/dF)``, ``mag_<j>(q, F) -> M``
    Kernel and term magnitude of the scene's ``j``-th distinct law (the code of
    :func:`lumped.codegen.compile_kernel` with ``guard=False``, unchanged).
``element_law(e, q, F) -> (R, dR/dq, dR/dF)``, ``element_magnitude(e, q, F) -> M``
    The same, by element index.
``scene_laws(q, F, out_R, out_Rq, out_RF)``
    All elements at once: ``q, F`` arrays of length ``E``, results written in place.
``evaluate(u, p, G, J, S, roundoff)``
    The residual ``G``, generalised Jacobian ``J`` (``n x n``, structural zeros left
    untouched) and row scales ``S`` of the BDF step system of
    :mod:`lumped.solvers.bdf.fixed_step` in ``u``, with ``p = [h, m_i / h (N), v_hat (N),
    x_hat (N), f(t) (N)]``: momentum rows ``(m_i / h)(v_i - v_hat_i) - f_i - sum_{a_e = i}
    F_e + sum_{b_e = i} F_e``, junction rows without the first term, law rows
    ``R_e(q_e, F_e)`` with ``q_e = x_hat_b + h v_b - (x_hat_a + h v_a)`` (springs) or
    ``v_b - v_a`` (dashpots). ``roundoff`` selects the law rows' scale
    ``max(|R_q| (|q_b| + |q_a|) + |R_F F|, M)`` (the terms ``q = q_b - q_a`` is computed
    from; :func:`lumped.solvers.implicit.step_system.law_scale`), else ``|R_q q| + |R_F F|``.
``active_branch(e, q, F) -> int``
    The index of element ``e``'s active smooth branch at ``(q, F)``, by the kernel's own
    rules (:meth:`lumped.codegen.branches.LawBranches.branch`; -1 where none holds).
``branch_count(e) -> int``, ``branch_law(e, i, q, F) -> (R, dR/dq, dR/dF)``
    Element ``e``'s law on its smooth branch ``i`` alone (``i < branch_count(e)``;
    :meth:`~lumped.codegen.branches.LawBranches.stage_kernel_for`: a steep branch in its
    inverse form ``F - G(q)``), smooth wherever defined.
``branch_guards(e, i, q, F, out) -> int``
    The branch's guard values (:meth:`~lumped.codegen.branches.LawBranches.stage_guards_for`:
    all ``> 0`` strictly inside branch ``i``, some ``< 0`` outside; an event is a sign
    change) written to ``out[0 .. k-1]``; returns ``k`` (0 for a smooth law).

The solvers are compiled once for all scenes (:mod:`lumped.solvers.bdf.core_jit`) and
take ``evaluate`` and ``element_law`` as function pointers (numba's first-class
function types): a new scene compiles only its own small functions.

The scene's structure (arrays, runtime data, not baked into the code) is on
:class:`JitScene`: ``masses`` (``m_i``, 0 for a junction), ``ea, eb`` (element ends,
-1 for ground), ``spring`` (True for a spring-like law), ``law_index`` (element -> ``j``).
Parameters of the laws are baked in (they are constants of the kernels); masses,
initial state, step size and forcing are not, so scenes that differ only in those share
one compiled module.

The disk cache
--------------
Directory: ``$LUMPED_CACHE_DIR``, else ``$XDG_CACHE_HOME/lumped``, else
``~/.cache/lumped``; modules in ``jit/``, each named by a hash of its source. Files are
written to a temporary name and hard-linked into place (atomic, and it never replaces
a file another process wrote first; :func:`os.replace` where the file system has no
hard links), and never rewritten, so numba's cache index (keyed on the file's time
stamp) stays valid. A cache directory that cannot be written gives a warning and a
temporary directory (the code is compiled, not kept).

Without numba, or with ``NUMBA_DISABLE_JIT=1``, the same module runs as plain Python:
correct and slow.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import re
import sys
import tempfile
import threading
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from types import ModuleType

import numpy as np

__all__ = ["njit", "numba_enabled", "cache_dir", "scene_source", "scene_module", "jit_scene",
           "JitScene"]

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


def cache_dir() -> Path:
    """The on-disk cache root (see the module notes); created on demand by the writers."""
    env = os.environ.get("LUMPED_CACHE_DIR")
    if env:
        return Path(env)
    xdg = os.environ.get("XDG_CACHE_HOME")
    base = Path(xdg) if xdg else Path.home() / ".cache"
    return base / "lumped"


def kernel_sources(bound) -> tuple[str, str]:
    """``(kernel, magnitude)`` source of a bound law, unguarded (numba-ready)."""
    from lumped.codegen import compile_kernel
    from lumped.laws import BoundLaw

    if not (isinstance(bound, BoundLaw) and type(bound).kernel is BoundLaw.kernel):
        raise ValueError(
            f"compiled methods need laws given as sympy residuals (ElementLaw.bind); got "
            f"{bound!r}, whose kernel is hand-written")
    law = bound.law
    params = {law.symbols[p]: v for p, v in bound.params.items()}
    kernel = compile_kernel(law.residual, law.q, law.F, params, guard=False)
    return kernel.__source__, kernel.magnitude.__source__


def _exact_powers(source: str) -> str:
    """Rewrite ``base**n`` (an integer literal ``n``) as ``math.pow(base, n.0)``.

    CPython evaluates ``x**3`` with the C library's ``pow``; numba expands an integer
    power into multiplications, which can differ in the last bit. ``math.pow`` is the C
    ``pow`` in both, so the compiled kernels give the Python kernels' numbers bit for bit.
    ``base`` is a name or a parenthesised group, with the call it belongs to if any.
    """
    out = source
    while True:
        m = re.search(r"\*\*(\d+)", out)
        if m is None:
            return out
        i = m.start()  # the operand ends just before i
        j = i
        if out[j - 1] == ")":
            depth = 0
            while True:
                j -= 1
                depth += {")": 1, "(": -1}.get(out[j], 0)
                if depth == 0:
                    break
        while j > 0 and (out[j - 1].isalnum() or out[j - 1] in "_."):
            j -= 1
        out = f"{out[:j]}math.pow({out[j:i]}, {m.group(1)}.0){out[m.end():]}"


def rename_function(source: str, name: str) -> str:
    head, rest = _exact_powers(source).split("\n", 1)
    args = head[head.index("("):]
    return f"@njit(cache=True)\ndef {name}{args}\n{rest}"


def _branches(bound):
    """``(selector source, [(kernel source, guard codes), ...])`` of a law's smooth
    branches (:func:`lumped.codegen.branches.law_branches`; the kernels in the form the
    stage solve of ``radau5`` takes, ``stage_source_for``)."""
    from lumped.codegen.branches import law_branches

    lb = law_branches(bound)
    return lb.branch.__source__, [(lb.stage_source_for(i), tuple(lb.stage_guards_for(i).codes))
                                  for i in range(lb.count)]


def scene_source(scene) -> tuple[str, list[int]]:
    """The generated module's source for ``scene`` and the element -> law index map."""
    E = len(scene.elements)
    laws: list[tuple[str, str]] = []
    bounds = []
    law_index: list[int] = []
    for el in scene.elements:
        srcs = kernel_sources(el.law)
        if srcs not in laws:
            laws.append(srcs)
            bounds.append(el.law)
        law_index.append(laws.index(srcs))
    L = ['"""Generated by lumped.codegen.jit for one scene: do not edit."""',
         "import math", "", "from lumped.codegen.jit import njit", ""]
    for j, (ksrc, msrc) in enumerate(laws):
        L += ["", rename_function(ksrc, f"law_{j}"), "", rename_function(msrc, f"mag_{j}")]
    for name, prefix, nan in (("element_law", "law", "math.nan, math.nan, math.nan"),
                              ("element_magnitude", "mag", "math.nan")):
        L += ["", "@njit(cache=True)", f"def {name}(e, q, F):"]
        L += [f"    if e == {e}:\n        return {prefix}_{law_index[e]}(q, F)"
              for e in range(E)]
        L += [f"    return {nan}", ""]
    L += ["@njit(cache=True)", "def scene_laws(q, F, out_R, out_Rq, out_RF):"]
    for e in range(E):
        L += [f"    out_R[{e}], out_Rq[{e}], out_RF[{e}] = law_{law_index[e]}(q[{e}], F[{e}])"]
    L += ["    return None", ""]
    L += _evaluate_source(scene, law_index)
    L += _branch_section(bounds, law_index)
    return "\n".join(L), law_index


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


def _evaluate_source(scene, law_index: list[int]) -> list[str]:
    """The unrolled step system (the twin of the reference's generated ``evaluate``)."""
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
        j = law_index[e]
        qb, qa, dq = end_values_source(el.kind, a, b, lambda i: f"p[{xh + i}]",
                                       lambda i: f"u[{i}]")
        L += [f"    qb = {qb}", f"    qa = {qa}", "    q = qb - qa", f"    Fe = u[{k}]",
              f"    R, Rq, RF = law_{j}(q, Fe)", f"    G{k} = R", "    if roundoff:",
              "        lin = abs(Rq) * (abs(qb) + abs(qa)) + abs(RF * Fe)",
              f"        M = mag_{j}(q, Fe)",
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


def _branch_section(bounds: list, law_index: list[int]) -> list[str]:
    """``active_branch``, ``branch_count``, ``branch_law`` and ``branch_guards``."""
    L: list[str] = []
    counts = []
    for j, bound in enumerate(bounds):
        selector, branches = _branches(bound)
        counts.append(len(branches))
        L += ["", rename_function(selector, f"select_{j}")]
        for i, (ksrc, codes) in enumerate(branches):
            L += ["", rename_function(ksrc, f"branch_{j}_{i}"), "", "@njit(cache=True)",
                  f"def guards_{j}_{i}(q, F, out):"]
            L += [f"    out[{m}] = {code}" for m, code in enumerate(codes)]
            L += [f"    return {len(codes)}"]
    E = len(law_index)
    L += ["", "@njit(cache=True)", "def active_branch(e, q, F):"]
    L += [f"    if e == {e}:\n        return select_{law_index[e]}(q, F)" for e in range(E)]
    L += ["    return -1", "", "@njit(cache=True)", "def branch_count(e):"]
    L += [f"    if e == {e}:\n        return {counts[law_index[e]]}" for e in range(E)]
    L += ["    return 0", "", "@njit(cache=True)", "def branch_law(e, i, q, F):"]
    for e in range(E):
        j = law_index[e]
        for i in range(counts[j]):
            L += [f"    if e == {e} and i == {i}:", f"        return branch_{j}_{i}(q, F)"]
    L += ["    return math.nan, math.nan, math.nan", "", "@njit(cache=True)",
          "def branch_guards(e, i, q, F, out):"]
    for e in range(E):
        j = law_index[e]
        for i in range(counts[j]):
            L += [f"    if e == {e} and i == {i}:", f"        return guards_{j}_{i}(q, F, out)"]
    L += ["    return 0", ""]
    return L


LOADED_MODULES: dict[str, ModuleType] = {}
MODULE_LOCK = threading.Lock()


def _write_once(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` unless it is there: temp file + atomic ``os.replace``."""
    if path.exists():
        return
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-", suffix=".py")
    try:
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(text)
        try:  # a hard link never replaces an existing file: the first writer wins
            os.link(tmp, path)
        except FileExistsError:
            pass
        except OSError:  # no hard links on this file system
            if not path.exists():
                os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def scene_module(scene) -> tuple[ModuleType, list[int]]:
    """The generated module of ``scene`` (from the disk cache, imported once per process)
    and its element -> law index map."""
    source, law_index = scene_source(scene)
    digest = hashlib.sha256(source.encode()).hexdigest()[:24]
    with MODULE_LOCK:
        module = LOADED_MODULES.get(digest)
        if module is None:
            module = LOADED_MODULES[digest] = import_generated(f"lumped_jit_{digest}", source)
    return module, law_index


def import_generated(name: str, source: str) -> ModuleType:
    """Write ``source`` to the disk cache as module ``name`` (once) and import it; an
    unwritable cache falls back to a temporary directory, with a warning (nothing is
    kept). The caller holds ``MODULE_LOCK`` and records the module."""
    path = cache_dir() / "jit" / f"{name}.py"
    try:
        _write_once(path, source)
    except OSError as err:  # an unwritable cache: compile, but nothing is kept
        warnings.warn(f"lumped: cannot write the compiled-code cache {path.parent} "
                      f"({err}); using a temporary directory", stacklevel=3)
        path = Path(tempfile.mkdtemp(prefix="lumped-jit-")) / f"{name}.py"
        _write_once(path, source)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@dataclass(frozen=True)
class JitScene:
    """A scene's generated module and structure arrays (see the module notes)."""

    module: ModuleType
    masses: np.ndarray
    ea: np.ndarray
    eb: np.ndarray
    spring: np.ndarray
    law_index: np.ndarray
    lock_q: np.ndarray


def jit_scene(scene) -> JitScene:
    """Generate (or load) ``scene``'s compiled module and collect its arrays."""
    module, law_index = scene_module(scene)
    return JitScene(
        module=module,
        masses=np.array(scene.masses, dtype=float),
        ea=np.array(scene.elem_a, dtype=np.int64),
        eb=np.array(scene.elem_b, dtype=np.int64),
        spring=np.array([el.kind == "spring" for el in scene.elements], dtype=np.bool_),
        law_index=np.array(law_index, dtype=np.int64),
        lock_q=position_locks(scene),
    )


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
