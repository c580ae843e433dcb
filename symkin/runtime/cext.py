"""The runtime's C libraries (``csrc/``) through ctypes and CPython: their sources, the compiled
library with its extension module, function signatures and the check that a C struct's layout is
the one Python mirrors (shared by the C IK solver and the MMC library)."""

from __future__ import annotations

import ctypes
import hashlib
from pathlib import Path
from typing import Any

__all__ = ["CSRC", "csrc", "build_extension", "bind_functions", "layout", "address"]

CSRC = Path(__file__).resolve().parent / "csrc"


def csrc(*names: str) -> dict[str, str]:
    """The texts of files of ``csrc/`` (file name -> text)."""
    return {name: (CSRC / name).read_text() for name in names}


def build_extension(
    sources: dict[str, str], stem: str, macro: str, prefix: str, flags: tuple[str, ...] = ()
) -> tuple[Path, str]:
    """(path of the library compiled from ``sources``, name of the CPython extension module in it):
    the module is ``prefix`` and a digest of the sources, passed to the C code as ``-D<macro>=``; the
    library (cached by :func:`symkin.emit.c.build.compile_library`) is ``lib<stem>.so``."""
    import sysconfig

    import numpy as np

    from symkin.emit.c.build import compile_library

    digest = hashlib.sha256("\0".join(f"{k}\0{sources[k]}" for k in sorted(sources)).encode()).hexdigest()
    module = f"{prefix}_{digest[:12]}"
    includes = (f"-I{sysconfig.get_paths()['include']}", f"-I{np.get_include()}")
    return compile_library(sources, stem, (*flags, f"-D{macro}={module}", *includes)), module


def bind_functions(lib: ctypes.CDLL, signatures: dict[str, tuple[Any, list[Any]]]) -> ctypes.CDLL:
    """Set the result and argument types of ``lib``'s functions (name -> (restype, argtypes))."""
    for name, (res, args) in signatures.items():
        fn = getattr(lib, name)
        fn.restype, fn.argtypes = res, args
    return lib


def layout(lib: ctypes.CDLL, name: str, expected: tuple[int, ...]) -> None:
    """Check the int32 values that ``lib``'s ``void name(int32_t *out)`` writes (sizes of its
    structs and their dimensions) against those of Python's mirrors; RuntimeError when they differ."""
    fn = getattr(lib, name)
    fn.restype, fn.argtypes = None, [ctypes.c_void_p]
    out = (ctypes.c_int32 * len(expected))()
    fn(out)
    if tuple(out) != tuple(expected):
        raise RuntimeError(f"{name}: the C layout {tuple(out)} differs from Python's {tuple(expected)}")


def address(fn: Any) -> int:
    """The address of a C function: a ctypes function's, an int as it is, 0 for None."""
    if fn is None or isinstance(fn, int):
        return fn or 0
    return int(ctypes.cast(fn, ctypes.c_void_p).value or 0)
