"""Progress bars for long work, shown only when someone watches: stderr is a terminal.

Every long command (``bench``, ``generate``, ``servo``, ``reach``...) goes through :func:`bar`, so
logs, pipes, CI and notebooks get no bar and no carriage-return noise, whatever the caller asked.
"""

from __future__ import annotations

import sys
from collections.abc import Iterable
from typing import Any

__all__ = ["bar", "progress_shown"]


def progress_shown(requested: bool = True) -> bool:
    """True when a bar was requested and stderr is a terminal."""
    if not requested:
        return False
    isatty = getattr(sys.stderr, "isatty", None)
    try:
        return bool(isatty and isatty())
    except (ValueError, OSError):  # a closed or detached stream
        return False


def bar(iterable: Iterable[Any] | None = None, progress: bool = True, **kwargs: Any) -> Any:
    """A ``tqdm`` bar over ``iterable`` (``leave=False`` unless given), disabled unless
    :func:`progress_shown`; it writes to stderr."""
    from tqdm import tqdm

    kwargs.setdefault("leave", False)
    return tqdm(iterable, disable=not progress_shown(progress), file=sys.stderr, **kwargs)
