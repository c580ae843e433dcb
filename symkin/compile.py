"""``symkin.compile``: robot -> symbolic derivation -> emitted code -> loaded :class:`Kinematics`.

Generated sources are cached per user (``$SYMKIN_CACHE`` or ``~/.cache/symkin``) under a key made
of everything they depend on: every attribute of the robot (:attr:`Robot.fingerprint`: name, ETS,
limits, speed limits, joint names, configurations, source; the C header lists the limits), the
backend and strategy, the symkin version, the templates, the compiler's own Python code
(symbolic, emit and the model classes it prints) and the sympy version. So a warm compile
neither imports sympy nor re-derives anything, a changed derivation never serves stale code, and
robots differing only in limits get their own files and their own in-memory :class:`Kinematics`
(the derivation itself, which depends on the name and ETS only, is shared).
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np

from symkin.emit.c.build import cache_dir, write_atomic
from symkin.errors import CompileError, SymkinError
from symkin.model.frames import ChainTables, frame_index, frame_jacobian
from symkin.model.robot import MAX_JOINT_VALUE, Robot, as_batch
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


# the compiler's own code: what it derives and prints depends on these files
_COMPILER_SOURCES = (
    "symbolic",
    "emit",
    "model/ets.py",
    "model/robot.py",
    "model/tree.py",
    "compile.py",
    "compile_tree.py",
)


@lru_cache(maxsize=1)
def _compiler_digest() -> str:
    """sha256 of the compiler's Python sources (:data:`_COMPILER_SOURCES`) and the sympy version."""
    from importlib import metadata

    h = hashlib.sha256(_sources_digest(Path(__file__).resolve().parent).encode())
    with contextlib.suppress(metadata.PackageNotFoundError):  # sympy is a declared dependency
        h.update(metadata.version("sympy").encode())
    return h.hexdigest()


def _sources_digest(root: Path) -> str:
    """sha256 of the :data:`_COMPILER_SOURCES` under the package folder ``root``."""
    h = hashlib.sha256()
    paths: list[Path] = []
    for part in _COMPILER_SOURCES:
        p = root / part
        paths += sorted(p.rglob("*.py")) if p.is_dir() else [p]
    for path in paths:
        h.update(path.relative_to(root).as_posix().encode() + b"\0")
        h.update(path.read_bytes() + b"\0")
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
    robot: Robot,
    backend: str,
    command: str | None = None,
    strategy: str | None = None,
    prefix: str | None = None,
    precision: str = "double",
    libm: bool = False,
) -> dict[str, str]:
    """The generated source files of ``robot`` for ``backend`` (filename -> text). Imports sympy.

    ``strategy``: ``"expanded"`` (one exact expression per output, then CSE: the smallest, most
    readable code for arms of up to about 7 joints), ``"program"`` (named link frames, Hessians as
    loops: linear in the number of joints), or None to choose by size (the generated header says
    which was used). C backend only: ``prefix``, the prefix of every exported symbol and file name
    instead of ``symkin_<robot>``, so several robots link into one program; ``precision="float"``
    for single-precision code (no Python module; for microcontrollers); ``libm`` to call the C
    library's sin and cos instead of the inline kernels.
    """
    _check_backend(backend)
    _check_strategy(strategy)
    if (prefix is not None or precision != "double" or libm) and backend != "c":
        raise SymkinError(f"prefix, precision and libm apply to the C backend only, not {backend!r}")
    if _is_tree(robot):
        from symkin.compile_tree import generate_tree

        if strategy not in (None, "program"):
            raise SymkinError("a tree compiles as one program (strategy 'program'), not " + repr(strategy))

        if prefix is not None or precision != "double" or libm:
            raise SymkinError(
                "prefix, precision and libm are for serial chains; trees compile with the defaults"
            )
        return generate_tree(robot, backend, command)  # type: ignore[arg-type]
    if robot.n == 0:
        raise SymkinError(f"robot {robot.name!r} has no joints: nothing to compile")
    if prefix is not None:
        from symkin.emit.c.backend import check_prefix

        check_prefix(prefix)  # before the derivation, which can take long
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

        return render_c(robot, functions, command, prefix, precision, libm)
    if backend == "numpy":
        from symkin.emit.numpy.backend import render_numpy

        return render_numpy(robot, functions, command)
    from symkin.emit.casadi.backend import render_casadi

    return render_casadi(robot, functions, command)


def write_generated(
    robot: Robot,
    backend: str,
    folder: str | Path,
    command: str | None = None,
    strategy: str | None = None,
    prefix: str | None = None,
    precision: str = "double",
    libm: bool = False,
) -> list[Path]:
    """Generate and write the files of ``robot`` for ``backend`` into ``folder``, with the manifest
    :func:`symkin.load_compiled` reads back (``<stem>.symkin.json``); returns the paths
    (options as :func:`generate`)."""
    from symkin.compiled import write_manifest

    files = generate(robot, backend, command, strategy, prefix, precision, libm)
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    out = []
    for name, text in sorted(files.items()):
        path = folder / name
        path.write_text(text)
        out.append(path)
    out.append(write_manifest(robot, backend, files, folder, precision))
    return out


