"""Safe names: identifiers, comments and string literals for generated code (leaf module)."""

from __future__ import annotations

import hashlib
import re
from collections.abc import Sequence

__all__ = ["IDENTIFIER_MAX", "identifier", "comment_safe", "c_string", "function_name", "listed", "robot_key"]

IDENTIFIER_MAX = 40  # longest identifier(): C symbols, module and file names stay short


def identifier(text: str) -> str:
    """A safe lowercase ASCII C/Python identifier for arbitrary text (robot names in generated
    code, symbols and file names), at most :data:`IDENTIFIER_MAX` characters.

    Letters, digits and underscores are kept (others become ``_``); a name that is not plain
    ASCII or is too long is cut and ends in ``_`` and 8 hex digits of its hash, so different
    names stay apart (``café`` -> ``caf__1f3a...``). The display name is kept in ``Robot.name``.
    """
    ident = re.sub(r"[^a-z0-9_]", "_", text.lower())
    if not ident or ident[0].isdigit():
        ident = "r_" + ident
    if not text.isascii() or len(ident) > IDENTIFIER_MAX:
        digest = hashlib.sha256(text.encode("utf-8", "surrogatepass")).hexdigest()[:8]
        ident = f"{ident[: IDENTIFIER_MAX - 9]}_{digest}"
    return ident


_UNSAFE = re.compile(r"[^\x20-\x7e]")
# between * and /, / and *, ? and ?: where a space keeps a comment from ending or a trigraph from forming
_APART = re.compile(r"(?<=\*)(?=/)|(?<=/)(?=\*)|(?<=\?)(?=\?)")


def comment_safe(text: str, limit: int = 300) -> str:
    """Any text made inert inside a C block or line comment, a Python comment and a Python
    docstring, cut to ``limit`` characters.

    Only printable ASCII is kept: control characters (newlines, ``\\r``, form feeds, NUL) and
    non-ASCII become ``?``, a backslash becomes ``/`` (no line continuation, no string escape) and
    a double quote becomes ``'`` (no ``\"\"\"``). Then ``*`` and ``/`` next to each other, and two ``?``,
    are set apart by a space, after every replacement, so no ``*/`` or ``/*`` and no trigraph
    (``??/`` is a backslash in ISO C modes) can form.
    """
    text = _UNSAFE.sub("?", text).replace("\\", "/").replace('"', "'")
    text = _APART.sub(" ", text)
    return text if len(text) <= limit else text[: limit - 3] + "..."


def c_string(text: str) -> str:
    """A C string literal of the UTF-8 bytes of ``text``: ASCII letters, digits and a few safe
    punctuation marks as they are, every other byte (non-ASCII too) escaped as octal."""
    out = []
    for b in text.encode("utf-8", "surrogatepass"):
        ch = chr(b)
        safe = b < 128 and (ch.isalnum() or ch in " _-.,:;()[]=+")
        out.append(ch if safe else f"\\{b:03o}")
    return '"' + "".join(out) + '"'


def function_name(kind: str, frame: int | None, frames: int) -> str:
    """The name of a generated function of ``kind`` ("fkine", "jacob0_hessian0"...) for frame
    ``frame`` of a model with ``frames`` frames: the kind itself for the only frame of a chain
    (``<prefix>_fkine``) or a function of every frame (``frame=None``, ``fkine_all``), else
    ``<kind>_<frame>`` (``<prefix>_fkine_3``)."""
    return kind if frame is None or frames == 1 else f"{kind}_{frame}"


def listed(texts: Sequence[str], most: int) -> str:
    """The first ``most`` of ``texts`` joined by commas, ending `` ...`` when there are more (what
    a message shows of a long list)."""
    return ", ".join(texts[:most]) + (" ..." if len(texts) > most else "")


def robot_key(name: str) -> str:
    """A built-in robot's key from its name as people write it: case-insensitive, ``-`` and
    spaces read as ``_`` (``"LBR-iiwa7"`` -> ``"lbr_iiwa7"``)."""
    return "_".join(name.strip().lower().replace("-", " ").split())
