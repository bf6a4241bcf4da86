"""How much code ``radau5``'s shared compiled loop makes numba and LLVM compile (counted in
functions typed and instructions emitted, never timed).

The loop (:func:`lumped.solvers.eventdriven.loop_jit.advance`) is compiled once per
machine. numba links the code of every function a compiled function calls into the
caller's module, where LLVM optimises and emits it again; the stage solve, the error
estimate and the guard test are compiled apart and called through their addresses, so
the loop's module holds its own code only. A call through an address is one indirect
call (no first-class function's fallback through Python at every call site), and the
shared loops are compiled without LLVM's loop vectorizer (their loops run over a scene's
few nodes and elements).
"""

from __future__ import annotations

import numpy as np
import pytest

from lumped.codegen.jit import njit, numba_enabled

pytestmark = pytest.mark.skipif(not numba_enabled(), reason="the compiled loop needs numba")

#: The stage Newton, the error estimate and the guard test, and what they call.
_APART = {"stage_solve", "stage_solve_at", "stage_evaluate", "step_error", "error_norm",
          "crossed", "lu_factor_into", "lu_solve_into"}


def _advance_signature():
    from lumped.solvers.eventdriven import loop_jit

    return loop_jit.advance_argument_types()


def _typed(py_func, args) -> dict:
    """numba's type inference of ``py_func`` for ``args`` (its untyped passes, then the
    typing; nothing lowered): the type of each variable. The functions it calls are
    compiled (or loaded) as numba types them."""
    from numba.core import registry
    from numba.core.compiler import CompilerBase, DefaultPassBuilder, Flags
    from numba.core.compiler_machinery import AnalysisPass, register_pass
    from numba.core.typed_passes import NopythonTypeInference

    @register_pass(mutates_CFG=False, analysis_only=True)
    class TypesOnly(AnalysisPass):
        _name = f"lumped_types_only_{id(py_func)}"

        def __init__(self) -> None:
            AnalysisPass.__init__(self)

        def run_pass(self, state) -> bool:
            state.cr = state.typemap  # (the result: the pipeline ends here)
            return False

    class TypingOnly(CompilerBase):
        def define_pipelines(self):
            pm = DefaultPassBuilder.define_untyped_pipeline(self.state)
            pm.add_pass(NopythonTypeInference, "the typing")
            pm.add_pass(TypesOnly, "the types as the result")
            pm.finalize()
            return [pm]

    target = registry.cpu_target
    return TypingOnly(target.typing_context, target.target_context, None, args, None,
                      Flags(), {}).compile_extra(py_func)


def test_the_shared_loop_calls_the_stage_solve_error_and_guard_test_through_addresses():
    # the compiled functions the loop calls, whose code numba would link into the loop's
    # module (before: the stage solve, the error estimate and the guard test, with the
    # stage system, the LU and the error norm inside them; about 4 s of LLVM of a first
    # run, half of it the second copy in the loop's module)
    from numba.core import types

    from lumped.solvers.eventdriven import loop_jit

    typemap = _typed(loop_jit.advance, _advance_signature())
    called = {ty.dispatcher.py_func.__name__ for ty in typemap.values()
              if isinstance(ty, types.Dispatcher)}
    assert "forces" in called
    assert not called & _APART, called & _APART


def _twice(i, a):
    return 2.0 * a[i]


def test_a_call_through_an_address_is_one_indirect_call():
    # a function called through its address (as the loop calls the scene's kernels and
    # the functions compiled apart): the same number, and no code that takes the GIL to
    # ask Python for an address (before, numba emitted that at every call site of a
    # first-class function)
    from numba import types

    from lumped.codegen.function_types import compiled_address, function_at

    ftype = types.FunctionType(types.float64(types.int64, types.float64[::1]))
    addr = compiled_address([], _twice, ftype)
    at = function_at(ftype)

    @njit
    def call(addr, a):
        return at(addr)(1, a) + at(addr)(2, a)

    assert call(addr, np.array([1.0, 2.5, -3.0])) == 2.0 * 2.5 + 2.0 * -3.0
    ir = call.inspect_llvm(call.signatures[0])
    assert "gil_ensure" not in ir  # (numba_gil_ensure: taking the GIL)
    assert "PyObject_CallFunctionObjArgs" not in ir  # (asking a Python object)


