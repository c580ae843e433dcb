"""What the benchmarks share: timing (the best of several rounds, paths measured in turn), peer
libraries that may be missing, a fresh Python interpreter for start-up and cold-compile figures,
figures, and the tables of their reports."""

from __future__ import annotations

import contextlib
import importlib
import math
import os
import resource
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable, Hashable, Iterable, Iterator, Sequence
from types import ModuleType
from typing import Any
from unittest import mock

__all__ = [
    "best_of",
    "timed",
    "interleaved",
    "rows_per_s",
    "optional",
    "fresh_python",
    "with_lanes",
    "guarded",
    "fresh_cache",
    "cpu_seconds",
    "figure",
    "table",
    "cell",
    "cells",
]


def interleaved(
    paths: dict[Any, Callable[[], Any]], rounds: int = 3, clock: Callable[[], float] = time.thread_time
) -> tuple[dict[Any, float], dict[Any, Any]]:
    """The least ``clock`` time (s) of one call of each path over ``rounds`` rounds, each round
    calling every path once in turn (so that a burst of load on a shared machine hits every path of
    a comparison, not just one), and each path's result of the last round.

    ``time.thread_time`` (the default) counts only the calling thread's CPU time, so that other
    processes of a shared machine do not count; ``time.process_time`` counts a peer library's
    threads too; ``time.perf_counter`` is wall time."""
    best: dict[Hashable, float] = dict.fromkeys(paths, math.inf)
    last: dict[Hashable, Any] = {}
    for _ in range(rounds):
        for key, f in paths.items():
            t0 = clock()
            last[key] = f()
            best[key] = min(best[key], clock() - t0)
    return best, last


def best_of(f: Callable[[], Any], rounds: int = 3, clock: Callable[[], float] = time.thread_time) -> float:
    """The least ``clock`` time (s) of ``rounds`` calls of f (:func:`interleaved` with one path)."""
    return interleaved({None: f}, rounds, clock)[0][None]


def timed(f: Callable[[], Any]) -> tuple[Any, float]:
    """``(f(), wall seconds of that one call)``: a step timed once, as it runs (a compile, a map)."""
    t0 = time.perf_counter()
    return f(), time.perf_counter() - t0


def rows_per_s(fn: Callable[[Any], Any], Q: Any, clock: Callable[[], float] = time.thread_time) -> float:
    """Rows of ``Q`` per second through one call ``fn(Q)``: the best of three, after a warm-up on
    the first 1000 rows."""
    fn(Q[:1000])
    return len(Q) / best_of(lambda: fn(Q), 3, clock)


def optional(name: str) -> ModuleType | None:
    """The module ``name`` of a peer library (the ``compare`` extra), or None when not installed."""
    try:
        return importlib.import_module(name)
    except ImportError:
        return None


def guarded(f: Callable[[], Any]) -> Any:
    """``f()``, or ``{"error": "<exception type>: <message>"}`` when it raises: an optional
    comparison with a peer library must not break the benchmark."""
    try:
        return f()
    except Exception as exc:  # noqa: BLE001 - an optional comparison must not break the benchmark
        return {"error": f"{type(exc).__name__}: {exc}"}


@contextlib.contextmanager
def fresh_cache() -> Iterator[str]:
    """A new, empty compile cache (``SYMKIN_CACHE``, restored after) for the block: every compile
    in it (and in a :func:`fresh_python` it starts) derives, generates and builds."""
    with (
        tempfile.TemporaryDirectory(prefix="symkin-bench-") as folder,
        mock.patch.dict(os.environ, {"SYMKIN_CACHE": folder}),
    ):
        yield folder


def cpu_seconds() -> float:
    """CPU seconds of this process and of its finished children (the compiler)."""
    own, kids = resource.getrusage(resource.RUSAGE_SELF), resource.getrusage(resource.RUSAGE_CHILDREN)
    return own.ru_utime + own.ru_stime + kids.ru_utime + kids.ru_stime


def fresh_python(code: str, env: dict[str, str], timeout: float | None = None, what: str = "") -> str:
    """The last line ``code`` prints, run by a fresh interpreter (``python -c``) with ``env``; a
    RuntimeError (``what`` failed, with the end of its stderr) when it fails."""
    proc = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, env=env, timeout=timeout
    )
    if proc.returncode != 0:
        raise RuntimeError(f"{what or repr(code)} failed:\n{proc.stderr.strip()[-2000:]}")
    return proc.stdout.strip().splitlines()[-1]


def with_lanes(kin: Any, timeout: float = 600) -> Any:
    """``kin`` once its four-lane batch code is bound (C backend; built in the background after the
    first batch call, :mod:`symkin.emit.c.lanes`), so batch timings on a cold cache measure it
    rather than the one-configuration steps before it; other backends as they are."""
    module = getattr(kin, "module", None)
    if getattr(kin, "backend", None) == "c" and module is not None:
        from symkin.emit.c.lanes import ready

        ready(module, timeout)
    return kin


@contextlib.contextmanager
def figure(path: Any, what: str, dpi: float | None = None, **subplots: Any) -> Iterator[tuple[Any, Any]]:
    """``(fig, axes)`` of ``matplotlib.pyplot.subplots(**subplots)`` (the Agg backend) for the
    block, then laid out tight, written to ``path`` (``dpi``; None: the figure's) and closed. A
    MissingExtraError naming ``what`` without matplotlib (the ``plot`` extra)."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:  # pragma: no cover - optional dependency
        from symkin.errors import MissingExtraError

        raise MissingExtraError(f"{what} needs matplotlib: pip install 'symkin[plot]'") from None
    fig, axes = plt.subplots(**subplots)
    try:
        yield fig, axes
        fig.tight_layout()
        fig.savefig(path, dpi=dpi or "figure")
    finally:
        plt.close(fig)


def table(head: Sequence[str], rows: Iterable[Sequence[Any] | None], align: str = "") -> list[str]:
    """The lines of a plain-text table: ``head``, a rule, then ``rows`` (cells as strings, other
    values by ``str``; a row None is an empty line), each column as wide as its widest cell, two
    spaces apart, aligned by ``align`` (``l`` or ``r`` per column; default: the first left, the
    others right)."""
    body = [None if r is None else [str(c) for c in r] for r in rows]
    align = align or "l" + "r" * (len(head) - 1)
    lines = [list(head)] + [r for r in body if r is not None]
    widths = [max(len(r[i]) for r in lines) for i in range(len(head))]

    def line(r: Sequence[str]) -> str:
        return "  ".join(c.ljust(w) if a == "l" else c.rjust(w) for c, w, a in zip(r, widths, align)).rstrip()

    rule = "-" * max(len(line(r)) for r in lines)
    return [line(head), rule] + ["" if r is None else line(r) for r in body]


def cell(value: Any, fmt: str = "{}", missing: str = "-") -> str:
    """``value`` by the format string ``fmt`` (``"{:.2f}x"``), or ``missing`` when it is None (a
    figure not measured)."""
    return missing if value is None else fmt.format(value)


def cells(label: str, values: dict[Any, Any], keys: Iterable[Any], fmt: str = "{}") -> list[str]:
    """A row of :func:`table`: ``label``, then ``values[k]`` by ``fmt`` for each of ``keys`` ("-"
    where missing)."""
    return [label, *(cell(values.get(k), fmt) for k in keys)]
