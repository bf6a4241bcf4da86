"""Helpers shared by several test modules (not a test module itself)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    """Floats spread evenly in ``log10`` between ``lo`` and ``hi`` (both > 0)."""
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


def assert_columns_close(a: np.ndarray, b: np.ndarray, rel: float = 1e-12,
                         scale: np.ndarray | None = None) -> None:
    """``|a - b| <= rel * max(1, scale of the variable)``, column by column, every step
    (``scale``: the columns' scales when the caller knows better, e.g. forces set by a
    balance carry the round-off of the largest term in it)."""
    assert a.shape == b.shape
    if scale is None:
        scale = np.abs(b).max(axis=0)
    scale = np.maximum(1.0, scale)
    bad = np.abs(a - b) > rel * scale
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise AssertionError(f"row {r} column {c}: {a[r, c]!r} vs {b[r, c]!r}")
