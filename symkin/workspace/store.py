"""Zarr stores of maps and datasets: layout, attributes, and which blocks are already written.

A store is a Zarr group whose attributes say what it holds (``kind``, ``robot``, ``settings``,
``seed``, ``symkin_version``) and whose ``done`` array marks the blocks written so far. The client
writes a block's data first and its ``done`` mark after, so an interrupted run (Ctrl-C, a lost
client) leaves at worst a block that is computed again when the run resumes.
"""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import MissingExtraError, WorkspaceError

__all__ = ["zarr_module", "open_store", "robot_attrs"]

SCALE_HINT = 'pip install "symkin[scale]"'


def zarr_module() -> Any:
    """The zarr module, or a MissingExtraError naming the extra."""
    try:
        import zarr
    except ImportError:
        raise MissingExtraError(f"workspace maps and datasets need zarr and dask: {SCALE_HINT}") from None
    return zarr


def robot_attrs(robot: Any) -> dict[str, Any]:
    """The robot as stored in a store's attributes (enough to rebuild it from the ETS)."""
    return {
        "name": robot.name,
        "ets": str(robot.ets),
        "qlim": np.asarray(robot.qlim).tolist(),
        "key": robot.key,
    }


def _jsonable(x: Any) -> Any:
    return json.loads(json.dumps(x, default=lambda v: v.tolist() if hasattr(v, "tolist") else str(v)))


def _first_difference(a: Any, b: Any, where: str = "") -> str | None:
    if isinstance(a, dict) and isinstance(b, dict):
        for k in sorted(set(a) | set(b)):
            d = _first_difference(a.get(k), b.get(k), f"{where}.{k}" if where else k)
            if d:
                return d
        return None
    return None if a == b else f"{where}: stored {a!r}, asked {b!r}"


def open_store(
    path: str | Path | None,
    attrs: dict[str, Any],
    arrays: dict[str, tuple[tuple[int, ...], tuple[int, ...], str, Any]],
    overwrite: bool = False,
    grow: str | None = None,
    init: Callable[[Any], None] | None = None,
) -> Any:
    """Open (or create) the Zarr group at ``path`` for ``attrs`` with ``arrays``
    (name -> (shape, chunks, dtype, fill value)); ``None`` keeps it in memory.

    An existing store is reused when its attributes equal ``attrs`` (so a run resumes), else a
    WorkspaceError names the first difference. With ``grow`` (an attribute of ``attrs["settings"]``
    such as the dataset size), a store holding fewer rows is extended along axis 0 (appending).
    ``init(group)`` fills a new store's arrays before its attributes are written; a store without
    attributes (its creation was interrupted) is made afresh.
    """
    zarr = zarr_module()
    attrs = _jsonable(attrs)
    group = None
    if path is not None and not overwrite and _exists(path):
        try:
            group = zarr.open_group(str(path), mode="r+")
        except Exception as exc:  # noqa: BLE001 - zarr raises many kinds for a non-store
            raise WorkspaceError(f"{path} exists and is not a Zarr store symkin can open: {exc}") from None
        if "kind" not in group.attrs and not list(group.keys()):
            group = None  # an empty group (a creation that was interrupted): make it afresh
        elif "kind" not in group.attrs and "done" in group:
            group = None  # arrays made but the attributes never written: an interrupted creation
    if group is not None:
        old = dict(group.attrs)
        new = json.loads(json.dumps(attrs))
        if grow is not None:
            have, want = old.get("settings", {}).get(grow), new["settings"][grow]
            old.get("settings", {}).pop(grow, None)
            new["settings"].pop(grow)
        diff = _first_difference(old, new)
        if diff is not None:
            raise WorkspaceError(
                f"{path} holds a different {old.get('kind', 'store')} ({diff}); "
                "choose another path or overwrite it"
            )
        if grow is not None and want != have:
            if want < have:
                raise WorkspaceError(f"{path} already holds {have} {grow}; ask for at least that many")
            for name, (shape, _chunks, _dtype, _fill) in arrays.items():
                group[name].resize(shape)
            group.attrs["settings"] = {**group.attrs["settings"], grow: want}
        return group
    store = str(path) if path is not None else zarr.storage.MemoryStore()
    group = zarr.open_group(store, mode="w")
    for name, (shape, chunks, dtype, fill) in arrays.items():
        group.create_array(name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill)
    if init is not None:
        init(group)
    group.attrs.update(attrs)  # last: a store with attributes is complete
    return group


def _exists(path: str | Path) -> bool:
    text = str(path)
    if "://" in text:  # a remote store: let zarr decide
        try:
            zarr_module().open_group(text, mode="r")
            return True
        except Exception:  # noqa: BLE001
            return False
    return Path(text).exists()
