"""The batch entry points' four-lane code as a library of its own, built when a batch needs it.

The generated ``<prefix>_lanes.c`` (``c/kernel_lanes.c.j2``) holds the four-lane bodies of the
batch entry points: about two thirds of what the C compiler spends on a robot's code. The extension
module is built from ``<prefix>.c`` and the module source alone (:func:`main_sources`), so a first
call waits for those only; :func:`attach` arranges the rest. When the lanes library is in the cache
already it is bound at once. Otherwise the extension calls a hook at its first batch call of four
or more configurations (or when :func:`ready` asks), which compiles the lanes library in a
background thread and hands its table to ``<prefix>_bind_lanes``; batch calls in between run one
configuration per step, with the same results bit for bit. The cache's entries are built in
private folders, renamed into place and verified by checksum, so processes and threads building
the same library at once, or a damaged entry, are safe (:mod:`symkin.emit.c.build`). The thread is
not a daemon: an interpreter exits after the compiler, so no entry is left half-built. A forked
child whose parent had not bound the library yet arms the hook again.
"""

from __future__ import annotations

import ctypes
import os
import threading
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from types import ModuleType

from symkin.emit.c.build import cached_library, compile_library, load_library
from symkin.errors import CompileError

__all__ = ["main_sources", "lanes_sources", "attach", "ready", "state"]

SUFFIX = "_lanes.c"


def _prefix(files: dict[str, str]) -> str:
    return next(name[:-2] for name in files if name.endswith(".h"))


def main_sources(files: dict[str, str]) -> dict[str, str]:
    """The sources of the extension module: every generated file but ``<prefix>_lanes.c``."""
    lanes = _prefix(files) + SUFFIX
    return {k: v for k, v in files.items() if k != lanes}


def lanes_sources(files: dict[str, str]) -> dict[str, str]:
    """The sources of the lanes library (the header and ``<prefix>_lanes.c``), or {} when the code
    has none (single precision)."""
    prefix = _prefix(files)
    lanes = files.get(prefix + SUFFIX)
    return {f"{prefix}.h": files[f"{prefix}.h"], prefix + SUFFIX: lanes} if lanes else {}


@dataclass
class State:
    """Where the lanes library of one extension module stands: ``bound`` (its table given to the
    module's library), ``error`` (why it is not, when building or binding failed), the building
    ``thread`` (None before the first batch call and when the cache had it)."""

    module: str
    main: Path
    sources: dict[str, str]
    bound: bool = False
    error: str = ""
    thread: threading.Thread | None = None
    lock: threading.Lock = field(default_factory=threading.Lock)


_STATES: dict[str, State] = {}


def state(module: ModuleType | str) -> State | None:
    """The :class:`State` of an extension module (or its name), None when it has no lanes code."""
    return _STATES.get(module if isinstance(module, str) else module.__name__)


def attach(module: ModuleType, main: Path, files: dict[str, str]) -> None:
    """Give the extension module ``module`` (built from ``main_sources(files)`` into ``main``) its
    four-lane batch code: bound now when the cache has the lanes library, else at the first batch
    call (module docstring). Once per module and process."""
    sources = lanes_sources(files)
    if not sources or not hasattr(module, "_lanes_hook") or module.__name__ in _STATES:
        return
    st = _STATES[module.__name__] = State(module.__name__, Path(main), sources)
    cached = cached_library(sources, _library_name(st))
    if cached is not None:
        _bind(st, cached)
    else:
        module._lanes_hook(lambda: _start(st))


def ready(module: ModuleType, timeout: float | None = None) -> bool:
    """Ask for the lanes library of ``module`` now (the same as a first batch call) and wait for
    it (at most ``timeout`` seconds); True when the batch entry points run four lanes."""
    st = state(module)
    if st is None:
        return False
    module._want_lanes()
    thread = st.thread
    if thread is not None:
        thread.join(timeout)
    return st.bound


def _library_name(st: State) -> str:
    return f"{st.module}_lanes"


def _start(st: State) -> None:
    """The hook: compile and bind in a background thread (non-daemon: see the module docstring)."""
    with st.lock:
        if st.bound or (st.thread is not None and st.thread.is_alive()):
            return
        st.thread = threading.Thread(target=_build, args=(st,), name=f"symkin-lanes-{st.module}")
        st.thread.start()


def _build(st: State) -> None:
    try:
        path = compile_library(st.sources, _library_name(st))
    except CompileError as exc:  # the batch entry points keep one configuration per step
        st.error = str(exc)
        warnings.warn(
            f"symkin: the four-lane batch code of {st.module} did not build; batches run one "
            f"configuration per step (same results): {exc}",
            RuntimeWarning,
            stacklevel=1,
        )
        return
    _bind(st, path)


def _bind(st: State, path: Path) -> None:
    """Hand the table ``<prefix>_lanes`` of the library at ``path`` to ``<prefix>_bind_lanes``."""
    prefix = _prefix(st.sources)
    try:
        lanes = load_library(path)
        table = ctypes.c_char.in_dll(lanes, f"{prefix}_lanes")  # absent without vector extensions
        bind = getattr(load_library(st.main), f"{prefix}_bind_lanes")
    except (CompileError, ValueError, AttributeError) as exc:
        st.error = f"cannot bind {path}: {exc}"
        return
    bind.restype = None
    bind.argtypes = (ctypes.c_void_p,)
    bind(ctypes.addressof(table))
    st.bound = True


def _after_fork() -> None:
    """In a forked child: a build the parent had started has no thread here; arm the hook again."""
    import sys

    for st in _STATES.values():
        if not st.bound:
            st.thread, st.lock = None, threading.Lock()
            module = sys.modules.get(st.module)
            if module is not None:
                module._lanes_hook(lambda st=st: _start(st))


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_after_fork)
