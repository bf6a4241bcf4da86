"""Counting numba's compilations in a block of a test (never timing them)."""

from __future__ import annotations

import contextlib


@contextlib.contextmanager
def compiles():
    """The functions numba compiles in the block, as ``module.qualname`` (cache loads are
    not compilations)."""
    from numba.core import event

    names: list[str] = []
    with event.install_recorder("numba:compile") as rec:
        yield names
    for _, ev in rec.buffer:
        if ev.is_start:
            fn = ev.data["dispatcher"].py_func
            names.append(f"{fn.__module__}.{fn.__qualname__}")
