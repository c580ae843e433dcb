"""Zarr stores of maps and datasets: layout, attributes, and which blocks are already written.

A store is a Zarr group whose attributes say what it holds (``kind``, ``robot``, ``settings``,
``seed``, ``symkin_version``) and whose ``done`` array marks the blocks written so far. The client
writes a block's data first and its ``done`` mark after, so an interrupted run (Ctrl-C, a lost
client) leaves at worst a block that is computed again when the run resumes.

symkin writes the attribute ``symkin_store`` first into every store it creates: only such a store
(or an empty folder) is ever replaced (``overwrite``) or remade; any other path (a folder of the
user's files, a file, a store another program wrote) is refused and left untouched. A chunk that
cannot be read (a damaged disk, a truncated file) is named in a WorkspaceError, and a run that
resumes computes the blocks of such chunks again (:func:`damaged_blocks`).

What is read back is verified: every chunk carries a CRC-32C (Zarr's ``crc32c`` codec), so a
flipped byte makes its chunk unreadable (and recomputed on resume) instead of a wrong number; and
the attribute ``symkin_sha256`` holds a sha256 of the other attributes and of every array's
metadata (shape, chunks, dtype, fill value, codecs: a chunk never written reads as its fill
value), so a store whose metadata were edited or damaged is a WorkspaceError, never a wrong map
(stores written before it have no such attribute and are read as they are).
"""

from __future__ import annotations

import json
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import MissingExtraError, WorkspaceError

__all__ = [
    "zarr_module",
    "open_store",
    "open_stored",
    "robot_attrs",
    "read_array",
    "read_marks",
    "damaged_blocks",
    "reset_blocks",
    "resume_marks",
    "MARK",
]

SCALE_HINT = 'pip install "symkin[scale]"'
MARK = "symkin_store"  # written first into every store symkin creates (value: the layout version)
SEAL = "symkin_sha256"  # the sha256 of the other attributes and of the arrays' metadata
_KINDS = ("reachability", "dataset")


def zarr_module() -> Any:
    """The zarr module, or a MissingExtraError naming the extra."""
    try:
        import zarr
    except ImportError:
        raise MissingExtraError(f"workspace maps and datasets need zarr and dask: {SCALE_HINT}") from None
    return zarr


def open_stored(path: Any, kind: str) -> Any:
    """The zarr group at ``path`` holding a symkin store of ``kind`` ("reachability" or
    "dataset"), read-only; WorkspaceError when it cannot be opened or holds something else."""
    what = "map" if kind == "reachability" else kind
    try:
        group = zarr_module().open_group(str(path), mode="r")
    except Exception as exc:  # noqa: BLE001
        raise WorkspaceError(f"cannot open the {what} {path}: {exc}") from None
    if dict(group.attrs).get("kind") != kind:
        raise WorkspaceError(f"{path} does not hold a symkin {'reachability map' if what == 'map' else kind}")
    _verify(group, path)
    return group


def _fingerprint(group: Any, attrs: dict[str, Any] | None = None) -> str:
    """sha256 of the group's attributes (or ``attrs``), but the seal, and of its arrays' shapes,
    chunks, dtypes and fill values."""
    import hashlib

    attrs = {k: v for k, v in (group.attrs if attrs is None else attrs).items() if k != SEAL}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        members = sorted(group.arrays(), key=lambda item: item[0])
    arrays = {
        name: [list(a.shape), list(a.chunks), str(a.dtype), _plain(a.fill_value)] for name, a in members
    }
    text = json.dumps([attrs, arrays], sort_keys=True)
    return hashlib.sha256(text.encode()).hexdigest()


def _plain(value: Any) -> Any:
    """A NumPy scalar as the Python number it holds (its repr differs between NumPy versions)."""
    return value.item() if hasattr(value, "item") else value


def _seal(group: Any) -> None:
    """Write the seal over the attributes and arrays as they now are."""
    group.attrs[SEAL] = _fingerprint(group)


