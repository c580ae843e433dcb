"""The NumPy backend: a generated, readable Python module per robot.

One configuration runs scalar ``math`` code (a few microseconds); a batch (N, n) runs the same
straight-line code on NumPy arrays, vectorised over N.
"""

from __future__ import annotations

import hashlib
import importlib.util
import linecache
import sys
from pathlib import Path
from types import ModuleType
from typing import Any

from symkin.emit.c.build import write_atomic
from symkin.emit.templates import chain_tables, render_python_module

__all__ = ["render_numpy", "load_numpy"]


def render_numpy(robot: Any, functions: list, command: str) -> dict[str, str]:
    """The generated module ``symkin_<robot>.py``."""
    from symkin.emit.lowering import lower
    from symkin.emit.printers import NumPyPrinter

    class _MathPrinter(NumPyPrinter):
        module = "math"

    printed = []
    for f in functions:
        vec, one = lower(f, NumPyPrinter()), lower(f, _MathPrinter())
        printed.append(
            {
                **vec.__dict__,
                "scalar_lines": one.lines,
                "scalar_outs": one.outs,
                "scalar_scratch": one.scratch,
            }
        )
    return render_python_module(
        "numpy/module.py.j2",
        robot,
        functions,
        printed,
        command,
        chain=chain_tables(robot),
        hessian_frames=sorted({h.frame for f in printed for h in f["hessians"]}),
    )


def load_numpy(files: dict[str, str], folder: Path) -> ModuleType:
    """Write the module into ``folder`` (if not there) and import it under a content-unique name.

    The file is written under a unique temporary name and renamed into place, so concurrent
    writers never see each other's half-written file. When ``folder`` cannot be written, the
    module is imported from memory: an unwritable cache only costs speed.
    """
    ((filename, text),) = files.items()
    digest = hashlib.sha256(text.encode()).hexdigest()[:12]
    name = f"_{filename[:-3]}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    path = folder / f"{name}.py"
    try:
        if not path.exists() or path.read_text() != text:
            write_atomic(path, text)
    except OSError:
        return _import_text(name, text)
    spec = importlib.util.spec_from_file_location(name, path)
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    sys.modules[name] = module
    return module


def _import_text(name: str, text: str) -> ModuleType:
    """Import generated source from memory (no file; tracebacks still show its lines)."""
    origin = f"<symkin generated {name}>"
    linecache.cache[origin] = (len(text), None, text.splitlines(True), origin)
    spec = importlib.util.spec_from_loader(name, loader=None, origin=origin)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    exec(compile(text, origin, "exec"), module.__dict__)  # noqa: S102 - our own generated code
    sys.modules[name] = module
    return module
