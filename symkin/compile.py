"""``symkin.compile``: robot -> symbolic derivation -> emitted code -> loaded :class:`Kinematics`.

Generated sources are cached per user (``$SYMKIN_CACHE`` or ``~/.cache/symkin``) under a key made
of the robot's structural hash, the backend, the symkin version and the templates, so a warm
compile neither imports sympy nor re-derives anything.
"""

from __future__ import annotations

import hashlib
import json
import os
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from symkin.emit.c.build import cache_dir
from symkin.errors import CompileError, SymkinError
from symkin.model.frames import ChainTables, frame_index, frame_jacobian
from symkin.model.robot import Robot, as_batch
from symkin.runtime.kinematics import KIN_METHODS, Kinematics

__all__ = ["compile", "generate", "write_generated", "BACKENDS", "STRATEGIES", "cache_dir"]

BACKENDS = ("c", "numpy", "casadi")
_LOADED: dict[str, Kinematics] = {}
_FUNCTIONS: dict[tuple[str, str | None], list] = {}  # functions by (robot key, strategy), shared by backends


@lru_cache(maxsize=1)
def _templates_digest() -> str:
    from symkin.emit.templates import template_dir

    h = hashlib.sha256()
    root = template_dir()
    for path in sorted(p for b in BACKENDS for p in (root / b).rglob("*.j2")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def _is_tree(robot: Any) -> bool:
    from symkin.model.tree import Tree

    return isinstance(robot, Tree)


def _check_backend(backend: str) -> None:
    if backend not in BACKENDS:
        raise SymkinError(f"unknown backend {backend!r}: choose one of {', '.join(BACKENDS)}")


STRATEGIES = ("expanded", "program")


def _check_strategy(strategy: str | None) -> None:
    if strategy is not None and strategy not in STRATEGIES:
        raise SymkinError(
            f"unknown strategy {strategy!r}: choose one of {', '.join(STRATEGIES)} (or None: by size)"
        )


def generate(
    robot: Robot, backend: str, command: str | None = None, strategy: str | None = None
) -> dict[str, str]:
    """The generated source files of ``robot`` for ``backend`` (filename -> text). Imports sympy.

    ``strategy``: ``"expanded"`` (one exact expression per output, then CSE: the smallest, most
    readable code for arms of up to about 7 joints), ``"program"`` (named link frames, Hessians as
    loops: linear in the number of joints), or None to choose by size (the generated header says
    which was used).
    """
    _check_backend(backend)
    _check_strategy(strategy)
    if _is_tree(robot):
        from symkin.compile_tree import generate_tree

        if strategy not in (None, "program"):
            raise SymkinError("a tree compiles as one program (strategy 'program'), not " + repr(strategy))

        return generate_tree(robot, backend, command)  # type: ignore[arg-type]
    if robot.n == 0:
        raise SymkinError(f"robot {robot.name!r} has no joints: nothing to compile")
    from symkin.symbolic.functions import kin_functions

    command = command or f"symkin compile {robot.identifier} --backend {backend}"
    functions = _FUNCTIONS.get((robot.key, strategy))
    if functions is None:
        functions = kin_functions(robot, strategy=strategy)
        if len(_FUNCTIONS) > 32:
            _FUNCTIONS.clear()
        _FUNCTIONS[(robot.key, strategy)] = functions
    if backend == "c":
        from symkin.emit.c.backend import render_c

        return render_c(robot, functions, command)
    if backend == "numpy":
        from symkin.emit.numpy.backend import render_numpy

        return render_numpy(robot, functions, command)
    from symkin.emit.casadi.backend import render_casadi

    return render_casadi(robot, functions, command)


def write_generated(
    robot: Robot, backend: str, folder: str | Path, command: str | None = None, strategy: str | None = None
) -> list[Path]:
    """Generate and write the files of ``robot`` for ``backend`` into ``folder``; returns the paths."""
    files = generate(robot, backend, command, strategy)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, text in sorted(files.items()):
        path = folder / name
        path.write_text(text)
        out.append(path)
    return out


def _cache_key(robot: Robot, backend: str, strategy: str | None = None) -> str:
    from symkin import __version__

    text = "\n".join((__version__, backend, robot.key, str(strategy), _templates_digest()))
    return hashlib.sha256(text.encode()).hexdigest()[:32]


def _cached_files(
    robot: Robot, backend: str, key: str, use_cache: bool, strategy: str | None = None
) -> dict[str, str]:
    """Generated files from the cache (verified by checksum), else generate and store atomically."""
    path = cache_dir() / "gen" / f"{key}.json"
    if use_cache and path.exists():
        try:
            data = json.loads(path.read_text())
            files = data["files"]
            digest = hashlib.sha256(json.dumps(files, sort_keys=True).encode()).hexdigest()
            if data.get("sha256") == digest:
                return files
        except (OSError, ValueError, KeyError, TypeError):
            pass  # corrupted entry: regenerate below
    files = generate(robot, backend, strategy=strategy)
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


def compile(  # noqa: A001
    robot: Robot | str, backend: str = "c", cache: bool = True, strategy: str | None = None
) -> Kinematics:
    """Compile ``robot`` (a Robot, a built-in name or ETS text) into a :class:`Kinematics`, or a
    :class:`symkin.Tree` into one kernel for all its frames, a
    :class:`~symkin.runtime.tree_kinematics.TreeKinematics`.

    ``backend`` is ``"c"`` (a generated C library behind a CPython extension, the fast path),
    ``"numpy"`` (a generated Python module, batched) or ``"casadi"`` (``casadi.Function`` objects,
    for optimisation problems). Every backend has the numeric reference's methods and shapes.
    ``strategy`` chooses how the code is derived (see :func:`generate`; default by size).
    """
    _check_backend(backend)
    _check_strategy(strategy)
    if _is_tree(robot):
        from symkin.compile_tree import compile_tree

        if strategy not in (None, "program"):
            raise SymkinError("a tree compiles as one program (strategy 'program'), not " + repr(strategy))

        return compile_tree(robot, backend, cache)  # type: ignore[arg-type,return-value]
    if isinstance(robot, str):
        from symkin.model.resolve import resolve_robot

        robot = resolve_robot(robot)
    if not isinstance(robot, Robot):
        raise TypeError(
            f"compile() needs a Robot, a built-in robot name or ETS text, not {type(robot).__name__}"
        )
    if robot.n == 0:
        raise SymkinError(f"robot {robot.name!r} has no joints: nothing to compile")
    key = _cache_key(robot, backend, strategy)
    if cache and key in _LOADED:
        return _LOADED[key]
    files = _cached_files(robot, backend, key, cache, strategy)
    if backend == "c":
        from symkin.emit.c.backend import build_c

        module, path = build_c(files)
        functions = {name: getattr(module, name) for name in (*KIN_METHODS, "manipulability", "jacobm")}
        kin = Kinematics(robot, backend, functions, files, path, module)
    elif backend == "numpy":
        from symkin.emit.numpy.backend import load_numpy

        module = load_numpy(files, cache_dir() / "numpy")
        functions = {name: getattr(module, name) for name in KIN_METHODS}
        kin = Kinematics(robot, backend, functions, files, Path(module.__file__ or ""), module)
    else:
        kin = _casadi_kinematics(robot, files)
    if cache:
        _LOADED[key] = kin
    return kin


def _casadi_kinematics(robot: Robot, files: dict[str, str]) -> Kinematics:
    from symkin.emit.numpy.backend import load_numpy

    try:
        module = load_numpy(files, cache_dir() / "casadi")
    except ImportError as exc:  # pragma: no cover - casadi is a declared dependency
        raise CompileError(f"the casadi backend needs casadi installed: {exc}") from exc
    fns = module.functions()
    n = robot.n
    shapes = {"T": (4, 4), "J": (6, n), "H": (n, 6, n), "links": (n, 4, 4)}

    def wrap(f: Any) -> Any:
        names = f.name_out()

        def call(q: Any) -> Any:
            Q, single = as_batch(q, n, robot.name)
            if single:
                res = f(Q[0])
                res = res if isinstance(res, (list, tuple)) else [res]
                outs = [np.asarray(r).reshape(shapes[k]) for k, r in zip(names, res)]
            else:
                fm = f.map(Q.shape[0])
                res = fm(Q.T)
                res = res if isinstance(res, (list, tuple)) else [res]
                outs = []
                for k, r in zip(names, res):
                    a = np.asarray(r)  # (rows, cols*N), column blocks per configuration
                    rows, cols = a.shape[0], a.shape[1] // Q.shape[0]
                    a = a.reshape(rows, Q.shape[0], cols).transpose(1, 0, 2)
                    outs.append(a.reshape((Q.shape[0], *shapes[k])))
            return outs[0] if len(outs) == 1 else tuple(outs)

        call.__name__ = f.name()
        call.__doc__ = f"{f.name()} through casadi.Function (see Kinematics.functions)."
        return call

    functions = {name: wrap(fns[name]) for name in KIN_METHODS}
    link_poses = functions["link_poses"]

    def framed(name: str) -> Any:
        plain = functions[name]

        def call(q: Any, frame: Any = None) -> Any:
            if frame is None:
                return plain(q)
            k = frame_index(frame, n, robot.name)
            L = link_poses(q)
            if name == "fkine":
                return L[..., k, :, :]
            Lb = L[None] if L.ndim == 3 else L
            J = frame_jacobian(Lb, k, chain, ee=name == "jacobe")
            return J[0] if L.ndim == 3 else J

        call.__name__, call.__doc__ = plain.__name__, plain.__doc__
        return call

    chain = ChainTables.of(robot.ets)
    for name in ("fkine", "jacob0", "jacobe"):
        functions[name] = framed(name)
    kin = Kinematics(robot, "casadi", functions, files, Path(module.__file__ or ""), module)
    kin.functions = fns  # type: ignore[attr-defined]
    return kin
