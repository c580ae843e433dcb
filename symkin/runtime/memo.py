"""The one bounded memo of loaded kinematics objects (chains, trees and closed-form solvers), so
compiling the same model again in a process returns the same object without growing memory; and
the bounded memo of what is made per kinematics object and options (IK solvers, C controllers)."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable, MutableMapping
from typing import Any

__all__ = ["LOADED_MAX", "memoised", "clear", "lru", "bounded", "per_object"]

LOADED_MAX = 256  # objects kept; the least recently used goes first
_LOADED: OrderedDict[Hashable, Any] = OrderedDict()


def memoised(key: Hashable, make: Callable[[], Any], use: bool = True) -> Any:
    """The object memoised under ``key``, else ``make()`` (memoised when ``use``)."""
    return lru(_LOADED, key, make, LOADED_MAX) if use else make()


def lru(store: OrderedDict, key: Hashable, make: Callable[[], Any], keep: int) -> Any:
    """``store[key]`` (now the most recently used), else ``make()`` stored there, the least recently
    used entries dropped beyond ``keep``."""
    if key in store:
        store.move_to_end(key)
        return store[key]
    obj = store[key] = make()
    while len(store) > keep:
        store.popitem(last=False)
    return obj


def clear() -> None:
    """Forget every memoised object (they stay valid where still referenced)."""
    _LOADED.clear()


def bounded(cache: dict, key: Any, make: Callable[[], Any]) -> Any:
    """``cache[key]``, else ``make()`` stored there (at most 64 keys: then the cache is emptied
    first); made and not stored when ``key`` is unhashable."""
    try:
        found = cache.get(key)
    except TypeError:
        return make()
    if found is None:
        if len(cache) > 64:
            cache.clear()
        found = cache[key] = make()
    return found


def per_object(table: MutableMapping, obj: Any, key: Any, make: Callable[[], Any]) -> Any:
    """:func:`bounded` on the dict of ``obj`` in ``table`` (a WeakKeyDictionary, say); made and not
    stored when ``obj`` cannot be a key (no weak references)."""
    try:
        cache = table.setdefault(obj, {})
    except TypeError:
        return make()
    return bounded(cache, key, make)
