r"""The fast path of the compiled generic BDF step: one loop generated per scene.

:mod:`lumped.solvers.bdf.core_jit` is compiled once for every scene and calls the
scene's step system through a function pointer: a faithful, general port of the
reference solver, paid for with about 140 ns a step. :func:`fast_module` generates, per
scene, a loop that does only what the common step needs, specialised to the scene's
sizes and structure, calling the laws' kernels (compiled once each; LLVM inlines them).
Its code grows linearly in the unknowns ``n``: numba's compile time grows with the
statements it types and lowers (about a millisecond each; its SSA pass with blocks times
variables), and a first run of a new structure pays it (see ``docs/benchmarks.md`` 4c):

* the forcing of :func:`lumped.scene.forcing_jit.forcing_into`,
  :func:`lumped.solvers.bdf.fast_force_jit.force_at` called for each node (kind and
  parameters read once before the loop; compiled once per machine, not per structure);
* the unknowns ``u = (v_0 .. v_{N-1}, F_0 .. F_{E-1})``, the residual ``G`` and its row
  scales ``S`` (the linearised scales, ``roundoff=False`` in :mod:`lumped.codegen.jit`)
  are scalar locals; the step system is unrolled, in the same arithmetic, term for term
  and in the same order, as the generated ``evaluate``;
* the generalised Jacobian is constant on a smooth branch except in two numbers per
  element, ``dR/dF`` and ``h^s dR/dq`` (``s = 1`` for a spring, 0 for a dashpot; the
  momentum rows hold ``m_i / h`` and ``+-1``). Those ``2 E`` numbers are the key of the
  factor cache: an equal key means an equal Jacobian, so nothing is rebuilt. A new key
  builds the matrix, factors it with :func:`lumped.solvers.newton.linalg_jit.lu_factor_into`
  (the reference's singleton-first pivots: the row ``v = 0`` of a stuck dashpot is a
  pivot of 1, so its column of the inverse is exact) and keeps ``J^{-1}`` (solved from
  the factors, column by column) in the array ``Inv``, the key in the array ``key``
  (up to :data:`UNROLLED_SOLVE` unknowns in ``2 E`` locals: read from ``key`` at every
  iteration it sat on the step's chain, 7 % of the paper scene's BDF2 step); a
  correction ``d = J^{-1} G`` is then ``n^2`` independent products (above
  :data:`UNROLLED_SOLVE` unknowns summed column by column in a loop of constant trip
  count ``n``: ``O(n)`` statements, which LLVM unrolls; below, balanced trees), without
  the divisions and the long dependent chain of a triangular solve -- a step is a short
  chain of dependent operations, which is what its time is. (The
  inverse used to be held in ``n^2`` unrolled locals: about the same speed, ``n^2`` code,
  7 s of compile for the 9 unknowns of a 3-mass chain);
* semismooth Newton from the previous step's solution: ``u <- u - J(u)^{-1} G(u)``,
  converged at an iterate ``u`` once ``|G_i| <= rtol S_i + atol`` and the correction
  ``d = J(u)^{-1} G(u)`` satisfies ``|d_j| <= rtol |u_j| + atol`` for all rows (the
  reference's two tests, at the same point). The reference then returns ``u - d``; the
  fast path returns ``u`` itself when ``d`` is round-off -- the residual is exactly zero
  (``d = J^{-1} 0 = 0``: the step at rest, accepted before the row scales and ``d`` are
  even computed), or ``u`` came from a correction on the same smooth branch (equal
  Jacobian before and after) and no element is on a branch that locks its rate
  (``dR/dF = 0``). On a piecewise-linear law that correction was the exact solve of the
  affine step system, so ``u`` and ``u - d`` differ by round-off, and the confirming
  evaluation at ``u`` (needed anyway to see that the branch holds) is off the chain of
  dependent operations from one step to the next: a moving step is one correction
  deep, not two. Otherwise (a law that is not piecewise linear, a branch switch, a stuck
  element) it returns ``u - d`` like the reference: the second correction is what makes
  eq. (19) exact (``F_d = f(t)`` to the last bit while stuck: the first correction
  leaves ``F_prev - (F_prev - f)``, which is not always ``f``). The accepted value always
  passes the reference's own tests, so it differs from the reference's by at most
  ``rtol |u| + atol`` per step, and by round-off in the common case;
* the fold check of :mod:`lumped.solvers.implicit.branch_check` on the elements whose law is not a
  known monotone built-in (:func:`lumped.solvers.implicit.branch_check_jit.left_branch`).

Anything else returns at once with the step it could not take: ``run_fast`` returns the
first step it did not take (``n_steps + 1`` when it reached the end), and the driver
(:mod:`lumped.solvers.bdf.fast_jit`) hands that step to the faithful port, which also
reports every failure. Because it keeps ``u`` where the reference takes ``u - d`` (above),
its numbers agree with the reference's to round-off on piecewise-linear laws; at a branch
switch and on other laws the two agree to the Newton tolerance (see the driver's notes).
At tolerances at the level of round-off (``rtol`` below about ``1e-15``) whether the
update test passes depends on the last bit of ``d``, which the explicit inverse and the
reference's triangular solve round differently, so there a step may converge in one
and not in the other.

Signature of the generated ``run_fast(masses, dt, n_steps, bdf2, step0, rtol, atol,
max_it, fkind, fpar, ftab, xs, vs, Fs, Jm, Jv, LU, P, Inv, Iv, key, b, y, counts, lawc)
-> int``
(``lawc``: the scene's law constants, :attr:`lumped.codegen.jit.JitScene.consts`, read
into locals before the loop; the module is the same for every value of them)
(``max_it``: Newton iterations per step before the hand-over; ``Jm .. y`` workspace,
``Jv`` and ``Iv`` flat views of ``Jm`` and ``Inv``, ``key`` of length ``2 E``): the
state at step ``step0`` (and ``step0 - 1`` for BDF2) is read from rows of ``xs, vs,
Fs``, and steps ``step0 + 1 ..`` are written to them; ``counts`` accumulates the Newton
iterations, residual evaluations, Jacobian evaluations, factorisations, the largest
iteration count of one step, and the steps taken.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable
from types import ModuleType

from ...codegen.jit import end_values_source, scene_templates
from ...codegen.module_cache import LOADED_MODULES, MODULE_LOCK, import_generated, loaded_key

__all__ = ["MAX_FAST_ITERATIONS", "MAX_FAST_UNKNOWNS", "fast_source", "fast_module",
           "fast_module_cached"]

#: Newton iterations the fast path tries before it hands the step over.
MAX_FAST_ITERATIONS = 6
#: Larger step systems run on the faithful port alone (its ``n^2`` products a correction
#: and the factorisation's ``n^3`` make the fast loop's advantage shrink).
MAX_FAST_UNKNOWNS = 16

#: ``fast_module``'s memo: caller's key -> module.
_BY_KEY: dict[tuple, ModuleType] = {}


def fast_source(scene) -> str:
    """The generated module's source for ``scene`` (see the module notes)."""
    from ..implicit.branch_check import known_monotone

    N, E = len(scene.nodes), len(scene.elements)
    n = N + E
    templates, law_index, _, offsets = scene_templates(scene)
    # element e's law constants: the first of its slots in the scene's constants, read
    # into locals before the loop (lc<e>_<m>)
    slots = [templates[law_index[e]].count("law") for e in range(E)]

    def law_args(e: int) -> str:
        return "".join(f", lc{e}_{m}" for m in range(slots[e]))

    checked = [e for e, el in enumerate(scene.elements) if not known_monotone(el.law)]
    mass = [m != 0.0 for m in scene.masses]
    spring = [el.kind == "spring" for el in scene.elements]
    ea, eb = scene.elem_a, scene.elem_b
    L = ['"""Generated by lumped.solvers.bdf.fast_codegen for one scene: do not edit."""',
         "import math", "", "from lumped.codegen.jit import njit",
         "from lumped.solvers.bdf.fast_force_jit import force_at",
         "from lumped.solvers.implicit.branch_check_jit import left_branch",
         "from lumped.solvers.newton.linalg_jit import inverse_into, lu_factor_into", ""]
    for j, t in enumerate(templates):
        law_text = t.source(j)[0]
        L += ["", law_text]
    L += ["", "@njit(cache=True)", "def element_law(e, q, F, c):"]
    L += [f"    if e == {e}:\n        return "
          f"{templates[law_index[e]].call('law', law_index[e], 'q, F', 'c', offsets[e])}"
          for e in range(E)]
    L += ["    return math.nan, math.nan, math.nan", "", ""]

    def elong(e: int, xs: str, vs: str) -> str:
        """Element ``e``'s elongation (spring) or rate (dashpot) from node names."""
        a, b = ea[e], eb[e]
        y = xs if spring[e] else vs
        yb = f"{y}{b}" if b >= 0 else "0.0"
        ya = f"{y}{a}" if a >= 0 else "0.0"
        return f"{yb} - {ya}"

    L += ["@njit(cache=True)",
          "def run_fast(masses, dt, n_steps, bdf2, step0, rtol, atol, max_it, fkind, fpar, ftab,",
          "             xs, vs, Fs, Jm, Jv, LU, P, Inv, Iv, key, b, y, counts, lawc):",
          "    h1 = dt", "    h2 = 2.0 * dt / 3.0", "    back = step0 - 1 if step0 >= 1 else 0"]
    for i in range(N):
        L += [f"    x{i} = xs[step0, {i}]", f"    v{i} = vs[step0, {i}]",
              f"    xp{i} = xs[back, {i}]", f"    vp{i} = vs[back, {i}]"]
    for e in range(E):
        L += [f"    F{e} = Fs[step0, {e}]"]
        L += [f"    lc{e}_{m} = lawc[{offsets[e] + m}]" for m in range(slots[e])]
    L += [f"    m{i} = masses[{i}]\n    c{i} = 0.0"
          for i in range(N) if mass[i]]
    small_key = n <= UNROLLED_SOLVE
    if small_key:
        L += [f"    kRF{e} = 0.0\n    kg{e} = 0.0" for e in range(E)]
    for e in checked:
        L += [f"    pq{e} = {elong(e, 'x', 'v')}",
              f"    _, pRq{e}, pRF{e} = law_{law_index[e]}(pq{e}, F{e}{law_args(e)})"]
    L += ["    n_it = 0", "    n_res = 0", "    n_fact = 0", "    most_it = 0", "    taken = 0",
          "    valid = False", "    kc = -1"]
    L += _forcing_setup_lines(N)
    L += ["    for step in range(step0 + 1, n_steps + 1):",
          "        t = step * dt",
          "        k = 0 if (not bdf2 or step == 1) else 1",
          "        h = h1 if k == 0 else h2",
          "        if k != kc:", "            valid = False", "            kc = k"]
    # m_i / h, the reference's value, computed when the formula changes (on the chain of
    # dependent operations at every step, a division would cost its latency)
    L += [f"            c{i} = m{i} / h" for i in range(N) if mass[i]]
    L += _forcing_lines(N, "        ")
    L += ["        if k == 0:"]
    L += [f"            xh{i} = x{i}\n            vh{i} = v{i}" for i in range(N)]
    L += ["        else:"]
    L += [f"            xh{i} = x{i} + (x{i} - xp{i}) / 3.0\n"
          f"            vh{i} = v{i} + (v{i} - vp{i}) / 3.0" for i in range(N)]
    L += [f"        u{i} = v{i}" for i in range(N)]
    L += [f"        u{N + e} = F{e}" for e in range(E)]
    L += ["        done = False", "        for it in range(max_it):"]
    ind = "            "
    g_lines, s_lines = _evaluate_lines(scene, law_index, law_args, ind)
    gsum = " + ".join(f"G{r}" for r in range(n))
    # ``&`` of comparisons where every term is evaluated anyway in the common case (one
    # basic block; numba's compile time grows with blocks times variables), ``and`` where
    # the first term usually decides (a moving iterate's residual and convergence tests)
    zero = "(" + " and ".join(f"G{r} == 0.0" for r in range(n)) + ")"
    # the factor cache's key (dR/dF, h^s dR/dq of each element): up to UNROLLED_SOLVE
    # unknowns in 2 E locals (a load of ``key`` at every iteration is on the step's chain:
    # 7 % on the paper scene's bdf2), above in ``key`` (locals carried through both loops
    # are each a copy at every join: compile time)
    if small_key:
        same = " and ".join(f"RF{e} == kRF{e} and g{e} == kg{e}" for e in range(E)) or "True"
        put_key = [f"{ind}    kRF{e} = RF{e}\n{ind}    kg{e} = g{e}" for e in range(E)]
    else:
        same = " & ".join(f"(RF{e} == key[{2 * e}]) & (g{e} == key[{2 * e + 1}])"
                          for e in range(E)) or "True"
        put_key = [f"{ind}    key[{2 * e}] = RF{e}\n{ind}    key[{2 * e + 1}] = g{e}"
                   for e in range(E)]
    L += g_lines
    L += [f"{ind}n_res += 1", f"{ind}same = valid and {same}",
          # a zero residual on the cached branch: the reference's tests hold, and its
          # correction is J^{-1} 0 = 0, so it returns u (at rest, the common step)
          f"{ind}if same and {zero}:", f"{ind}    done = True", f"{ind}    break",
          f"{ind}if not math.isfinite({gsum}):", f"{ind}    break"]
    L += s_lines
    L += [f"{ind}if not same:"]
    L += _matrix_lines(scene, f"{ind}    ")
    L += [f"{ind}    n_fact += 1", f"{ind}    valid = lu_factor_into(Jm, LU, P)",
          f"{ind}    if not valid:", f"{ind}        break"]
    L += put_key
    L += [f"{ind}    inverse_into(LU, P, b, y, Inv)"]
    L += _solve_lines(n, ind)
    dsum = " + ".join(f"d{r}" for r in range(n))
    res_ok = " and ".join(f"abs(G{r}) <= rtol * S{r} + atol" for r in range(n))
    upd = " and ".join(f"abs(d{r}) <= rtol * abs(u{r}) + atol" for r in range(n))
    lock = " | ".join(f"(RF{e} == 0.0)" for e in range(E)) or "False"
    L += [f"{ind}if not math.isfinite({dsum}):", f"{ind}    break",
          f"{ind}if ({res_ok}) and ({upd}):",
          # the reference's tests hold at u: it returns u - d; the fast path keeps u when
          # d is round-off (see the module notes)
          f"{ind}    done = True",
          f"{ind}    if ({zero}) or (it > 0 and same and not ({lock})):",
          f"{ind}        break"]
    L += [f"{ind}u{r} = u{r} - d{r}" for r in range(n)]
    L += [f"{ind}if done:", f"{ind}    break"]
    ind = "        "
    L += [f"{ind}if not done:", f"{ind}    break"]
    L += [f"{ind}xn{i} = xh{i} + h * u{i}" for i in range(N)]
    for e in checked:
        q1 = elong(e, "xn", "u")
        L += [f"{ind}q1 = {q1}",
              f"{ind}_, Rq1, RF1 = law_{law_index[e]}(q1, u{N + e}{law_args(e)})",
              f"{ind}if left_branch(element_law, lawc, {e}, pq{e}, F{e}, pRq{e}, pRF{e}, q1, "
              f"u{N + e}, Rq1, RF1):", f"{ind}    break",
              f"{ind}pq{e} = q1", f"{ind}pRq{e} = Rq1", f"{ind}pRF{e} = RF1"]
    L += [f"{ind}n_it += it", f"{ind}if it > most_it:", f"{ind}    most_it = it",
          f"{ind}taken += 1"]
    for i in range(N):
        L += [f"{ind}xp{i} = x{i}", f"{ind}vp{i} = v{i}", f"{ind}x{i} = xn{i}",
              f"{ind}v{i} = u{i}", f"{ind}xs[step, {i}] = x{i}", f"{ind}vs[step, {i}] = v{i}"]
    for e in range(E):
        L += [f"{ind}F{e} = u{N + e}", f"{ind}Fs[step, {e}] = F{e}"]
    L += ["    counts[0] += n_it", "    counts[1] += n_res", "    counts[2] += n_res",
          "    counts[3] += n_fact", "    if most_it > counts[4]:", "        counts[4] = most_it",
          "    counts[5] += taken", "    return step0 + 1 + taken", ""]
    return "\n".join(L)


