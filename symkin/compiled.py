"""Folders of generated code: what ``symkin compile -o DIR`` writes, and :func:`load_compiled`.

Beside the generated sources, ``symkin compile -o DIR`` (and :func:`symkin.write_generated`)
writes a manifest ``<stem>.symkin.json`` (``stem`` the main file's name without its suffix, e.g.
``symkin_panda``): the symkin version, the backend, the C prefix, the robot (ETS text, which
round-trips exactly, name, joint names, limits, speeds, configurations, source) and the sha256 of
every file. :func:`load_compiled` reads it back: the C sources are compiled (through the cache,
like :func:`symkin.compile`) and their extension module loaded, a NumPy or CasADi module is
imported from the folder itself. No sympy is imported.
"""

from __future__ import annotations

import hashlib
import json
import sys
from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import CompileError
from symkin.model.ets import ETS
from symkin.model.robot import Robot
from symkin.runtime.kinematics import KIN_METHODS, Kinematics

__all__ = ["load_compiled", "write_manifest", "manifest_name", "MANIFEST_SUFFIX"]

MANIFEST_SUFFIX = ".symkin.json"
FORMAT = 1


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def manifest_name(files: dict[str, str]) -> str:
    """The manifest's file name for a set of generated files: ``<stem>.symkin.json``."""
    headers = sorted(name for name in files if name.endswith(".h"))
    main = headers[0] if headers else sorted(name for name in files if name.endswith(".py"))[0]
    return main.rsplit(".", 1)[0] + MANIFEST_SUFFIX


def write_manifest(
    robot: Robot, backend: str, files: dict[str, str], folder: str | Path, precision: str = "double"
) -> Path:
    """Write the manifest of ``files`` (generated for ``robot`` on ``backend``, in ``precision``)
    into ``folder``."""
    data = {
        "format": FORMAT,
        "generator": "symkin",
        "version": _version(),
        "backend": backend,
        "robot": {
            "name": robot.name,
            "ets": str(robot.ets),
            "joint_names": list(robot.joint_names),
            "qlim": robot.qlim.tolist(),
            "qd_max": None if robot.qd_max is None else robot.qd_max.tolist(),
            "configs": {k: v.tolist() for k, v in robot.configs.items() if k != "qz"},
            "source": robot.source,
        },
        "files": {name: _digest(text) for name, text in sorted(files.items())},
    }
    if precision != "double":
        data["precision"] = precision
    path = Path(folder) / manifest_name(files)
    path.write_text(json.dumps(data, indent=2) + "\n")
    return path


def _version() -> str:
    from symkin import __version__

    return __version__


def _find_manifest(folder: Path, name: str | None) -> Path:
    if not folder.is_dir():
        what = "does not exist" if not folder.exists() else "is not a folder"
        raise CompileError(
            f"{str(folder)!r} {what}: load_compiled takes the folder written by `symkin compile -o DIR`"
        )
    found = sorted(folder.glob("*" + MANIFEST_SUFFIX))
    if name is not None:
        found = [
            p for p in found if p.name[: -len(MANIFEST_SUFFIX)] in (name, f"symkin_{name}", f"{name}_casadi")
        ]
    if not found and any(folder.glob("*_tree*.[chp]*")):
        raise CompileError(
            f"{str(folder)!r} holds the code of a kinematic tree, which load_compiled does not read "
            "(it reads chains): compile the tree with symkin.compile(symkin.Tree.from_urdf(...)), "
            "which reuses the compile cache"
        )
    if not found:
        hint = f" for {name!r}" if name is not None else ""
        raise CompileError(
            f"{str(folder)!r} is not a folder written by `symkin compile -o DIR`: it has no "
            f"*{MANIFEST_SUFFIX} manifest{hint} (older symkin versions wrote none: compile again)"
        )
    if len(found) > 1:
        stems = [p.name[: -len(MANIFEST_SUFFIX)] for p in found]
        raise CompileError(f"{str(folder)!r} holds the code of several robots {stems}: choose one with name=")
    return found[0]


