"""Helpers shared by several test modules (not a test module itself)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import strategies as st


def log_uniform(lo: float, hi: float) -> st.SearchStrategy[float]:
    """Floats spread evenly in ``log10`` between ``lo`` and ``hi`` (both > 0)."""
    return st.floats(math.log10(lo), math.log10(hi)).map(lambda e: 10.0**e)


def assert_columns_close(a: np.ndarray, b: np.ndarray, rel: float = 1e-12) -> None:
    """``|a - b| <= rel * max(1, scale of the variable)``, column by column, every step."""
    assert a.shape == b.shape
    scale = np.maximum(1.0, np.abs(b).max(axis=0))
    bad = np.abs(a - b) > rel * scale
    if bad.any():
        r, c = np.argwhere(bad)[0]
        raise AssertionError(f"row {r} column {c}: {a[r, c]!r} vs {b[r, c]!r}")
