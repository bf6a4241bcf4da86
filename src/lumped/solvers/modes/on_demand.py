r"""Shared compiled helpers compiled once per machine, and only when a run needs them.

The compiled loop of ``radau5`` (:mod:`lumped.solvers.eventdriven.loop_jit`) is helped at
its events by compiled twins of Python references: the mode probe
(:func:`lumped.solvers.modes.mode_guess_jit.probe_modes`), the break-out scan and root of a
stuck interval (:mod:`lumped.solvers.modes.stuck_jit`) and the single attempts of a
landing. Each is compiled once for every scene (its signature takes the scene's kernels
as addresses) and kept in numba's disk cache; each gives the numbers of its reference bit
for bit. A first run on a fresh machine needs them a handful of times, where the
reference costs microseconds to a millisecond a call and numba seconds of CPU to compile
each; so :class:`OnDemand` hands out the compiled helper when it is in numba's disk cache
(a load, nothing compiled), and otherwise ``None`` (the caller runs the reference) until
the process has asked for it :data:`AFTER` times, when it compiles it (once per machine).
"""

from __future__ import annotations

from collections.abc import Callable

from ...codegen.jit import njit, numba_enabled

__all__ = ["AFTER", "OnDemand", "compile_all", "compiled_once", "from_disk"]

#: Calls of a shared helper that run its Python reference, in one process, before the
#: helper is compiled (when numba's disk cache does not hold it). A reference costs about
#: 0.1-0.2 ms a call more than the compiled helper, which costs 1-3 s of CPU to compile,
#: once per machine: after this many calls a process has spent about a tenth of that in
#: the references. (The 3-mass chain of the benchmarks asks about 200 times a run for the
#: crossing root of its landing attempts, 30 times for the probe.)
AFTER = 1000


def compiled_once(store: list, py_func: Callable, signature: Callable, compile: bool = True,
                  **options):
    """``py_func`` compiled for the numba signature ``signature()`` once per process (kept
    in ``store``; numba's disk cache after the first time on a machine), or ``None``
    without numba. With ``compile=False`` it is only loaded from numba's disk cache: the
    dispatcher if the cache holds it (nothing compiled), else ``None`` (nothing kept).
    ``options``: more of numba's ``jit`` options (``no_cfunc_wrapper``)."""
    if not numba_enabled():
        return None
    if not store:
        if compile:
            store.append(njit(signature(), cache=True, **options)(py_func))
        else:
            got = from_disk(py_func, signature(), **options)
            if got is None:
                return None
            store.append(got)
    return store[0]


def from_disk(py_func: Callable, sig, **options):
    """A dispatcher of ``py_func`` with the overload for ``sig`` loaded from numba's disk
    cache, as :meth:`numba.core.dispatcher.Dispatcher.compile` loads it, or ``None`` when
    the cache does not hold it (then nothing is compiled). These are numba's internal
    calls: where a numba version lacks them, the answer is ``None`` (the reference runs,
    and the helper is compiled at :data:`AFTER` calls as where the cache is empty)."""
    disp = njit(cache=True, **options)(py_func)
    try:
        cres = disp._cache.load_overload(sig, disp.targetctx)
    except (AttributeError, TypeError):  # numba's internals changed: compile later
        return None
    if cres is None:
        return None
    disp.targetctx.insert_user_function(cres.entry_point, cres.fndesc, [cres.library])
    disp.add_overload(cres)
    disp.disable_compile()  # (as a dispatcher made with its signature)
    return disp


class OnDemand:
    """A shared compiled helper, compiled when a process needs it often.

    ``make(compile)`` is the helper's ``compiled_*`` function (:func:`compiled_once`).
    :meth:`get` returns the compiled helper when numba's disk cache holds it (looked up
    at the first call) or once it has been asked for ``after`` times in this process
    (then compiled: about a second or more of CPU, once per machine), else ``None``: the
    caller runs the Python reference, which gives the same numbers."""

    def __init__(self, make: Callable[[bool], Callable | None], after: int | None = None
                 ) -> None:
        self.make = make
        self.after = after
        self.calls = 0
        self.fn: Callable | None = None
        _ALL.append(self)

    def get(self) -> Callable | None:
        fn = self.fn
        if fn is None:
            self.calls += 1
            after = AFTER if self.after is None else self.after
            if self.calls == 1 or self.calls >= after:
                fn = self.fn = self.make(self.calls >= after)
        return fn


_ALL: list[OnDemand] = []


def compile_all() -> None:
    """Compile (or load from numba's disk cache) every shared helper made on demand, now
    (``lumped warm``: a machine warmed ahead runs every later run fully compiled)."""
    for helper in _ALL:
        helper.fn = helper.make(True)
