"""Folders of generated code: what ``symkin compile -o DIR`` writes, and :func:`load_compiled`.

Beside the generated sources, ``symkin compile -o DIR`` (and :func:`symkin.write_generated`)
writes a manifest ``<stem>.symkin.json`` (``stem`` the main file's name without its suffix, e.g.
``symkin_panda``, ``symkin_quadruped_tree`` or a C prefix): the symkin version, the kind of model
(``"chain"`` or ``"tree"``; manifests without it are chains), the backend, the model and the
sha256 of every file. A chain is stored as its ETS text (which round-trips exactly), name, joint
names, limits, speeds, configurations and source; a tree as every field of :class:`Tree` (its
segments' ETS as text, the slots' multipliers and offsets as exact fractions), so either is rebuilt
exactly without the URDF. :func:`load_compiled` reads it back: the C sources are compiled (through
the cache, like :func:`symkin.compile`) and their extension module loaded, a NumPy or CasADi module
is imported from the folder itself. No sympy is imported.
"""

from __future__ import annotations

import hashlib
import json
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from symkin.errors import CompileError, SymkinError
from symkin.model.data import model_of_data
from symkin.model.robot import Robot
from symkin.model.tree import Tree

__all__ = [
    "Manifest",
    "read_manifest",
    "import_module_file",
    "write_manifest",
    "manifest_name",
    "MANIFEST_SUFFIX",
]

MANIFEST_SUFFIX = ".symkin.json"
FORMAT = 1
KINDS = ("chain", "tree")


def _digest(text: str) -> str:
    return hashlib.sha256(text.encode()).hexdigest()


def manifest_name(files: dict[str, str]) -> str:
    """The manifest's file name for a set of generated files: ``<stem>.symkin.json``."""
    headers = sorted(name for name in files if name.endswith(".h"))
    main = headers[0] if headers else sorted(name for name in files if name.endswith(".py"))[0]
    return main.rsplit(".", 1)[0] + MANIFEST_SUFFIX


def write_manifest(
    robot: Robot | Tree, backend: str, files: dict[str, str], folder: str | Path, precision: str = "double"
) -> Path:
    """Write the manifest of ``files`` (generated for the chain or tree ``robot`` on ``backend``,
    in ``precision``) into ``folder``."""
    kind, model = robot.to_data()
    data = {
        "format": FORMAT,
        "generator": "symkin",
        "version": _version(),
        "kind": kind,
        "backend": backend,
        "robot": model,
        "files": {name: _digest(text) for name, text in sorted(files.items())},
    }
    if precision != "double":
        data["precision"] = precision
    path = Path(folder) / manifest_name(files)
    path.write_text(json.dumps(data, indent=2) + "\n")
    return path


def _version() -> str:
    from symkin.core.version import __version__

    return __version__


def _find_manifest(folder: Path, name: str | None) -> Path:
    if not folder.is_dir():
        what = "does not exist" if not folder.exists() else "is not a folder"
        raise CompileError(
            f"{str(folder)!r} {what}: load_compiled takes the folder written by `symkin compile -o DIR`"
        )
    found = sorted(folder.glob("*" + MANIFEST_SUFFIX))
    if name is not None:
        stems = {p: p.name[: -len(MANIFEST_SUFFIX)] for p in found}
        exact = [p for p in found if stems[p] == name]  # a prefix, or the stem itself
        forms = {
            f"{name}_casadi",
            *(f"symkin_{name}{tail}" for tail in ("", "_casadi", "_tree", "_tree_casadi")),
        }
        found = exact or [p for p in found if stems[p] in forms]
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


def _model(data: dict, where: str) -> Robot | Tree:
    """The chain or tree the manifest describes (a manifest without ``kind``: a chain)."""
    kind = data.get("kind", "chain")
    if kind not in KINDS:
        raise CompileError(f"{where}: unknown kind of model {kind!r} (symkin reads {', '.join(KINDS)})")
    try:
        return model_of_data(kind, data["robot"])
    except (KeyError, TypeError, ValueError, StopIteration, SymkinError) as exc:
        raise CompileError(
            f"{where}: the {'tree' if kind == 'tree' else 'robot'} in the manifest is unreadable ({exc})"
        ) from None


@dataclass(frozen=True)
class Manifest:
    """What a folder of ``symkin compile -o`` holds: the robot (a chain, or a :class:`Tree`), the
    backend, the generated files (name -> text) and the folder."""

    robot: Robot | Tree
    backend: str
    files: dict[str, str]
    folder: Path

    @property
    def kind(self) -> str:
        """``"tree"`` or ``"chain"``."""
        return self.robot.to_data()[0]


def read_manifest(folder: str | Path, name: str | None = None, verify: bool = True) -> Manifest:
    """The manifest and files in ``folder`` (see :func:`symkin.load_compiled` for ``name`` and
    ``verify``); CompileError when they are missing, unreadable, edited or for embedding only."""
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
    return Manifest(_model(data, where), backend, files, folder)


def import_module_file(path: Path, text: str) -> Any:
    """Import the module at ``path`` (whose verified text is ``text``) under a name unique to its
    content, compiled from that text: never from a ``__pycache__`` beside it, which nothing checks."""
    from symkin.emit.numpy.backend import import_source

    name = f"_{path.stem}_{_digest(text)[:12]}_loaded"
    if name in sys.modules:
        return sys.modules[name]
    return import_source(name, text, path)