def _verify(group: Any, path: Any) -> None:
    """WorkspaceError when the store's seal does not match its attributes and arrays."""
    seal = dict(group.attrs).get(SEAL)
    if seal is not None and seal != _fingerprint(group):
        raise WorkspaceError(
            f"{path}: its attributes or array metadata (zarr.json) do not match their sha256: edited or "
            "damaged; compute it again with overwrite"
        )


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

    Only a new path, an empty folder or a store symkin wrote is ever created, replaced
    (``overwrite``) or remade; anything else is refused with a WorkspaceError and left as it is.
    """
    zarr = zarr_module()
    attrs = _jsonable(attrs)
    group = None if path is None else _existing_store(path)
    if group is not None and (overwrite or "kind" not in group.attrs):
        _check_replaceable(path, group)  # overwrite, or remake a creation that was interrupted
        group = None
    if group is not None:
        _verify(group, path)
        old = {k: v for k, v in group.attrs.items() if k not in (MARK, SEAL)}
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
            if SEAL in group.attrs:
                _seal(group)
        return group
    store = str(path) if path is not None else zarr.storage.MemoryStore()
    group = zarr.open_group(store, mode="w", attributes={MARK: 1})  # the mark first: a store of ours
    from zarr.codecs import Crc32cCodec, ZstdCodec

    for name, (shape, chunks, dtype, fill) in arrays.items():
        group.create_array(  # Zarr's default compressor, then a checksum of each chunk
            name, shape=shape, chunks=chunks, dtype=dtype, fill_value=fill,
            compressors=(ZstdCodec(level=0), Crc32cCodec()),
        )  # fmt: skip
    if init is not None:
        init(group)
    seal = _fingerprint(group, {**dict(group.attrs), **attrs})
    group.attrs.update({**attrs, SEAL: seal})  # last, in one write: a store with attributes is complete
    return group


_ONLY = "symkin writes only to a new path, an empty folder or a store it wrote"


def _entries(path: str | Path) -> list[str] | None:
    """The names at the top of ``path`` (None: nothing there); a WorkspaceError for a file."""
    text = str(path)
    if "://" in text:  # a remote store: list it with fsspec, as zarr does
        import fsspec

        fs, root = fsspec.core.url_to_fs(text)
        if not fs.exists(root):
            return None
        if not fs.isdir(root):
            raise WorkspaceError(f"{path} is a file, not a symkin store: {_ONLY}")
        return [name.rstrip("/").rsplit("/", 1)[-1] for name in fs.ls(root, detail=False)]
    p = Path(text)
    if not p.exists():
        return None
    if not p.is_dir():
        raise WorkspaceError(f"{path} is a file, not a symkin store: {_ONLY}")
    return sorted(e.name for e in p.iterdir())


def _existing_store(path: str | Path) -> Any:
    """The symkin store at ``path``, or None when nothing is there (or an empty folder); any other
    content is refused (WorkspaceError) before anything is written."""
    entries = _entries(path)
    if not entries:
        return None
    try:
        group = zarr_module().open_group(str(path), mode="r+")
    except Exception as exc:  # noqa: BLE001 - zarr raises many kinds for a non-store
        held = ", ".join(entries[:3]) + (", ..." if len(entries) > 3 else "")
        why = (
            f"its zarr.json cannot be read: {_reason(exc)}" if "zarr.json" in entries else f"it holds {held}"
        )
        raise WorkspaceError(f"{path} is not a symkin store ({why}): {_ONLY}") from None
    attrs = dict(group.attrs)
    legacy = attrs.get("kind") in _KINDS and "symkin_version" in attrs  # written before the mark
    if MARK not in attrs and not legacy:
        raise WorkspaceError(f"{path} is a Zarr store symkin did not write (no {MARK!r} attribute): {_ONLY}")
    return group


def _check_replaceable(path: str | Path, group: Any) -> None:
    """Refuse to delete a store of ours that also holds something symkin did not write."""
    entries = _entries(path) or []
    with warnings.catch_warnings():  # zarr warns of the very entries looked for here
        warnings.simplefilter("ignore")
        members = set(group.keys())
    foreign = sorted(set(entries) - {"zarr.json"} - members)
    if foreign:
        shown = ", ".join(foreign[:3]) + (", ..." if len(foreign) > 3 else "")
        raise WorkspaceError(
            f"{path} holds files symkin did not write ({shown}): move them out or choose another path"
        )


def _reason(exc: BaseException) -> str:
    text = str(exc).strip()
    return f"{type(exc).__name__}: {text.splitlines()[0]}" if text else type(exc).__name__


def _chunk_rows(array: Any) -> list[tuple[slice, ...]]:
    """The selections of ``array`` one row of chunks (along axis 0) each: bounded memory."""
    if array.ndim == 0:
        return [()]
    c, n = array.chunks[0], array.shape[0]
    return [(slice(i, min(i + c, n)),) for i in range(0, n, c)]


def unreadable_chunks(array: Any) -> list[tuple[int, ...]]:
    """Chunk coordinates of ``array`` that cannot be read (damaged), reading it a row at a time."""
    bad = []
    for row in _chunk_rows(array):
        try:
            array[row]
        except Exception:  # noqa: BLE001 - codecs raise many kinds for damaged data
            i = row[0].start // array.chunks[0] if row else 0
            grid = tuple(-(-s // c) for s, c in zip(array.shape[1:], array.chunks[1:]))
            for rest in np.ndindex(grid):
                coords = (i, *rest) if row else rest
                try:
                    array.get_block_selection(coords)
                except Exception:  # noqa: BLE001
                    bad.append(coords)
    return bad


def chunk_name(array: Any, coords: tuple[int, ...]) -> str:
    """``array/c/i/j/k``: the chunk's key in the store."""
    return f"{array.path}/{array.metadata.encode_chunk_key(coords)}"


