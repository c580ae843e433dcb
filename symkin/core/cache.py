"""The compile cache folder, atomic writes into it and its verified JSON store (leaf module).

Every file symkin reads back from its cache is verified before use and made again when it does
not verify; a cache that cannot be written (full, read-only, not a folder) only costs speed. The
JSON entries of this module (generated sources, OSQP sources, clearance proofs) carry a sha256 of
their kind, their key and their content, so an entry that was truncated, edited (one flipped
digit still parses) or copied under another key is recomputed, never used.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import os
import re
from collections.abc import Callable
from pathlib import Path
from typing import Any

__all__ = ["cache_dir", "write_atomic", "load_verified", "store_verified", "verified"]

_ABSOLUTE: dict[str, Path] = {}
_KEY = re.compile(r"^[A-Za-z0-9_\-]+$")


def cache_dir() -> Path:
    """``$SYMKIN_CACHE`` or ``~/.cache/symkin`` (created on first use), as an absolute path.

    A relative ``SYMKIN_CACHE`` is taken relative to the working directory at its first use in
    the process, so compiled objects keep working (and the cache stays put) after ``os.chdir``.
    """
    env = os.environ.get("SYMKIN_CACHE")
    if not env:
        return Path.home() / ".cache" / "symkin"
    path = _ABSOLUTE.get(env)
    if path is None:
        path = _ABSOLUTE[env] = Path(env).expanduser().absolute()
    return path


def write_atomic(path: Path, text: str | bytes) -> None:
    """Write ``text`` (or bytes) to a unique temporary file beside ``path``, then rename it over
    ``path``. Raises OSError when it cannot (nothing is left behind)."""
    import tempfile

    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb" if isinstance(text, bytes) else "w") as f:
            f.write(text)
        os.replace(tmp, path)
    finally:
        with contextlib.suppress(FileNotFoundError):
            os.unlink(tmp)


def _path(kind: str, key: str) -> Path:
    if not (_KEY.match(kind) and _KEY.match(key)):
        raise ValueError(f"cache kind and key must be letters, digits, '-' and '_': {kind!r}, {key!r}")
    return cache_dir() / kind / f"{key}.json"


def _digest(kind: str, key: str, body: Any) -> str:
    text = json.dumps([kind, key, body], sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode()).hexdigest()


def load_verified(kind: str, key: str) -> Any | None:
    """The JSON value stored by :func:`store_verified` as ``<cache>/<kind>/<key>.json``, or None
    when it is missing, unreadable, or does not match its sha256 (of kind, key and value)."""
    try:
        data = json.loads(_path(kind, key).read_text())
        if data["sha256"] == _digest(kind, key, data["body"]):
            return data["body"]
    except (OSError, ValueError, KeyError, TypeError, RecursionError):
        pass  # missing, truncated, edited or of an older format: the caller makes it again
    return None


def store_verified(kind: str, key: str, body: Any) -> bool:
    """Store the JSON value ``body`` as ``<cache>/<kind>/<key>.json`` with its sha256, atomically;
    False when the cache cannot be written (full, read-only): that only costs speed."""
    body = json.loads(json.dumps(body))  # as it reads back (tuples as lists, keys as text)
    text = json.dumps({"sha256": _digest(kind, key, body), "body": body})
    try:
        write_atomic(_path(kind, key), text)
    except OSError:
        return False
    return True


def verified(kind: str, key: str, make: Callable[[], Any], use_cache: bool = True) -> Any:
    """The verified cache entry ``kind/key``, else ``make()`` (stored when the cache can take it)."""
    if use_cache:
        body = load_verified(kind, key)
        if body is not None:
            return body
    body = make()
    if use_cache:
        store_verified(kind, key, body)
    return body
