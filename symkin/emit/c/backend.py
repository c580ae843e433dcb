"""The C backend: a ``.c``/``.h`` pair per robot plus a CPython extension module around it.

Call path, chosen by measurement (``symkin bench kin`` prints all three): a generated CPython
extension (METH_O functions taking the ndarray directly) beats ctypes with cached pointers and
cffi, because each ``ndarray.ctypes`` access and each foreign-call marshalling costs about as much
as the arithmetic. The same shared library also exports the plain C entry points, so ctypes users
(and the C IK solver) can call them directly.
"""

from __future__ import annotations

import hashlib
import importlib.machinery
import importlib.util
import sysconfig
from pathlib import Path
from types import ModuleType
from typing import Any

from symkin.emit.templates import Header, c_string, chain_tables, identifier, render

__all__ = ["render_c", "build_c", "compile_c", "load_extension", "c_prefix"]


def c_prefix(robot: Any) -> str:
    """The C symbol prefix of a robot: ``symkin_<identifier>``."""
    return f"symkin_{identifier(robot.name)}"


def render_c(robot: Any, functions: list, command: str) -> dict[str, str]:
    """The generated ``<prefix>.h``, ``<prefix>.c`` and the extension module source."""
    from symkin.emit.lowering import lower
    from symkin.emit.printers import CPrinter

    printer = CPrinter()
    printed = [lower(f, printer) for f in functions]
    prefix = c_prefix(robot)
    header = Header.of(robot, functions, command, c_string(robot.name))
    context = {
        "prefix": prefix,
        "n": robot.n,
        "functions": printed,
        "header": header,
        "chain": chain_tables(robot),
        "hessian_frames": sorted({h.frame for f in printed for h in f.hessians}),
    }
    h = render("c/kinematics.h.j2", **context)
    c = render("c/kinematics.c.j2", **context)
    files = {f"{prefix}.h": h, f"{prefix}.c": c}
    ext = render("c/module.c.j2", module=module_name(files), **context)
    return {**files, f"{prefix}_pymodule.c": ext}


def module_name(files: dict[str, str]) -> str:
    """The extension module's import name: unique per kinematics source, so versions can coexist."""
    prefix = next(name[:-2] for name in files if name.endswith(".h"))
    digest = hashlib.sha256((files[f"{prefix}.h"] + files[f"{prefix}.c"]).encode()).hexdigest()[:12]
    return f"_{prefix}_{digest}"


def extension_cflags() -> tuple[str, ...]:
    """Include paths of the Python and NumPy headers the extension module needs."""
    import numpy as np

    return (f"-I{sysconfig.get_paths()['include']}", f"-I{np.get_include()}")


def compile_c(files: dict[str, str]) -> tuple[str, Path]:
    """Compile the generated files (cached): the extension module's name and library path."""
    from symkin.emit.c.build import compile_library

    name = module_name(files)
    return name, compile_library(files, name, extra_cflags=extension_cflags())


def build_c(files: dict[str, str]) -> tuple[ModuleType, Path]:
    """Compile the generated files (cached) and import the extension module."""
    name, path = compile_c(files)
    return load_extension(name, path), path


def load_extension(name: str, path: Path) -> ModuleType:
    """Import the extension module ``name`` from the shared library at ``path``."""
    import sys

    if name in sys.modules:
        return sys.modules[name]
    loader = importlib.machinery.ExtensionFileLoader(name, str(path))
    spec = importlib.util.spec_from_file_location(name, str(path), loader=loader)
    assert spec is not None
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    sys.modules[name] = module
    return module
