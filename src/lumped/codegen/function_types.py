r"""Numba function types of the generated kernels, and calls through their addresses.

The compiled loops are compiled once for every scene; a scene's generated kernels reach
them as plain integers, the addresses of their C wrappers, and :func:`function_at` turns
such an address back into a callable first-class function of a known type:

* :data:`BRANCH_LAW_TYPE` (:func:`law_type`): ``branch_law(e, i, q, F, c) -> (R, dR/dq,
  dR/dF)``, element ``e`` held on branch ``i``;
* :func:`guards_type`: ``branch_guards(e, i, q, F, out, c) -> count``, the guard values
  of element ``e`` on branch ``i`` written into ``out``;
* :func:`branch_type`: ``active_branch(e, q, F, c) -> int``;
* :func:`template_law_type`, :func:`template_guards_type`, :func:`template_select_type`:
  the same three for one law template, ``c`` a pointer to its element's constants and
  ``out`` a pointer (``t_law(i, q, F, c)``, ``t_guards(i, q, F, out, c)``,
  ``t_select(q, F, c)``; :mod:`lumped.codegen.template_module`), called at their jit
  entries (:func:`call_jit_at`, :func:`jit_address`).

``c`` is the scene's array of law constants (:attr:`lumped.codegen.jit.JitScene.consts`):
the laws' numbers reach the compiled code at run time, so one compiled module serves
every value of them.
"""

from __future__ import annotations

import contextlib
import functools

from .jit import numba_module

__all__ = ["BRANCH_LAW_TYPE", "function_at", "call_jit_at", "jit_address", "compiled_address",
           "law_type", "guards_type", "branch_type", "scalar_loops", "template_law_type",
           "template_guards_type", "template_select_type", "template_full_law_type",
           "template_magnitude_type", "step_evaluate_type", "element_law_type", "data_at"]

if numba_module is not None:
    from numba import types as _T

    _f8 = _T.float64
    #: ``branch_law(e, i, q, F, c) -> (R, dR/dq, dR/dF)`` as a numba function type.
    BRANCH_LAW_TYPE = _T.FunctionType(_T.UniTuple(_f8, 3)(_T.int64, _T.int64, _f8, _f8,
                                                          _f8[::1]))
else:  # pragma: no cover - without numba
    BRANCH_LAW_TYPE = None


def function_at(ftype):
    """An intrinsic ``addr -> function``: the function whose C wrapper is at ``addr``
    (:func:`numba.experimental.function_type._get_wrapper_address`), of the signature of
    the numba function type ``ftype``, called as a plain C function pointer.

    Its value is not a numba first-class function (a ``ftype``) but a pointer of the
    type of a ctypes function (:class:`_AddressCall`): a call is one indirect call. A
    first-class function's call also checks its jit address and, at a null C address,
    takes the GIL and asks its Python object for one; that code is emitted, and
    compiled, at every call site. The callee (the C wrapper) and the numbers are the
    same."""
    from numba.extending import intrinsic

    ptype = _address_call_type(ftype.signature)

    @intrinsic
    def at(typingctx, addr):
        def codegen(context, builder, signature, args):
            return builder.inttoptr(args[0], context.get_value_type(ptype))

        return ptype(_T.int64), codegen

    return at


def call_jit_at(ftype):
    """An intrinsic ``(addr, *args) -> result``: a call of the numba-compiled function
    whose *jit* entry is at ``addr`` (:func:`jit_address`), of the signature of the numba
    function type ``ftype``, with numba's own calling convention.

    :func:`function_at` calls a function's C wrapper, which in turn calls the function
    itself; here the caller calls the function directly (what numba does for a
    first-class function whose jit address it knows). For callees that cannot raise (the
    generated kernels: ``error_model="numpy"``, no bounds checks); a callee's error
    status is not read."""
    from numba.extending import intrinsic

    sig = ftype.signature

    def codegen(context, builder, signature, args):
        llty = context.call_conv.get_function_type(sig.return_type, sig.args).as_pointer()
        fn = builder.inttoptr(args[0], llty)
        _, res = context.call_conv.call_function(builder, fn, sig.return_type, sig.args,
                                                 args[1:])
        return res

    typed = sig.return_type(_T.int64, *sig.args), codegen
    # (an intrinsic takes no star arguments: one definition per arity)
    if len(sig.args) == 3:
        def call(typingctx, addr, a0, a1, a2):
            return typed
    elif len(sig.args) == 4:
        def call(typingctx, addr, a0, a1, a2, a3):
            return typed
    elif len(sig.args) == 5:
        def call(typingctx, addr, a0, a1, a2, a3, a4):
            return typed
    else:  # pragma: no cover - the templates' types have 3 to 5 arguments
        raise ValueError(f"call_jit_at: no intrinsic of {len(sig.args)} arguments")
    return intrinsic(call)


def jit_address(dispatcher, ftype) -> int:
    """The address of ``dispatcher``'s function itself (numba's calling convention, for
    :func:`call_jit_at`) compiled for ``ftype``'s signature (compiled, or loaded from
    numba's disk cache, if not yet)."""
    from numba.experimental.function_type import _get_jit_address

    return _get_jit_address(dispatcher, ftype.signature)


def _no_pointer(obj):  # pragma: no cover - a value of _AddressCall never comes from Python
    raise TypeError("a compiled function's address comes from compiled_address")


@functools.cache
def _address_call_type(sig):
    """The numba type of a C function pointer of signature ``sig`` (one per signature)."""
    return _AddressCall(sig)


