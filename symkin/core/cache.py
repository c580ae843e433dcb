"""The compile cache folder and atomic writes into it (leaf module)."""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

__all__ = ["cache_dir", "write_atomic"]

_ABSOLUTE: dict[str, Path] = {}


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
    ``path``."""
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
