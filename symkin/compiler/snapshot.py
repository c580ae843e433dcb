"""The checked-in copies of the generated code under ``generated/``: regenerate, compare, update.

``symkin generate`` writes ``generated/<robot>/<backend>/...`` for every built-in robot and every
backend; ``symkin generate --check`` (and the test suite) regenerates into memory and reports the
files that differ, like SymForce's ``compare_or_update``.
"""

from __future__ import annotations

from collections.abc import Iterable
from pathlib import Path

from symkin.compiler.compile import BACKENDS, generate

__all__ = ["snapshot_files", "compare_or_update", "COMMAND"]

COMMAND = "symkin generate"


def snapshot_files(
    robots: Iterable[str] | None = None, backends: Iterable[str] = BACKENDS, progress: bool = False
) -> dict[str, str]:
    """Every generated file as ``"<robot>/<backend>/<file>" -> text``."""
    from symkin.core.progress import bar
    from symkin.model.robots import list_robots, load

    out: dict[str, str] = {}
    for name in bar(list(robots or list_robots()), progress, desc="generating"):
        robot = load(name)
        for backend in backends:
            for fname, text in generate(robot, backend, COMMAND).items():
                out[f"{name}/{backend}/{fname}"] = text
    return out


def compare_or_update(
    folder: str | Path, update: bool = False, robots: Iterable[str] | None = None, progress: bool = False
) -> list[str]:
    """Files under ``folder`` that differ from a fresh generation (missing, changed or stale).

    With ``update`` the folder is rewritten to match and the same list is returned.
    """
    folder = Path(folder)
    fresh = snapshot_files(robots, progress=progress)
    existing = {
        p.relative_to(folder).as_posix(): p
        for p in folder.rglob("*")
        if p.is_file() and p.name != "README.md"
    }
    if robots is not None:
        existing = {k: v for k, v in existing.items() if k.split("/", 1)[0] in set(robots)}
    differ = sorted(
        [k for k, text in fresh.items() if k not in existing or existing[k].read_text() != text]
        + [k for k in existing if k not in fresh]
    )
    if update:
        for k in differ:
            path = folder / k
            if k in fresh:
                path.parent.mkdir(parents=True, exist_ok=True)
                path.write_text(fresh[k])
            else:
                path.unlink()
    return differ
