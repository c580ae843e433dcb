"""Checks of the ``symkin`` command line made before any long work: argparse types for counts and
positive numbers, output paths, ``--plot`` (matplotlib and the target folder) and ``SYMKIN_CFLAGS``.
Each failure is a :class:`UserError` (one line, exit status 2)."""

from __future__ import annotations

import argparse
import math
from pathlib import Path
from typing import Any

__all__ = [
    "UserError",
    "int_at_least",
    "at_least_1",
    "positive_float",
    "output_dir",
    "output_file",
    "need_matplotlib",
    "check_cflags_for",
]


class UserError(Exception):
    """A mistake in the command line; printed as one line."""


# -- argument types and checks done before any long work -------------------------------------
def int_at_least(minimum: int) -> Any:
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected an integer, got {text!r}") from None
        if value < minimum:
            raise argparse.ArgumentTypeError(f"must be at least {minimum}, got {value}")
        return value

    parse.__name__ = "integer"
    return parse


at_least_1 = int_at_least(1)


def _finite_float(ok: Any, bound: str) -> Any:
    """An argparse type: a finite float for which ``ok(value)`` holds (``bound``: what it must be)."""

    def parse(text: str) -> float:
        try:
            value = float(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a number, got {text!r}") from None
        if not (math.isfinite(value) and ok(value)):
            raise argparse.ArgumentTypeError(f"must be {bound}, got {text!r}")
        return value

    parse.__name__ = "number"
    return parse


non_negative_float = _finite_float(lambda v: v >= 0, "a finite number >= 0")
positive_float = _finite_float(lambda v: v > 0, "a positive finite number")


def output_dir(path: str) -> Path:
    """``-o DIR``: an existing folder or one that can be created (checked before the work)."""
    out = Path(path)
    if out.exists() and not out.is_dir():
        raise UserError(f"-o {path}: exists and is not a folder")
    return out


def output_file(path: str | None, what: str) -> None:
    """A file to write after the work (``--plot``, ``-o FILE``): its folder must exist."""
    if path is None:
        return
    p = Path(path)
    if p.is_dir():
        raise UserError(f"{what} {path}: is a folder; give a file name")
    if not p.absolute().parent.is_dir():
        raise UserError(f"{what} {path}: the folder {str(p.absolute().parent)!r} does not exist")


def need_matplotlib(path: str | None) -> None:
    if path is None:
        return
    output_file(path, "--plot")
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise UserError("--plot needs matplotlib: pip install 'symkin[plot]'") from None


def check_cflags_for(backend: str) -> None:
    """Reject a SYMKIN_CFLAGS the C compiler cannot use before generating anything."""
    if backend == "c":
        from symkin.emit.c.build import check_cflags

        check_cflags()
