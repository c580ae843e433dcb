"""The one bounded memo of loaded kinematics objects (chains, trees and closed-form solvers), so
compiling the same model again in a process returns the same object without growing memory."""

from __future__ import annotations

from collections import OrderedDict
from collections.abc import Callable, Hashable
from typing import Any

__all__ = ["LOADED_MAX", "memoised", "clear"]

LOADED_MAX = 256  # objects kept; the least recently used goes first
_LOADED: OrderedDict[Hashable, Any] = OrderedDict()


def memoised(key: Hashable, make: Callable[[], Any], use: bool = True) -> Any:
    """The object memoised under ``key``, else ``make()`` (memoised when ``use``)."""
    if use and key in _LOADED:
        _LOADED.move_to_end(key)
        return _LOADED[key]
    obj = make()
    if use:
        _LOADED[key] = obj
        while len(_LOADED) > LOADED_MAX:
            _LOADED.popitem(last=False)
    return obj


def clear() -> None:
    """Forget every memoised object (they stay valid where still referenced)."""
    _LOADED.clear()