def _square_up(a) -> None:
    for i in range(a.shape[0]):
        a[i] = a[i] * a[i] + 1.0


def test_scalar_loops_compiles_without_the_loop_vectorizer_and_sets_it_back():
    from numba.core import config

    from lumped.codegen.function_types import scalar_loops

    before = config.LOOP_VECTORIZE
    plain = njit(_square_up)
    plain.compile("none(float64[::1])")
    with scalar_loops():
        assert config.LOOP_VECTORIZE == 0
        scalar = njit(_square_up)
        scalar.compile("none(float64[::1])")
    assert config.LOOP_VECTORIZE == before
    vector = "x double>"
    if before:  # (a machine whose numba vectorizes loops at all)
        assert vector in plain.inspect_llvm(plain.signatures[0])
    assert vector not in scalar.inspect_llvm(scalar.signatures[0])
    a, b = np.linspace(-1.0, 1.0, 37), np.linspace(-1.0, 1.0, 37)
    plain(a)
    scalar(b)
    assert np.array_equal(a, b)


def test_a_new_law_template_compiles_no_branch_kernel_apart(monkeypatch, tmp_path):
    # a law template's branch kernels and guards are inlined (numba's IR) into its
    # dispatchers t_law and t_guards (lumped.codegen.template_module; a scene module's
    # branch_law and branch_guards before): compiled there once, not each on its own as
    # well (before: each a compilation of its own, wrappers and LLVM, about 0.05 s
    # apiece, 14 of them for the 3-mass chain)
    import re

    from numba.core import config, event

    from lumped import Element, Mass, Scene, get_law, simulate
    from lumped.scene.forcing import SineBurst

    simulate(Scene([Mass("m", m=1.0, x0=0.0)],
                   [Element("k", get_law("linear_spring").bind(k=10.0), "ground", "m")]),
             method="radau5", t_end=0.1, compiled=True)  # the shared loop, compiled or loaded
    # a structure no other test builds: a Bingham chain of two masses, each on a spring
    # and a Coulomb slider, loaded on the second
    lin, bing, coul = get_law("linear_spring"), get_law("bingham"), get_law("coulomb")
    scene = Scene([Mass("p", m=1.3, x0=0.0), Mass("r", m=0.7, x0=0.0)],
                  [Element("k1", lin.bind(k=31.0), "ground", "p"),
                   Element("b1", bing.bind(gamma=0.9, tau=0.45), "ground", "p"),
                   Element("k2", lin.bind(k=23.0), "p", "r"),
                   Element("c2", coul.bind(tau=0.3, r=1.0), "p", "r")],
                  {"r": SineBurst(4.0, 6.0, 0.7)})
    monkeypatch.setattr(config, "CACHE_DIR", str(tmp_path))  # (numba's disk cache: empty)
    monkeypatch.setenv("LUMPED_CACHE_DIR", str(tmp_path))  # (no template module either)
    with event.install_recorder("numba:compile") as rec:
        got = simulate(scene, method="radau5", t_end=0.4, rtol=1e-6, compiled=True)
    assert got.stats["loop"] == "compiled" and got.ok
    names = [ev.data["dispatcher"].py_func.__qualname__ for _, ev in rec.buffer
             if ev.is_start and ev.data["dispatcher"].py_func.__module__.startswith(
                 "lumped_jit_")]
    assert names.count("t_law") == 3 and names.count("t_guards") == 3  # (three templates)
    assert not [n for n in names if re.fullmatch(r"(branch|guards)_\d+_\d+", n)], names
