"""A bounded memo: the per-law caches of code generation (:mod:`.branches`,
:mod:`.parametric`, :mod:`.templates`) keep at most a bound of entries, since a sweep of
new numbers binds a new law per point and would otherwise keep every one for good."""

from __future__ import annotations

from collections.abc import Hashable

__all__ = ["remember"]


def remember(cache: dict, key: Hashable, value: object, bound: int) -> None:
    """``cache[key] = value``, having first dropped the oldest entries (a dict's insertion
    order) down to half of ``bound`` when ``cache`` holds ``bound`` or more. An unhashable
    ``key`` raises ``TypeError``, as the dict does."""
    if len(cache) >= bound:
        for old in list(cache)[:len(cache) - bound // 2]:
            cache.pop(old, None)
    cache[key] = value
