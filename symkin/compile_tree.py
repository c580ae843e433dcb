"""``symkin.compile(tree, backend)``: a :class:`symkin.Tree` -> one kernel -> :class:`TreeKinematics`.

Generated sources are cached like a chain's (``$SYMKIN_CACHE``), under a key made of the tree's
structural hash, the backend, the symkin version and the templates.
"""

from __future__ import annotations

import hashlib
import json
import os
from pathlib import Path
from typing import Any

import numpy as np

from symkin.emit.c.build import cache_dir
from symkin.errors import CompileError, SymkinError
from symkin.model.robot import as_batch
from symkin.model.tree import Tree
from symkin.runtime.tree_kinematics import TREE_METHODS, TreeKinematics

__all__ = ["generate_tree", "compile_tree", "tree_derivation_functions"]

_LOADED: dict[tuple[str, bytes, bytes, str], TreeKinematics] = {}
_FUNCTIONS: dict[str, list] = {}


def tree_derivation_functions(tree: Tree) -> list:
    """Derive the tree program of ``tree`` and build its emitted functions (imports sympy)."""
    cached = _FUNCTIONS.get(tree.key)
    if cached is not None:
        return cached
    from symkin.symbolic.kinematics import const_to_sympy, joint_symbols
    from symkin.symbolic.tree_program import derive_tree_program, tree_functions

    functions = tree_functions(derive_tree_program(tree, joint_symbols(tree.n), const_to_sympy, fold=True))
    if len(_FUNCTIONS) > 16:
        _FUNCTIONS.clear()
    _FUNCTIONS[tree.key] = functions
    return functions


def generate_tree(tree: Tree, backend: str, command: str | None = None) -> dict[str, str]:
    """The generated source files of ``tree`` for ``backend`` (filename -> text). Imports sympy."""
    from symkin.compile import _check_backend
    from symkin.emit.tree import render_tree

    _check_backend(backend)
    if tree.n == 0:
        raise SymkinError(f"tree {tree.name!r} has no joints on the paths to its frames: nothing to compile")
    frames = ",".join(tree.frames)
    command = command or f"symkin compile {tree.identifier} --frames {frames} --backend {backend}"
    return render_tree(tree, tree_derivation_functions(tree), backend, command)


def _cache_key(tree: Tree, backend: str) -> str:
    from symkin import __version__
    from symkin.compile import _compiler_digest, _templates_digest

    text = "\n".join((__version__, "tree", backend, tree.key, _templates_digest(), _compiler_digest()))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _cached_files(tree: Tree, backend: str, key: str, use_cache: bool) -> dict[str, str]:
    path = cache_dir() / "gen" / f"{key}.json"
    if use_cache and path.exists():
        try:
            data = json.loads(path.read_text())
            files = data["files"]
            if data.get("sha256") == hashlib.sha256(json.dumps(files, sort_keys=True).encode()).hexdigest():
                return files
        except (OSError, ValueError, KeyError, TypeError):
            pass  # corrupted entry: regenerate
    files = generate_tree(tree, backend)
    if use_cache:
        digest = hashlib.sha256(json.dumps(files, sort_keys=True).encode()).hexdigest()
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            tmp = path.with_suffix(f".{os.getpid()}.tmp")
            tmp.write_text(json.dumps({"sha256": digest, "files": files}))
            os.replace(tmp, path)
        except OSError:
            pass  # an unwritable cache only costs speed
    return files


def compile_tree(tree: Tree, backend: str = "c", cache: bool = True) -> TreeKinematics:
    """Compile every frame of ``tree`` into one kernel on ``backend`` (see :func:`symkin.compile`)."""
    from symkin.compile import _check_backend

    _check_backend(backend)
    if tree.n == 0:
        raise SymkinError(f"tree {tree.name!r} has no joints on the paths to its frames: nothing to compile")
    key = _cache_key(tree, backend)
    # the generated code depends on the structure only (key); the object also carries the limits,
    # speeds and source a controller reads, so trees that differ there get their own object
    loaded_key = (key, tree.qlim.tobytes(), np.asarray(tree.velocity).tobytes(), tree.source)
    if cache and loaded_key in _LOADED:
        return _LOADED[loaded_key]
    files = _cached_files(tree, backend, key, cache)
    if backend == "c":
        from symkin.emit.c.backend import build_c

        module, path = build_c(files)
        functions = {name: getattr(module, name) for name in TREE_METHODS}
        kin = TreeKinematics(tree, backend, functions, files, path, module)
    elif backend == "numpy":
        from symkin.emit.numpy.backend import load_numpy

        module = load_numpy(files, cache_dir() / "numpy")
        functions = {name: getattr(module, name) for name in TREE_METHODS}
        kin = TreeKinematics(tree, backend, functions, files, Path(module.__file__ or ""), module)
    else:
        kin = _casadi(tree, files)
    if cache:
        _LOADED[loaded_key] = kin
    return kin


def _casadi(tree: Tree, files: dict[str, str]) -> TreeKinematics:
    from symkin.emit.numpy.backend import load_numpy

    try:
        module = load_numpy(files, cache_dir() / "casadi")
    except ImportError as exc:  # pragma: no cover - casadi is a declared dependency
        raise CompileError(f"the casadi backend needs casadi installed: {exc}") from exc
    fns = module.functions()
    n, F = tree.n, len(tree.frames)
    shapes = {"T": (4, 4), "J": (6, n)}
    shapes_all = {"T": (F, 4, 4), "J": (F, 6, n)}

    def call(f: Any, q: Any, shape: dict[str, tuple[int, ...]]) -> Any:
        Q, single = as_batch(q, n, tree.name)
        names = f.name_out()
        if Q.shape[0] == 0:  # casadi cannot map over 0 items
            outs = [np.zeros((0, *shape[k])) for k in names]
        elif single:
            res = f(Q[0])
            res = res if isinstance(res, (list, tuple)) else [res]
            outs = [np.asarray(r).reshape(shape[k]) for k, r in zip(names, res)]
        else:
            res = f.map(Q.shape[0])(Q.T)
            res = res if isinstance(res, (list, tuple)) else [res]
            outs = []
            for k, r in zip(names, res):
                a = np.asarray(r)  # (rows, cols*N), column blocks per configuration
                rows, cols = a.shape[0], a.shape[1] // Q.shape[0]
                outs.append(
                    a.reshape(rows, Q.shape[0], cols).transpose(1, 0, 2).reshape((Q.shape[0], *shape[k]))
                )
        return outs[0] if len(outs) == 1 else tuple(outs)

    def framed(base: str) -> Any:
        def method(q: Any, frame: Any = None) -> Any:
            k = tree.frame_position(frame)
            return call(fns[f"{base}_{k}"], q, shapes)

        method.__name__ = base
        return method

    def every(name: str) -> Any:
        def method(q: Any) -> Any:
            return call(fns[name], q, shapes_all)

        method.__name__ = name
        return method

    functions = {name: every(name) if name.endswith("_all") else framed(name) for name in TREE_METHODS}
    kin = TreeKinematics(tree, "casadi", functions, files, Path(module.__file__ or ""), module)
    kin.functions = fns  # type: ignore[attr-defined]
    return kin