def _robot(data: dict, where: str) -> Robot:
    try:
        r = data["robot"]
        return Robot(
            ETS.parse(r["ets"]),
            name=r["name"],
            qlim=np.array(r["qlim"], dtype=float),
            configs={k: np.array(v, dtype=float) for k, v in r.get("configs", {}).items()},
            joint_names=tuple(r["joint_names"]),
            qd_max=None if r.get("qd_max") is None else np.array(r["qd_max"], dtype=float),
            source=r.get("source", ""),
        )
    except (KeyError, TypeError, ValueError) as exc:
        raise CompileError(f"{where}: the robot in the manifest is unreadable ({exc})") from None


def load_compiled(folder: str | Path, name: str | None = None, verify: bool = True) -> Kinematics:
    """The :class:`symkin.Kinematics` of the generated code in ``folder`` (``symkin compile -o DIR``).

    C: the ``.c``/``.h`` files are compiled (cached by content, needs a C compiler) and their
    extension module imported; NumPy and CasADi: the module in the folder is imported. ``name``
    picks one robot when the folder holds several (the prefix or robot name). With ``verify`` a file
    whose sha256 differs from the manifest's (edited since it was written) raises CompileError;
    ``verify=False`` loads edited files as they are.
    """
    folder = Path(folder).expanduser()
    path = _find_manifest(folder, name)
    where = str(path)
    try:
        data = json.loads(path.read_text())
        backend, digests = data["backend"], data["files"]
    except (OSError, ValueError, KeyError, TypeError) as exc:
        raise CompileError(f"{where} is not a readable symkin manifest ({exc})") from None
    if data.get("generator") != "symkin" or backend not in ("c", "numpy", "casadi"):
        raise CompileError(f"{where} is not a symkin manifest (backend {backend!r})")
    files: dict[str, str] = {}
    for fname, digest in digests.items():
        if "/" in fname or "\\" in fname or fname.startswith("."):
            raise CompileError(f"{where} names the file {fname!r}, which is not a plain file name")
        try:
            text = (folder / fname).read_text()
        except OSError:
            raise CompileError(f"{str(folder)!r} lacks {fname}, which the manifest lists") from None
        if verify and _digest(text) != digest:
            raise CompileError(
                f"{fname} in {str(folder)!r} differs from what symkin wrote (edited?); "
                "load it anyway with load_compiled(..., verify=False)"
            )
        files[fname] = text
    if data.get("precision", "double") != "double":
        raise CompileError(
            f"{str(folder)!r} holds {data['precision']}-precision C code, which is for embedding and has "
            "no Python module: compile without --precision to load it here"
        )
    robot = _robot(data, where)
    if backend == "c":
        from symkin.emit.c.backend import build_c

        module, lib = build_c(files)
        functions = {f: getattr(module, f) for f in (*KIN_METHODS, "manipulability", "jacobm")}
        return Kinematics(robot, "c", functions, files, lib, module)
    (pyname,) = [f for f in files if f.endswith(".py")]
    if backend == "numpy":
        module = _import(folder / pyname, files[pyname])
        return Kinematics(
            robot, "numpy", {f: getattr(module, f) for f in KIN_METHODS}, files, folder / pyname, module
        )
    from symkin.compile import _casadi_kinematics

    return _casadi_kinematics(robot, {pyname: files[pyname]})


def _import(path: Path, text: str) -> Any:
    """Import the module at ``path`` (whose verified text is ``text``) under a name unique to its
    content, compiled from that text: never from a ``__pycache__`` beside it, which nothing checks."""
    from symkin.emit.numpy.backend import import_source

    name = f"_{path.stem}_{_digest(text)[:12]}_loaded"
    if name in sys.modules:
        return sys.modules[name]
    return import_source(name, text, path)
