r"""The BDF step system, structure-generic: compiled once per machine, dispatched per element.

The compiled step loop of ``jit-bdf1``/``jit-bdf2`` (:mod:`lumped.solvers.bdf.core_jit`)
reaches a scene through two callbacks, ``evaluate(u, p, G, J, S, roundoff)`` and
``element_law(e, q, F, c)``. A scene module (:mod:`lumped.codegen.jit`) generates them per
*structure*, unrolled; here they are defined once for every scene, as
:mod:`lumped.codegen.dispatch` does for ``radau5``'s branch kernels. The structure is read
from a *header* at the start of the constants ``c`` and the node count from its end::

    c = [full_0, mag_0, o_0, a_0, b_0, s_0,  ...,  full_{E-1}, ..., s_{E-1},
         w_0 .. w_{N-1},  law constants, element after element,  N]

with ``full_e``, ``mag_e`` the jit entries of element ``e``'s law module's ``t_full`` and
``t_mag`` (:func:`~lumped.codegen.template_module.law_addresses`), ``o_e`` where its
constants start in ``c``, ``a_e``, ``b_e`` its ends (-1 for ground), ``s_e`` 1 for a
spring and 0 for a dashpot, ``w_i`` 1 for a node with a mass and 0 for a junction (all
integers below 2**53, exact in a double). The loop copies ``c`` to the tail of ``p``
after the ``1 + 4 N`` step parameters; :func:`evaluate` finds ``N`` in ``p``'s last entry
and ``E`` as ``len(u) - N``.

:func:`evaluate` does the generated ``evaluate``'s floating-point operations in its order
(:func:`lumped.codegen.jit._evaluate_source`): the momentum rows first, node by node,

.. math::

    G_i = ((m_i/h) v_i - (m_i/h) \hat v_i) - f_i, \quad
    S_i = |(m_i/h) v_i| + |(m_i/h) \hat v_i| + |f_i|

(``G_i = -f_i``, ``S_i = |f_i|`` at a junction), then element by element its law row
``G_k = R_e(q_e, F_e)`` with ``q_e = q_b - q_a`` (end positions after the step ``\hat x +
h v`` for a spring, velocities for a dashpot), its scale (``roundoff``: ``max(|R_q| (|q_b|
+ |q_a|) + |R_F F_e|, M_e)`` unless ``M_e`` is infinite, else ``|R_q q_e| + |R_F F_e|``),
its Jacobian entries, and ``G_a -= F_e``, ``S_a += |F_e|``, then ``G_b += F_e``, ``S_b +=
|F_e|``: the same sums in the same order, on the same kernels with the same doubles, so
the same numbers bit for bit. Each law is one direct call through its address (a scene
module's is inlined).

:func:`step_layout` gives a scene's constants with the header written when first needed
(:func:`step_scene` at once); :func:`step_callbacks` the two functions compiled (numba's
disk cache after the first time on a machine). A new structure whose laws' law modules
are compiled compiles nothing; a run that never needs the two (``jit-bdf``'s fast loop
taking a run whole) compiles neither them nor a law module.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from .function_types import (
    call_jit_at,
    data_at,
    element_law_type,
    scalar_loops,
    step_evaluate_type,
    template_full_law_type,
    template_magnitude_type,
)
from .jit import njit, numba_enabled, numba_module, refuse_moving_supports, scene_templates
from .scene_numbers import JitScene, structure_record, with_numbers
from .template_module import law_addresses

__all__ = ["STEP_WIDTH", "evaluate", "element_law", "step_header", "step_layout",
           "step_scene", "step_callbacks"]

#: Header values per element: its law module's two addresses, its constants' start, its
#: ends and whether it is a spring.
STEP_WIDTH = 6

if numba_module is not None:
    _at = data_at()
    _full_call = call_jit_at(template_full_law_type())
    _mag_call = call_jit_at(template_magnitude_type())


def element_law(e: int, q: float, F: float, c: np.ndarray) -> tuple[float, float, float]:
    """Element ``e``'s law ``(R, dR/dq, dR/dF)`` at ``(q, F)`` (its law module's
    ``t_full`` at the address in the header of ``c``)."""
    row = _at(c, STEP_WIDTH * e)
    return _full_call(int(row[0]), q, F, _at(c, int(row[2])))


def evaluate(u: np.ndarray, p: np.ndarray, G: np.ndarray, J: np.ndarray, S: np.ndarray,
             roundoff: bool) -> None:
    """The residual ``G``, Jacobian entries ``J`` and row scales ``S`` of the BDF step
    system at ``u`` (see the module notes; ``p = [h, m_i / h (N), v_hat (N), x_hat (N),
    f(t) (N), c]``)."""
    N = int(p[p.shape[0] - 1])
    E = u.shape[0] - N
    h = p[0]
    base = 1 + 4 * N
    xh = 1 + 2 * N
    weighed = _at(p, base + STEP_WIDTH * E)
    for i in range(N):
        fi = p[1 + 3 * N + i]
        if weighed[i] != 0.0:
            c = p[1 + i]
            pp = c * u[i]
            r = c * p[1 + N + i]
            G[i] = (pp - r) - fi
            S[i] = abs(pp) + abs(r) + abs(fi)
            J[i, i] = c
        else:
            G[i] = -fi
            S[i] = abs(fi)
    for e in range(E):
        row = _at(p, base + STEP_WIDTH * e)
        k = N + e
        a = int(row[3])
        b = int(row[4])
        if row[5] != 0.0:
            qb = (p[xh + b] + h * u[b]) if b >= 0 else 0.0
            qa = (p[xh + a] + h * u[a]) if a >= 0 else 0.0
            dq = h
        else:
            qb = u[b] if b >= 0 else 0.0
            qa = u[a] if a >= 0 else 0.0
            dq = 1.0
        q = qb - qa
        Fe = u[k]
        consts = _at(p, base + int(row[2]))
        R, Rq, RF = _full_call(int(row[0]), q, Fe, consts)
        G[k] = R
        if roundoff:
            lin = abs(Rq) * (abs(qb) + abs(qa)) + abs(RF * Fe)
            M = _mag_call(int(row[1]), q, Fe, consts)
            S[k] = M if (M > lin and M != math.inf) else lin
        else:
            S[k] = abs(Rq * q) + abs(RF * Fe)
        g = Rq * dq
        J[k, k] = RF
        if a >= 0:
            G[a] -= Fe
            S[a] += abs(Fe)
            J[a, k] = -1.0
            J[k, a] = -g
        if b >= 0:
            G[b] += Fe
            S[b] += abs(Fe)
            J[b, k] = 1.0
            J[k, b] = g
    return None


def step_header(scene, templates, law_index: list[int], offsets: list[int]) -> list[float]:
    """The header of ``scene``'s structure (see the module notes), each law module
    compiled or loaded (:func:`~lumped.codegen.template_module.law_addresses`)."""
    addresses = [law_addresses(t) for t in templates]
    E, N = len(law_index), len(scene.nodes)
    start = STEP_WIDTH * E + N
    out: list[float] = []
    for e, (j, el) in enumerate(zip(law_index, scene.elements, strict=True)):
        out += [float(addresses[j][0]), float(addresses[j][1]), float(start + offsets[e]),
                float(scene.elem_a[e]), float(scene.elem_b[e]),
                1.0 if el.kind == "spring" else 0.0]
    out += [1.0 if m != 0.0 else 0.0 for m in scene.masses]
    if any(int(v) != v or abs(v) >= 2.0 ** 53 for v in out):  # pragma: no cover - 64-bit
        raise RuntimeError("a compiled function's address is not exact in a double")
    return out


def step_layout(scene) -> tuple[JitScene, np.ndarray, Callable[[], np.ndarray], list[int]]:
    """``scene``'s :class:`~lumped.codegen.scene_numbers.JitScene` without a module of its
    own (``module=None``; its ``consts`` those of :func:`lumped.codegen.jit.jit_scene`),
    its constants for :func:`evaluate` and :func:`element_law` (its laws' constants and
    its node count after a header left blank, zeros) and a function that writes the
    header into them and returns them (the first time for a structure in a process it
    compiles or loads the laws' law modules, :func:`step_header`), and the structure's
    *tally*: a one-element list the caller may count in (the steps this process ran the
    structure on the port, :func:`lumped.solvers.bdf.fixed_step_jit.takes_fast_path`).
    Nothing is generated for the structure. A scene with moving supports is refused
    (``ValueError``), and so is a law with a hand-written kernel."""
    refuse_moving_supports(scene)
    templates, law_index, consts, offsets = scene_templates(scene)
    record = structure_record(scene, templates, law_index, offsets)
    width = STEP_WIDTH * len(law_index) + len(scene.nodes)
    step = np.zeros(width + consts.shape[0])
    step[width:-1] = consts[:-1]
    step[-1] = float(len(scene.nodes))

    def with_header() -> np.ndarray:
        head = record.headers.get("step")
        if head is None:
            head = record.headers["step"] = step_header(scene, templates, law_index, offsets)
        step[:width] = head
        return step

    return with_numbers(scene, None, record.arrays, consts), step, with_header, record.tally


def step_scene(scene) -> tuple[JitScene, np.ndarray]:
    """:func:`step_layout` with the header written: the scene's
    :class:`~lumped.codegen.scene_numbers.JitScene` and its constants for
    :func:`evaluate` and :func:`element_law`."""
    js, _, with_header, _ = step_layout(scene)
    return js, with_header()


#: :func:`step_callbacks`'s compiled pair, once per process.
_COMPILED: list = []


def step_callbacks() -> tuple:
    """``(evaluate, element_law)`` compiled for the step loop's function types (once per
    machine: numba's disk cache; loaded once per process); the plain functions without
    numba (they call compiled code through addresses: ``RuntimeError`` then)."""
    if not numba_enabled():
        raise RuntimeError("the structure-generic step system needs numba")
    if not _COMPILED:
        with scalar_loops():  # (a scene's few nodes and elements: no vector loops)
            ev = njit(step_evaluate_type().signature, cache=True)(evaluate)
            law = njit(element_law_type().signature, cache=True)(element_law)
        _COMPILED.append((ev, law))
    return _COMPILED[0]
