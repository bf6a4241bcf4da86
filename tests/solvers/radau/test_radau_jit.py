"""The compiled Radau IIA stage system against the pure-Python one of ``radau5``.

Runs once the adaptive method (``lumped.solvers.radau.stage``, branch ``adaptive``) is merged:
the compiled port must give the same residual, Jacobian and Newton solution bit for bit.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from lumped import Element, Junction, Mass, Scene
from lumped.codegen.branches import law_branches
from lumped.codegen.jit import jit_scene
from lumped.laws import get_law

radau = pytest.importorskip("lumped.solvers.radau.stage")
from lumped.codegen.jit import njit, numba_enabled  # noqa: E402
from lumped.solvers.radau import tableau  # noqa: E402
from lumped.solvers.radau.stage_jit import compiled_stage_solve, workspace  # noqa: E402
from lumped.solvers.radau.stage_jit import stage_evaluate as _cached_stage_evaluate  # noqa: E402

#: :func:`~lumped.solvers.radau.stage_jit.stage_evaluate` compiled here without numba's disk
#: cache. The tests pass the scene's kernels as a dispatcher, whose numba type is new in
#: every process; a cached entry keyed on it cannot be pickled again once its dispatcher
#: is gone, and the suite's second run on a machine failed with numba's "ReferenceError:
#: underlying object has vanished". (The solver passes a function type, one entry.)
stage_evaluate = (njit(_cached_stage_evaluate.py_func) if numba_enabled()
                  else _cached_stage_evaluate)


@pytest.fixture(scope="module")
def setup():
    scene = Scene(
        [Mass("m1", 1.0, x0=0.2), Mass("m2", 0.5), Junction("j")],
        [Element("s1", get_law("linear_spring").bind(k=40.0), "ground", "m1"),
         Element("d", get_law("bingham").bind(gamma=0.5, tau=1.5), "ground", "m1"),
         Element("s2", get_law("linear_spring").bind(k=20.0), "m1", "j"),
         Element("c", get_law("newtonian").bind(c=2.0), "j", "m2")],
    )
    js = jit_scene(scene)
    system = radau.StageSystem(scene.masses, scene.elem_a, scene.elem_b,
                               [el.kind == "spring" for el in scene.elements])
    return scene, js, system


def _inputs(scene, data, mode_d):
    N, E = len(scene.nodes), len(scene.elements)
    n = N + E
    vals = st.floats(-2.0, 2.0, allow_nan=False)
    U = np.array(data.draw(st.lists(vals, min_size=3 * n, max_size=3 * n)))
    x_n = np.array(data.draw(st.lists(vals, min_size=N, max_size=N)))
    v_n = np.array(data.draw(st.lists(vals, min_size=N, max_size=N)))
    f = np.array([data.draw(st.lists(vals, min_size=N, max_size=N)) for _ in range(3)])
    modes = np.zeros(E, dtype=np.int64)
    modes[1] = mode_d
    return U, x_n, v_n, f, modes


@settings(max_examples=100)
@given(data=st.data(), h=st.floats(1e-4, 0.1), mode_d=st.integers(0, 2))
def test_stage_system_bit_for_bit(setup, data, h, mode_d):
    scene, js, system = setup
    U, x_n, v_n, f, modes = _inputs(scene, data, mode_d)
    kernels = [law_branches(el.law).kernel_for(int(modes[e]))
               for e, el in enumerate(scene.elements)]
    G_ref, J_ref = system.evaluate(list(U), h, list(x_n), list(v_n), f.tolist(), kernels)
    G, J, *_ = workspace(len(scene.nodes), len(scene.elements))
    A, W = np.array(tableau.A), np.array(tableau.W)
    stage_evaluate(js.module.branch_law, js.consts, js.masses, js.ea, js.eb, js.spring,
                   js.lock_q, modes,
                   A, W, U, h, x_n, v_n, f, G, J)
    assert G.tolist() == G_ref
    assert J.tolist() == J_ref


@pytest.mark.parametrize("mode_d", [0, 1, 2])
def test_stage_solve_bit_for_bit(setup, mode_d):
    scene, js, system = setup
    N, E = len(scene.nodes), len(scene.elements)
    rng = np.random.default_rng(mode_d)
    U = rng.uniform(-1.0, 1.0, 3 * (N + E))
    x_n, v_n = rng.uniform(-0.5, 0.5, N), rng.uniform(-0.5, 0.5, N)
    f = rng.uniform(-1.0, 1.0, (3, N))
    modes = np.array([0, mode_d, 0, 0], dtype=np.int64)
    scale = np.full(U.shape, 1e-3)
    kernels = [law_branches(el.law).kernel_for(int(modes[e]))
               for e, el in enumerate(scene.elements)]
    U_ref, it_ref, nfac_ref = system.solve(list(U), 1e-2, list(x_n), list(v_n), f.tolist(),
                                           kernels, list(scale), tol=1e-6, max_iters=10)
    ws = workspace(N, E)
    ok = compiled_stage_solve()(js.module.branch_law, js.consts, js.masses, js.ea, js.eb, js.spring,
                                js.lock_q, modes, np.array(tableau.A), np.array(tableau.W), U,
                                1e-2, x_n, v_n, f, scale, 1e-6, 10, *ws)
    assert ok == (U_ref is not None)
    assert tuple(ws[-1][:2]) == (it_ref, nfac_ref)
    if ok:
        assert U.tolist() == U_ref


def test_a_taut_string_is_held_on_the_velocity_level_bit_for_bit() -> None:
    # the locking branch of string_spring (q = L): both systems use L + h sum a dV
    scene = Scene([Mass("m1", 1.0, x0=0.1), Mass("m2", 2.0, x0=0.1 + 0.3)],
                  [Element("s", get_law("string_spring").bind(k=5.0, L=0.3), "m1", "m2"),
                   Element("k", get_law("linear_spring").bind(k=3.0), "ground", "m1")])
    js = jit_scene(scene)
    lb = law_branches(scene.elements[0].law)
    taut = next(i for i in range(lb.count) if lb.info[i].locks)
    assert js.lock_q[0, taut] == 0.3 and np.isnan(js.lock_q[1]).all()
    system = radau.StageSystem(scene.masses, scene.elem_a, scene.elem_b, [True, True])
    modes = np.array([taut, 0], dtype=np.int64)
    kernels = [lb.kernel_for(taut), law_branches(scene.elements[1].law).kernel_for(0)]
    rng = np.random.default_rng(7)
    U = rng.uniform(-1.0, 1.0, 12)
    x_n, v_n = np.array([0.1, 0.4]), np.array([0.2, 0.2])
    f = rng.uniform(-1.0, 1.0, (3, 2))
    h = 1e-7
    G_ref, J_ref = system.evaluate(list(U), h, list(x_n), list(v_n), f.tolist(), kernels)
    G, J, *_ = workspace(2, 2)
    stage_evaluate(js.module.branch_law, js.consts, js.masses, js.ea, js.eb, js.spring,
                   js.lock_q, modes,
                   np.array(tableau.A), np.array(tableau.W), U, h, x_n, v_n, f, G, J)
    assert G.tolist() == G_ref and J.tolist() == J_ref
    # the lock's residual is h sum_l a_kl (V_l,2 - V_l,1): no rounding of x in it
    for k in range(3):
        want = h * sum(tableau.A[k][j] * (U[j * 4 + 1] - U[j * 4]) for j in range(3))
        assert abs(G_ref[k * 4 + 2] - want) <= 4 * np.spacing(abs(want))