def _cache_key(robot: Robot, backend: str, strategy: str | None = None) -> str:
    from symkin import __version__

    parts = (__version__, backend, robot.fingerprint, str(strategy), _templates_digest(), _compiler_digest())
    text = "\n".join(parts)
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
        with contextlib.suppress(OSError):  # an unwritable cache only costs speed
            write_atomic(path, json.dumps({"sha256": digest, "files": files}))
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
    key = _cache_key(robot, backend, strategy)  # every attribute of the robot: see the module docstring
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
        kin = Kinematics(robot, backend, functions, files, _module_path(module), module)
    else:
        kin = _casadi_kinematics(robot, files)
    if cache:
        if len(_LOADED) > 256:
            _LOADED.clear()
        _LOADED[key] = kin
    return kin


def _module_path(module: Any) -> Path | None:
    """The file a generated module was loaded from; None when imported from memory."""
    file = getattr(module, "__file__", None)
    return Path(file) if file else None


def _casadi_kinematics(robot: Robot, files: dict[str, str]) -> Kinematics:
    from symkin.emit.numpy.backend import load_numpy

    try:
        module = load_numpy(files, cache_dir() / "casadi")
    except ImportError as exc:  # pragma: no cover - casadi is a declared dependency
        raise CompileError(f"the casadi backend needs casadi installed: {exc}") from exc
    fns = module.functions()
    n = robot.n
    functions = {name: _casadi_method(fns[name], robot) for name in KIN_METHODS}
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
    kin = Kinematics(robot, "casadi", functions, files, _module_path(module), module)
    kin.functions = fns  # type: ignore[attr-defined]
    return kin


def _casadi_method(f: Any, robot: Robot) -> Any:
    """A Kinematics method calling the casadi.Function ``f``: one configuration through a
    ``Function.buffer()`` bound once to arrays (no DM conversion; a lock keeps it thread-safe), a
    batch through ``f.map``."""
    import threading

    n, name = robot.n, robot.name
    shapes = {"T": (4, 4), "J": (6, n), "H": (n, 6, n), "links": (n, 4, 4)}
    names = f.name_out()
    dense = f.sparsity_in(0).is_dense() and all(f.sparsity_out(i).is_dense() for i in range(f.n_out()))
    buf = evaluate = None
    if dense and hasattr(f, "buffer"):
        qbuf = np.zeros(n)
        outs = [np.zeros(f.nnz_out(i)) for i in range(f.n_out())]
        buf, evaluate = f.buffer()
        buf.set_arg(0, memoryview(qbuf))
        for i, out in enumerate(outs):
            buf.set_res(i, memoryview(out))
        sizes = [f.size_out(i) for i in range(f.n_out())]  # (rows, cols); nonzeros column-major
        lock = threading.Lock()
    f64 = np.dtype(float)

    def call(q: Any) -> Any:
        fast = evaluate is not None and type(q) is np.ndarray and q.dtype is f64 and q.shape == (n,)
        if fast and math.isfinite(sum(ql := q.tolist())) and max(map(abs, ql)) <= MAX_JOINT_VALUE:
            with lock:
                np.copyto(qbuf, q)
                evaluate()
                ok = buf.ret() == 0
                # copies: the buffers are reused by the next call (and by other threads)
                res = [
                    o.reshape(c, r).T.copy().reshape(shapes[k]) for o, (r, c), k in zip(outs, sizes, names)
                ]
            if ok:
                return res[0] if len(res) == 1 else tuple(res)
        Q, single = as_batch(q, n, name)  # raises the reference's error for invalid q
        if Q.shape[0] == 0:  # casadi cannot map over 0 items
            outs1 = [np.zeros((0, *shapes[k])) for k in names]
        elif single:
            res = f(Q[0])
            res = res if isinstance(res, (list, tuple)) else [res]
            outs1 = [np.asarray(r).reshape(shapes[k]) for k, r in zip(names, res)]
        else:
            fm = f.map(Q.shape[0])
            res = fm(Q.T)
            res = res if isinstance(res, (list, tuple)) else [res]
            outs1 = []
            for k, r in zip(names, res):
                a = np.asarray(r)  # (rows, cols*N), column blocks per configuration
                rows, cols = a.shape[0], a.shape[1] // Q.shape[0]
                a = a.reshape(rows, Q.shape[0], cols).transpose(1, 0, 2)
                outs1.append(a.reshape((Q.shape[0], *shapes[k])))
        return outs1[0] if len(outs1) == 1 else tuple(outs1)

    call.__name__ = f.name()
    call.__doc__ = f"{f.name()} through casadi.Function (see Kinematics.functions)."
    return call