def read_array(array: Any, where: str | None) -> np.ndarray:
    """The whole of ``array``, or a WorkspaceError naming its first damaged chunk."""
    try:
        return np.asarray(array[...])
    except Exception as exc:  # noqa: BLE001 - codecs raise many kinds for damaged data
        bad = unreadable_chunks(array)
        if not bad:
            raise
        raise WorkspaceError(
            f"{where or 'the store'}: chunk {chunk_name(array, bad[0])} cannot be read ({_reason(exc)}); "
            "the store is damaged: run the same computation on it again to recompute its damaged "
            "blocks, or overwrite it"
        ) from None


def read_marks(array: Any) -> np.ndarray:
    """The ``done`` marks of a store; a damaged chunk of them is reset to its fill (not done) first,
    so its blocks are computed again."""
    try:
        return np.asarray(array[...])
    except Exception:  # noqa: BLE001 - codecs raise many kinds for damaged data
        for coords in unreadable_chunks(array):
            array[_chunk_selection(array, coords)] = array.fill_value
        return np.asarray(array[...])


def damaged_blocks(arrays: list[Any], blocks: tuple[int, ...]) -> set[int]:
    """Blocks (C-order indices over the chunk grid ``blocks`` of the arrays' leading axes) with an
    unreadable chunk in any of ``arrays``. Unmark them, then :func:`reset_blocks`, then compute them."""
    damaged: set[int] = set()
    for array in arrays:
        for coords in unreadable_chunks(array):
            damaged.add(int(np.ravel_multi_index(coords[: len(blocks)], blocks)))
    return damaged


def reset_blocks(arrays: list[Any], blocks: tuple[int, ...], indices: set[int]) -> None:
    """Write the fill value over blocks ``indices`` of ``arrays``: whole chunks, so zarr does not read
    (and fail on) the damaged data, and a block whose result is all fill is not left damaged."""
    for i in sorted(indices):
        lead = tuple(int(k) for k in np.unravel_index(i, blocks))
        for array in arrays:
            array[_chunk_selection(array, lead)] = array.fill_value


def resume_marks(arrays: list[Any], blocks: tuple[int, ...], marks: Any) -> tuple[np.ndarray, list[int]]:
    """The ``done`` marks of a resumed store (:func:`read_marks` of ``marks``, flat over the chunk
    grid ``blocks``) once the blocks of ``arrays`` with an unreadable chunk (:func:`damaged_blocks`)
    are unmarked, in ``marks`` too, and then reset (:func:`reset_blocks`): (the marks, the blocks
    that were marked done and are to be computed again)."""
    done = read_marks(marks).ravel()
    damaged = damaged_blocks(arrays, blocks) if done.any() else set()
    redo = sorted(i for i in damaged if done[i])
    if damaged:  # unmarked before the reset: an interruption cannot leave a reset block marked done
        done[redo] = 0
        marks[...] = done.reshape(blocks)
        reset_blocks(arrays, blocks, damaged)
    return done, redo


def _chunk_selection(array: Any, coords: tuple[int, ...]) -> tuple[slice, ...]:
    """The region of the chunk at ``coords`` (leading axes; the others whole)."""
    return tuple(slice(k * c, min((k + 1) * c, n)) for k, c, n in zip(coords, array.chunks, array.shape))
