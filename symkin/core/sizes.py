"""The one rule for sizes a user asks for: numbers of samples, steps, blocks, orientations,
searches, points (leaf module).

A size is checked before anything is allocated or any long work starts: :func:`count` takes an
integer (a Python or NumPy integer, or a float with an integral value) within bounds, and
:func:`room` refuses a request whose arrays would not fit in this machine's memory
(:func:`stored`: nor on the disk of the store that keeps them); :func:`read_bounded` reads an
input file only up to a size (:func:`read_text`: a UTF-8 text file). They raise
a :class:`~symkin.errors.SymkinError` subclass naming the size (ParameterError unless the caller
passes its own), never ``MemoryError``, ``OverflowError`` or NumPy's "Maximum allowed size
exceeded".
"""

from __future__ import annotations

import math
import numbers
import os
from functools import lru_cache
from typing import Any

from symkin.errors import ParameterError, SymkinError

__all__ = ["MAX_COUNT", "count", "memory_bytes", "room", "stored", "read_bounded", "read_text", "human_bytes"]

#: The largest count any size may take: beyond 2**53 integers are not exact as doubles, and
#: no machine holds that many samples anyway.
MAX_COUNT = 2**53

#: Assumed when the operating system does not tell the size of its memory.
_FALLBACK_MEMORY = 2**40


@lru_cache(maxsize=1)
def memory_bytes() -> int:
    """This machine's physical memory in bytes (``sysconf``), else 1 TiB when it cannot be read."""
    try:
        size = os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES")
    except (AttributeError, ValueError, OSError):
        return _FALLBACK_MEMORY
    return int(size) if size > 0 else _FALLBACK_MEMORY


def human_bytes(n: float) -> str:
    """``n`` bytes as text: ``"512 B"``, ``"15.6 GiB"``, ``"8.7e+21 B"``."""
    if not math.isfinite(n) or n >= 2**60:
        return f"{n:.3g} B"
    for unit, scale in (("GiB", 2**30), ("MiB", 2**20), ("KiB", 2**10)):
        if n >= scale:
            return f"{n / scale:.1f} {unit}"
    return f"{int(n)} B"


def count(
    value: Any,
    what: str,
    minimum: int = 1,
    maximum: int = MAX_COUNT,
    error: type[SymkinError] = ParameterError,
) -> int:
    """``value`` as an int in ``minimum .. maximum``, else ``error`` naming ``what``. Accepts Python
    and NumPy integers and floats with an integral value (``1e6``); refuses bools, NaN, inf,
    fractions and anything else."""
    ok = isinstance(value, (numbers.Integral, numbers.Real)) and not isinstance(value, bool)
    if ok and not isinstance(value, numbers.Integral):
        ok = math.isfinite(value) and float(value).is_integer()
    if type(value).__name__ == "bool_":  # numpy.bool_ is not a numbers.Integral, but be explicit
        ok = False
    if not ok:
        raise error(f"{what} must be an integer, got {value!r}")
    v = int(value)
    if not minimum <= v <= maximum:
        raise error(f"{what} must be an integer from {minimum} to {maximum}, got {v}")
    return v


def room(nbytes: float, what: str, error: type[SymkinError] = ParameterError) -> None:
    """``error`` naming ``what`` when ``nbytes`` (what the request's arrays take; may be a float,
    inf too) exceed this machine's memory."""
    limit = memory_bytes()
    if not nbytes <= limit:
        raise error(
            f"{what} needs {human_bytes(nbytes)}, more than this machine's memory ({human_bytes(limit)}): "
            "ask for fewer"
        )


def stored(path: Any, nbytes: float, what: str, error: type[SymkinError] = ParameterError) -> None:
    """``error`` naming ``what`` when ``nbytes`` would not fit where they are kept: in memory for
    ``path`` None, else on the disk holding the folder or file ``path`` (its whole capacity; a
    URL such as ``s3://...`` is not checked)."""
    if path is None:
        room(nbytes, what, error)
        return
    import shutil
    from pathlib import Path

    if "://" in str(path):
        return
    folder = Path(path).expanduser().absolute()
    while not folder.exists() and folder != folder.parent:
        folder = folder.parent
    try:
        total = shutil.disk_usage(folder).total
    except OSError:
        return
    if not nbytes <= total:
        raise error(
            f"{what} needs {human_bytes(nbytes)}, more than the whole disk holding {path} "
            f"({human_bytes(total)}): ask for fewer"
        )


def read_bounded(path: Any, limit: int, what: str, error: type[Exception] = ParameterError) -> bytes:
    """The bytes of the file at ``path``, reading at most ``limit`` + 1 of them: ``error`` naming
    ``what`` for a larger file (or an endless one such as ``/dev/zero``) before it fills memory.
    OSError as ``open`` raises it."""
    with open(path, "rb") as f:
        data = f.read(limit + 1)
    if len(data) > limit:
        raise error(f"{what} is larger than {human_bytes(limit)}: not an input symkin reads")
    return data


def read_text(path: Any, limit: int, what: str, error: type[Exception]) -> str:
    """The text of the UTF-8 file at ``path`` read by :func:`read_bounded` (a byte-order mark
    dropped, newlines as ``Path.read_text`` reads them): ``error`` naming ``what`` (``"URDF file
    'arm.urdf'"``) when it cannot be read, is larger than ``limit`` bytes or is not UTF-8."""
    try:
        data = read_bounded(path, limit, "the file", OSError)  # named below
        return data.decode("utf-8-sig").replace("\r\n", "\n").replace("\r", "\n")
    except UnicodeDecodeError as exc:
        raise error(f"{what} is not UTF-8 text: {exc.reason} at byte {exc.start}") from None
    except (OSError, ValueError) as exc:  # ValueError: a NUL in the path
        raise error(f"cannot read {what}: {getattr(exc, 'strerror', None) or exc}") from None