def _forcing_setup_lines(N: int) -> list[str]:
    """Each node's forcing kind and parameters, read once before the loop."""
    return ["    i0 = step0 - step0"] + [
        f"    fk{i} = fkind[{i}]\n    fa{i} = fpar[{i}, 0]\n    fw{i} = fpar[{i}, 1]\n"
        f"    ft{i} = fpar[{i}, 2]" for i in range(N)]


def _forcing_lines(N: int, ind: str) -> list[str]:
    """``f{i}``, the force on node ``i`` at ``t``; a non-finite force ends the loop (the
    faithful port reports it)."""
    # the node's index as ``i0 + i``: an int64, not a literal (numba would compile one
    # ``force_at`` for each literal value)
    L = [f"{ind}f{i} = force_at(fk{i}, fa{i}, fw{i}, ft{i}, t, ftab, step, i0 + {i})"
         for i in range(N)]
    fsum = " + ".join(f"f{i}" for i in range(N))
    return L + [f"{ind}if not math.isfinite({fsum}):", f"{ind}    break"]


def _evaluate_lines(scene, law_index: list[int], law_args: Callable[[int], str],
                    ind: str) -> tuple[list[str], list[str]]:
    """The step system in scalars, the arithmetic of :mod:`lumped.codegen.jit`'s
    ``evaluate`` (``roundoff=False``) term for term: the lines of the residual ``G`` and
    the Jacobian's variable entries, then those of the row scales ``S`` (emitted apart:
    they are needed only when the residual is not exactly zero)."""
    N = len(scene.nodes)
    GL: list[str] = []
    SL: list[str] = []
    # each node row once, its terms in the order of evaluate's in-place sums (Python's
    # left-to-right ``a + b + c`` is ``(a + b) + c``): one assignment a row
    grow, srow = [], []
    for i, m in enumerate(scene.masses):
        if m != 0.0:
            GL += [f"{ind}pp{i} = c{i} * u{i}", f"{ind}r{i} = c{i} * vh{i}"]
            grow.append(f"(pp{i} - r{i}) - f{i}")
            srow.append(f"abs(pp{i}) + abs(r{i}) + abs(f{i})")
        else:
            grow.append(f"-f{i}")
            srow.append(f"abs(f{i})")
    for e, el in enumerate(scene.elements):
        k, a, b = N + e, scene.elem_a[e], scene.elem_b[e]
        qb, qa, dq = end_values_source(el.kind, a, b, lambda i: f"xh{i}", lambda i: f"u{i}")
        GL += [f"{ind}q{e} = {qb} - {qa}",
               f"{ind}G{k}, Rq{e}, RF{e} = law_{law_index[e]}(q{e}, u{k}{law_args(e)})",
               f"{ind}g{e} = Rq{e} * {dq}"]
        SL += [f"{ind}S{k} = abs(Rq{e} * q{e}) + abs(RF{e} * u{k})"]
        if a >= 0:
            grow[a] += f" - u{k}"
            srow[a] += f" + abs(u{k})"
        if b >= 0:
            grow[b] += f" + u{k}"
            srow[b] += f" + abs(u{k})"
    GL += [f"{ind}G{i} = {grow[i]}" for i in range(N)]
    SL += [f"{ind}S{i} = {srow[i]}" for i in range(N)]
    return GL, SL


