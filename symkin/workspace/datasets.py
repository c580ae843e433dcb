"""``symkin.workspace.samples``: (q, pose) datasets for learning, computed on Dask into Zarr.

Sample i has joint values q_i uniform in the joint limits (infinite limits replaced by +-pi for
revolute and +-1 m for prismatic joints) drawn from counters of the seed's sample stream, and the
tool pose fkine(q_i) in the base frame. Samples are computed in blocks of ``chunk`` (one Dask task
and one Zarr chunk each); asking an existing store for more samples appends the missing ones, so
the first N samples of a dataset never change.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.sizes import count, room, stored
from symkin.errors import WorkspaceError
from symkin.runtime.ik import revolute_mask, sample_range
from symkin.workspace.blocks import SampleSpec, sample_block
from symkin.workspace.maps import kinematics_of, robot_of
from symkin.workspace.run import client_for, require_scale, run_blocks
from symkin.workspace.store import (
    open_store,
    open_stored,
    read_array,
    resume_marks,
    robot_attrs,
    zarr_module,
)

__all__ = ["Dataset", "samples", "open_dataset"]


@dataclass(frozen=True, eq=False)
class Dataset:
    """A (q, pose) dataset in a Zarr store.

    Attributes:
        q: lazy Zarr array (N, n) of joint values (``q[...]`` or ``np.asarray(q)`` reads it).
        pose: lazy Zarr array (N, 4, 4) of tool poses fkine(q) in the base frame.
        attrs: the store's attributes (robot, settings, seed, symkin_version).
        path: the store, or None when it was kept in memory.
        complete: every block is written.
        stats: for a run, ``blocks``, ``computed``, ``skipped``, ``damaged`` (written blocks computed
            again because a chunk of theirs could not be read), ``seconds``, ``task_seconds``.
    """

    q: Any
    pose: Any
    attrs: dict[str, Any]
    path: str | None
    complete: bool
    stats: dict[str, float] | None = None

    def __len__(self) -> int:
        return int(self.q.shape[0])


def samples(
    robot_or_kin: Any,
    n: int,
    *,
    output: str | Path | None = None,
    seed: int = 0,
    chunk: int = 65536,
    backend: str = "c",
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool | None = None,
    overwrite: bool = False,
    on_block: Callable[[int, dict[str, Any]], None] | None = None,
) -> Dataset:
    """A dataset of ``n`` (q, pose) samples of a robot, computed on Dask (see the module docstring).

    ``output`` is the Zarr store (None: in memory); an existing store of the same robot and seed
    resumes its unwritten blocks (keeping its own ``chunk``) and grows when ``n`` is larger
    (appending). ``scheduler``,
    ``workers``, ``progress``, ``overwrite`` and ``on_block`` are as for
    :func:`symkin.workspace.reachability`. The samples do not depend on workers or chunk size.
    """
    require_scale(scheduler)
    n = count(n, "n (the number of samples)", error=WorkspaceError)
    chunk = count(chunk, "chunk (samples per block)", error=WorkspaceError)
    if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)):
        raise WorkspaceError(f"seed must be an integer, got {seed!r}")
    # a block larger than the dataset is the dataset (Zarr fills a whole chunk in memory to write part)
    chunk, seed = _stored_chunk(output, overwrite) or min(chunk, n), int(seed)
    robot = robot_of(robot_or_kin)
    _check_size(n, chunk, robot.n, output)  # before compiling
    kin = kinematics_of(robot, backend)
    sample = sample_range(np.asarray(kin.qlim, dtype=float), revolute_mask(kin))
    blocks = -(-n // chunk)
    from symkin.core.version import __version__

    attrs = {
        "kind": "dataset",
        "robot": robot_attrs(kin.robot),
        "settings": {"kind": "dataset", "n": n, "sample_range": sample.tolist(), "backend": kin.backend},
        "seed": seed,
        "symkin_version": __version__,
    }  # fmt: skip
    d = kin.n
    arrays = {
        "q": ((n, d), (chunk, d), "f8", np.nan),
        "pose": ((n, 4, 4), (chunk, 4, 4), "f8", np.nan),
        "done": ((blocks,), (4096,), "i8", 0),
    }
    group = open_store(output, attrs, arrays, overwrite=overwrite, grow="n")
    spec = SampleSpec(n, chunk, seed, sample)
    rows = np.minimum(chunk, n - chunk * np.arange(blocks))
    q_arr, pose_arr, done_arr = group["q"], group["pose"], group["done"]
    done, redo = resume_marks([q_arr, pose_arr], (blocks,), done_arr)
    todo = [i for i in range(blocks) if done[i] != rows[i]]

    def write(i: int, result: dict[str, Any]) -> None:
        sl = slice(i * chunk, i * chunk + len(result["q"]))
        q_arr[sl] = result["q"]
        pose_arr[sl] = result["pose"]
        done_arr[i] = len(result["q"])  # after the data: marks it complete

    stats: dict[str, float] = {"blocks": blocks, "computed": len(todo), "skipped": blocks - len(todo),
                               "damaged": len(redo)}  # fmt: skip
    if todo:
        with client_for(scheduler, workers) as client:
            stats.update(run_blocks(sample_block, (kin, spec), todo, write, client, total=blocks,
                                    progress=progress, on_block=on_block, desc="samples"))  # fmt: skip
    return _load(group, None if output is None else str(output), stats)


def _check_size(n: int, chunk: int, d: int, output: Any) -> None:
    """WorkspaceError before any work when the dataset would not fit: its q and pose in memory
    (``output`` None) or on the store's disk, a block of ``chunk`` samples (three copies: computed,
    sent, written) or the marks of its blocks in memory."""
    sample = 8.0 * (d + 16)
    blocks = -(-n // chunk)
    stored(output, n * sample, f"a dataset of {n} samples", WorkspaceError)
    room(3 * chunk * sample + 64.0 * blocks, f"blocks of {chunk} samples", WorkspaceError)


def _stored_chunk(output: Any, overwrite: bool) -> int | None:
    """The block size of the existing store at ``output`` (a resumed store keeps its own)."""
    if output is None or overwrite:
        return None
    try:
        return int(zarr_module().open_group(str(output), mode="r")["q"].chunks[0])
    except Exception:  # noqa: BLE001 - no store there (open_store reports other problems)
        return None


def _load(group: Any, path: str | None, stats: dict[str, float] | None) -> Dataset:
    n, chunk = group["q"].shape[0], group["q"].chunks[0]
    rows = np.minimum(chunk, n - chunk * np.arange(group["done"].shape[0]))
    complete = bool((read_array(group["done"], path) == rows).all())
    return Dataset(group["q"], group["pose"], dict(group.attrs), path, complete, stats)


def open_dataset(path: str | Path) -> Dataset:
    """The (q, pose) dataset stored at ``path``."""
    return _load(open_stored(path, "dataset"), str(path), None)