if numba_module is not None:
    from numba.core.datamodel.models import ExternalFuncPointerModel
    from numba.extending import register_model

    class _AddressCall(_T.ExternalFunctionPointer):
        """A C function pointer of signature ``sig`` (numba lowers a call to it as a
        ctypes function's: one indirect call); pickled by its signature (numba's disk
        cache keeps the signatures of the functions that take one)."""

        def __init__(self, sig) -> None:
            super().__init__(sig, get_pointer=_no_pointer)

        def __reduce__(self):
            return _address_call_type, (self.sig,)

    register_model(_AddressCall)(ExternalFuncPointerModel)


@contextlib.contextmanager
def scalar_loops():
    """Compile without LLVM's loop vectorizer (``numba.core.config.LOOP_VECTORIZE``, which
    numba reads at each compile; set back after, under numba's compiler lock so no other
    thread's compile sees it).

    The shared loops run over a scene's few nodes and elements (3 to a few dozen): a
    vectorized loop body, its remainder loop and its run-time checks of overlap never
    pay there, and they were about a third of the LLVM time of ``radau5``'s loop (1.5 s
    of a first run). Vectorizing reorders no floating-point sum (LLVM does so only
    under fast-math), so the numbers are the same."""
    from numba.core import config
    from numba.core.compiler_lock import global_compiler_lock

    with global_compiler_lock:
        before = config.LOOP_VECTORIZE
        config.LOOP_VECTORIZE = 0
        try:
            yield
        finally:
            config.LOOP_VECTORIZE = before


def compiled_address(kept: list, py_func, ftype) -> int:
    """The address of ``py_func`` compiled for ``ftype``'s signature, for a loop that calls
    it through :func:`function_at`: compiled the first time a process asks (numba's disk
    cache after the first time on a machine) and kept in ``kept`` (the caller's list,
    ``[(address, dispatcher)]``, so that the dispatcher lives as long as its address)."""
    if not kept:
        from numba.experimental.function_type import _get_wrapper_address

        from .jit import njit

        with scalar_loops():  # (called through its address only: no Python wrapper)
            disp = njit(ftype.signature, cache=True, no_cpython_wrapper=True)(py_func)
        kept.append((_get_wrapper_address(disp, ftype.signature), disp))
    return kept[0][0]


def law_type():
    """The numba function type of ``branch_law(e, i, q, F, c) -> (R, dR/dq, dR/dF)``."""
    return BRANCH_LAW_TYPE


@functools.cache
def guards_type():
    """The numba function type of ``branch_guards(e, i, q, F, out, c) -> count`` (made
    once: a run's compiled parts ask for it per scene)."""
    f8 = _T.float64
    return _T.FunctionType(_T.int64(_T.int64, _T.int64, f8, f8, f8[::1], f8[::1]))


@functools.cache
def branch_type():
    """The numba function type of ``active_branch(e, q, F, c) -> int`` (made once)."""
    f8 = _T.float64
    return _T.FunctionType(_T.int64(_T.int64, f8, f8, f8[::1]))


@functools.cache
def template_law_type():
    """The numba function type of a template's ``t_law(i, q, F, c) -> (R, dR/dq, dR/dF)``
    (``c`` a pointer to its element's constants)."""
    f8, p = _T.float64, _T.CPointer(_T.float64)
    return _T.FunctionType(_T.UniTuple(f8, 3)(_T.int64, f8, f8, p))


@functools.cache
def template_guards_type():
    """The numba function type of a template's ``t_guards(i, q, F, out, c) -> count``
    (``out`` and ``c`` pointers)."""
    f8, p = _T.float64, _T.CPointer(_T.float64)
    return _T.FunctionType(_T.int64(_T.int64, f8, f8, p, p))


@functools.cache
def template_select_type():
    """The numba function type of a template's ``t_select(q, F, c) -> int``."""
    f8, p = _T.float64, _T.CPointer(_T.float64)
    return _T.FunctionType(_T.int64(f8, f8, p))


@functools.cache
def template_full_law_type():
    """The numba function type of a law module's ``t_full(q, F, c) -> (R, dR/dq, dR/dF)``
    (:func:`~lumped.codegen.template_module.law_addresses`; ``c`` a pointer)."""
    f8, p = _T.float64, _T.CPointer(_T.float64)
    return _T.FunctionType(_T.UniTuple(f8, 3)(f8, f8, p))


@functools.cache
def template_magnitude_type():
    """The numba function type of a law module's ``t_mag(q, F, c) -> M``."""
    f8, p = _T.float64, _T.CPointer(_T.float64)
    return _T.FunctionType(f8(f8, f8, p))


@functools.cache
def step_evaluate_type():
    """The numba function type of the BDF step system ``evaluate(u, p, G, J, S,
    roundoff) -> None`` (:mod:`lumped.codegen.jit`; the type the shared step loop,
    :mod:`lumped.solvers.bdf.core_jit`, takes)."""
    f8 = _T.float64
    return _T.FunctionType(_T.none(f8[::1], f8[::1], f8[::1], f8[:, ::1], f8[::1],
                                   _T.boolean))


@functools.cache
def element_law_type():
    """The numba function type of ``element_law(e, q, F, c) -> (R, dR/dq, dR/dF)``."""
    f8 = _T.float64
    return _T.FunctionType(_T.UniTuple(f8, 3)(_T.int64, f8, f8, f8[::1]))


def data_at():
    """An intrinsic ``(a, k) -> pointer``: the address of ``a[k]`` (``a`` a contiguous
    float64 array) as a ``CPointer(float64)``; nothing is checked and nothing but the
    array's data pointer is read."""
    from numba.extending import intrinsic

    def codegen(context, builder, signature, args):
        array = context.make_array(signature.args[0])(context, builder, args[0])
        return builder.gep(array.data, [args[1]])

    @intrinsic
    def at(typingctx, a, k):
        return _T.CPointer(_T.float64)(a, _T.int64), codegen

    return at