def _matrix_lines(scene, ind: str) -> list[str]:
    """Fill ``Jm`` through its flat view ``Jv`` (zeroed by the caller; only structural
    entries are written)."""
    N = len(scene.nodes)
    n = N + len(scene.elements)

    def at(r: int, c: int) -> str:
        return f"{ind}Jv[{r * n + c}]"

    L = [f"{at(i, i)} = c{i}" for i, m in enumerate(scene.masses) if m != 0.0]
    for e in range(len(scene.elements)):
        k, a, b = N + e, scene.elem_a[e], scene.elem_b[e]
        L += [f"{at(k, k)} = RF{e}"]
        if a >= 0:
            L += [f"{at(a, k)} = -1.0", f"{at(k, a)} = -g{e}"]
        if b >= 0:
            L += [f"{at(b, k)} = 1.0", f"{at(k, b)} = g{e}"]
    return L


#: Up to this many unknowns a correction is unrolled (``n^2`` products summed as balanced
#: trees straight from ``G``, as little code as the loop's below); above it, a loop.
UNROLLED_SOLVE = 4


def _solve_lines(n: int, ind: str) -> list[str]:
    """``d = J^{-1} G``, the inverse read from ``Iv`` (``Inv`` flattened). For ``n <=``
    :data:`UNROLLED_SOLVE` each row is a balanced tree of products of the locals ``G``;
    above, ``G`` goes into ``b`` and a loop over the columns ``c`` adds ``Inv[r, c] G_c``
    to each ``d_r``: ``O(n)`` statements for numba to compile, not ``n^2`` (LLVM unrolls
    the loop: its trip count is a constant)."""
    if n <= UNROLLED_SOLVE:
        return [f"{ind}d{r} = " + _tree([f"Iv[{r * n + c}] * G{c}" for c in range(n)])
                for r in range(n)]
    L = [f"{ind}b[{c}] = G{c}" for c in range(n)]
    L += [f"{ind}d{r} = 0.0" for r in range(n)]
    L += [f"{ind}for c in range({n}):", f"{ind}    gc = b[c]"]
    L += [f"{ind}    d{r} += Iv[c + {r * n}] * gc" for r in range(n)]
    return L


