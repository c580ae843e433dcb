"""The NumPy backend: a generated, readable Python module per robot.

One configuration runs scalar ``math`` code (a few microseconds); a batch (N, n) runs the same
straight-line code on NumPy arrays, vectorised over N.
"""

from __future__ import annotations

import contextlib
import hashlib
import importlib.util
import linecache
import marshal
import sys
from pathlib import Path
from types import CodeType, ModuleType
from typing import Any

from symkin.core.cache import write_atomic
from symkin.emit.kernel import LINKED
from symkin.emit.templates import python_module

__all__ = ["render_numpy", "load_numpy", "import_source"]


def render_numpy(kernel: Any) -> dict[str, str]:
    """The generated module ``symkin_<code_name>.py`` of ``kernel``.

    The scalar code of one configuration is written for CPython's speed, as measured with
    ``symkin bench calls``: inline in the public function (no second call), the joint values
    unpacked from a list in one statement and checked by the sum of their squares (at most 1e30:
    every value finite and within +-MAX_JOINT_VALUE; no function call), ``sin``, ``cos`` and
    ``sqrt`` imported from ``math`` (one global lookup each), and each output array filled by
    ``struct.pack_into`` on ``np.empty`` (0.5-0.9 us less than ``np.array(list)`` for a 4x4 or
    6x6 array); it still returns a new, writeable float64 array per call."""
    from symkin.emit.lowering import lower
    from symkin.emit.printers import MathPrinter, NumPyKinPrinter

    printed = []
    for f in kernel.functions:
        vec, one = lower(f, NumPyKinPrinter()), lower(f, MathPrinter())
        joints = [str(s) for s in f.code.inputs]
        printed.append(
            {
                **vec.__dict__,
                "scalar_lines": one.lines,
                "scalar_fill": [_fill(o, f.name) for o in (*one.outs, *one.scratch) if o.values],
                # every joint, also those the function does not use: the sum of their squares is
                # the check (<= MAX_JOINT_VALUE**2: each within +-MAX_JOINT_VALUE, and NaN fails)
                "unpack": ", ".join(joints) + ("," if len(joints) == 1 else ""),
                "joint_squares": " + ".join(f"{j} * {j}" for j in joints),
                # a function with one output returns the array, not a 1-tuple
                "ret_one": _returned([o.name for o in one.outs]),
                "ret_batch": _returned([f"{o.name}.reshape((N,) + {o.shape})" for o in vec.outs]),
                "ret_first": "out[0]"
                if len(vec.outs) == 1
                else _returned([f"out[{i}][0]" for i in range(len(vec.outs))]),
                "ret_delegate": _returned([f"out[{i}]" for i in vec.delegate_pick]),
            }
        )
    sizes = {size for f in printed for o in f["scalar_fill"] for size, _, _ in o["chunks"]}
    return python_module(
        "numpy/module.py.j2",
        kernel,
        printed,
        pack_sizes=sorted(sizes),
        framed_kinds=kernel.framed,
        linked_kinds=LINKED,
        tables={kind: kernel.table(kind) for kind in kernel.framed},
    )


# CPython passes a call's arguments on its stack up to 30 of them, beyond through a list (about
# 0.4 us slower for 36 values): an output is written by calls of at most PACK_MAX values each.
PACK_MAX = 28


def _fill(o: Any, function: str) -> dict[str, Any]:
    """How the scalar code of ``function`` writes output ``o``: its name and shape, the array the
    values go to (``target``, of shape ``alloc``) and chunks (number of values, byte offset,
    printed values) of at most PACK_MAX values, of nearly equal sizes; a gathered output's
    distinct values go to ``<name>_of``, then its table ``at`` picks the entries."""
    values = list(o.distinct) if o.index else [text for _, text in o.values]
    k = -(-len(values) // PACK_MAX)
    bounds = [len(values) * i // k for i in range(k + 1)]
    chunks = [(b - a, 8 * a, ", ".join(values[a:b])) for a, b in zip(bounds, bounds[1:])]
    at = f"_AT_{function}_{o.name}" if o.index else ""
    target, alloc = (f"{o.name}_of", (len(values),)) if at else (o.name, o.shape)
    return {"name": o.name, "shape": o.shape, "chunks": chunks, "at": at, "target": target, "alloc": alloc}


def _returned(values: list[str]) -> str:
    """The returned expression: one value itself, several as a tuple."""
    return values[0] if len(values) == 1 else f"({', '.join(values)})"


def load_numpy(files: dict[str, str], folder: Path) -> ModuleType:
    """Write the module into ``folder`` (if not there) and import it under a content-unique name.

    The file is written under a unique temporary name and renamed into place, so concurrent
    writers never see each other's half-written file; a file that differs from ``files`` (damaged,
    edited) is written again. The bytecode comes from :func:`import_source`'s verified cache, never
    from Python's unverified ``__pycache__``. When ``folder`` cannot be written, the module is
    imported from memory: an unwritable cache only costs speed.
    """
    ((filename, text),) = files.items()
    digest = hashlib.sha256(text.encode()).hexdigest()[:12]
    name = f"_{filename[:-3]}_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    path = folder / f"{name}.py"
    try:
        if not path.is_file() or path.read_bytes() != text.encode():
            write_atomic(path, text.encode())
    except OSError:
        return _import_text(name, text)
    return import_source(
        name, text, path, cache=path.with_name(f"{name}.{sys.implementation.cache_tag}.code")
    )


def import_source(name: str, text: str, path: Path, cache: Path | None = None) -> ModuleType:
    """Import ``text``, the source in the file ``path``, as module ``name`` (tracebacks show the
    file's lines). Its bytecode is read from ``cache`` when that file's checksums hold (about 0.1 ms,
    where compiling a large robot's module takes 10-25 ms), else compiled and stored there: a
    damaged (truncated, overwritten) bytecode file is compiled again, never run or raised as
    ``EOFError: marshal data too short`` as Python's own ``__pycache__`` would."""
    code = _bytecode(text, path, cache)
    spec = importlib.util.spec_from_loader(name, loader=None, origin=str(path))
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    module.__file__ = str(path)
    exec(code, module.__dict__)  # noqa: S102 - our own generated code
    sys.modules[name] = module
    return module


def _bytecode(text: str, path: Path, cache: Path | None) -> CodeType:
    """The code object of ``text``; ``cache`` holds the interpreter's magic number, the source's
    sha256, the marshalled code's sha256 and the marshalled code."""
    head = importlib.util.MAGIC_NUMBER + hashlib.sha256(text.encode()).digest()
    if cache is not None:
        try:
            data = cache.read_bytes()
            body = data[len(head) + 32 :]
            if data[: len(head) + 32] == head + hashlib.sha256(body).digest():
                code = marshal.loads(body)
                if isinstance(code, CodeType):
                    return code
        except (OSError, ValueError, EOFError, TypeError):
            pass  # missing or damaged: compile below
    code = compile(text, str(path), "exec", dont_inherit=True)
    if cache is not None:
        body = marshal.dumps(code)
        with contextlib.suppress(OSError):  # an unwritable cache only costs speed
            write_atomic(cache, head + hashlib.sha256(body).digest() + body)
    return code


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
