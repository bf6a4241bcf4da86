"""The progress bar of a sweep (``tqdm`` when installed and asked for)."""

from __future__ import annotations

import sys

__all__ = ["progress_bar"]


class _NoBar:
    """A bar that shows nothing."""

    def update(self, k: int) -> None:
        pass

    def close(self) -> None:
        pass


def progress_bar(total: int, show: bool):
    """A ``tqdm`` bar over ``total`` scenes on stderr when ``show`` and tqdm is installed,
    else one that shows nothing (both have ``update(k)`` and ``close()``)."""
    if not show:
        return _NoBar()
    try:
        from tqdm import tqdm
    except ImportError:
        return _NoBar()
    return tqdm(total=total, unit="scene", file=sys.stderr)