def _tree(terms: list[str]) -> str:
    """The sum of ``terms`` as a balanced tree (a shorter chain of dependent additions
    than left to right)."""
    if len(terms) == 1:
        return terms[0]
    mid = (len(terms) + 1) // 2
    return f"({_tree(terms[:mid])} + {_tree(terms[mid:])})"


def _fast_name(source: str) -> str:
    return "lumped_jitfast_" + hashlib.sha256(source.encode()).hexdigest()[:24]


def fast_module_cached(scene, key: tuple | None = None) -> bool:
    """The scene's fast-path module exists: loaded in this process (under ``key`` or its
    source) or in the disk cache. Its source does not depend on the laws' numbers, so any
    earlier run of the same structure built it."""
    from ...codegen.module_cache import cache_dir, generated_module_exists

    if key is not None and (str(cache_dir()), key) in _BY_KEY:
        return True
    return generated_module_exists(_fast_name(fast_source(scene)))


def fast_module(scene, key: tuple | None = None) -> ModuleType:
    """The generated fast-path module of ``scene``, from the disk cache (as
    :func:`lumped.codegen.jit.scene_module`, under the prefix ``lumped_jitfast_``).

    ``key``, if given, must determine :func:`fast_source` (the caller's promise: the
    driver passes the scene's faithful module name, which fixes the laws and the
    topology, and the structure arrays); a later call with an equal key returns the
    module without generating the source again (about 0.4 ms of sympy printing, 8 ns a
    step on a run of 50 000 steps)."""
    from ...codegen.module_cache import cache_dir

    if key is not None:
        key = (str(cache_dir()), key)  # (as the modules: per cache directory)
        module = _BY_KEY.get(key)
        if module is not None:
            return module
    source = fast_source(scene)
    name = _fast_name(source)
    with MODULE_LOCK:
        module = LOADED_MODULES.get(loaded_key(name))
        if module is None:
            module = LOADED_MODULES[loaded_key(name)] = import_generated(name, source)
        if key is not None:
            _BY_KEY[key] = module
    return module
