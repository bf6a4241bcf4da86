r"""Numba function types of the generated kernels, and calls through their addresses.

The compiled loops are compiled once for every scene; a scene's generated kernels reach
them as plain integers, the addresses of their C wrappers, and :func:`function_at` turns
such an address back into a callable first-class function of a known type:

* :data:`BRANCH_LAW_TYPE` (:func:`law_type`): ``branch_law(e, i, q, F, c) -> (R, dR/dq,
  dR/dF)``, element ``e`` held on branch ``i``;
* :func:`guards_type`: ``branch_guards(e, i, q, F, out, c) -> count``, the guard values
  of element ``e`` on branch ``i`` written into ``out``;
* :func:`branch_type`: ``active_branch(e, q, F, c) -> int``.

``c`` is the scene's array of law constants (:attr:`lumped.codegen.jit.JitScene.consts`):
the laws' numbers reach the compiled code at run time, so one compiled module serves
every value of them.
"""

from __future__ import annotations

import functools

from .jit import numba_module

__all__ = ["BRANCH_LAW_TYPE", "function_at", "compiled_address", "law_type", "guards_type",
           "branch_type"]

if numba_module is not None:
    from numba import types as _T

    _f8 = _T.float64
    #: ``branch_law(e, i, q, F, c) -> (R, dR/dq, dR/dF)`` as a numba function type.
    BRANCH_LAW_TYPE = _T.FunctionType(_T.UniTuple(_f8, 3)(_T.int64, _T.int64, _f8, _f8,
                                                          _f8[::1]))
else:  # pragma: no cover - without numba
    BRANCH_LAW_TYPE = None


def function_at(ftype):
    """An intrinsic ``addr -> ftype``: the first-class function whose C wrapper is at
    ``addr`` (:func:`numba.experimental.function_type._get_wrapper_address`), as numba
    unboxes a function argument, without its Python object (``py_addr``) and jit
    address (``jit_addr``, 0 for a wrapper-address object): calls go through the C
    wrapper, as they do for such an argument."""
    from numba.core import cgutils
    from numba.extending import intrinsic

    @intrinsic
    def at(typingctx, addr):
        def codegen(context, builder, signature, args):
            fn = cgutils.create_struct_proxy(ftype)(context, builder)
            voidptr = context.get_value_type(_T.voidptr)
            fn.c_addr = builder.inttoptr(args[0], voidptr)
            fn.py_addr = cgutils.get_null_value(voidptr)
            fn.jit_addr = cgutils.get_null_value(voidptr)
            return fn._getvalue()

        return ftype(_T.int64), codegen

    return at


def compiled_address(kept: list, py_func, ftype) -> int:
    """The address of ``py_func`` compiled for ``ftype``'s signature, for a loop that calls
    it through :func:`function_at`: compiled the first time a process asks (numba's disk
    cache after the first time on a machine) and kept in ``kept`` (the caller's list,
    ``[(address, dispatcher)]``, so that the dispatcher lives as long as its address)."""
    if not kept:
        from numba.experimental.function_type import _get_wrapper_address

        from .jit import njit

        disp = njit(ftype.signature, cache=True)(py_func)
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
