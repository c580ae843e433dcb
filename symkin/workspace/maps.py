"""``symkin.workspace.reachability``: reachability and manipulability maps of the workspace.

The reachable ball of the robot (:func:`symkin.workspace.grid.reach_ball`) is cut into cubic
voxels of edge ``resolution``; at each voxel centre the tool is asked to take each of a fixed set
of K orientations (uniform on SO(3) from the seed, :func:`symkin.workspace.grid.so3_uniform`, or
given). Batched IK solves the K targets of a voxel; the map stores per voxel the reachability index
(fraction of orientations solved), the best manipulability among the solutions and, optionally,
one solution per orientation. Blocks of voxels are Dask tasks; results go to a Zarr store that a
stopped run resumes from.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import WorkspaceError
from symkin.workspace.blocks import ReachSpec, reach_block
from symkin.workspace.grid import VoxelGrid, reach_ball, so3_uniform
from symkin.workspace.run import client_for, require_scale, run_blocks
from symkin.workspace.store import (
    open_store,
    open_stored,
    read_array,
    resume_marks,
    robot_attrs,
    unreadable_chunks,
)

__all__ = ["ReachMap", "reachability", "open_map", "kinematics_of", "MAP_IK_DEFAULTS"]

MAP_IK_DEFAULTS: dict[str, Any] = {"ilimit": 30, "slimit": 10, "tol": 1e-6}
_AXES = {"all": (0, 1, 2, 3, 4, 5), "trans": (0, 1, 2), "rot": (3, 4, 5)}
_IK_KEYS = ("method", "damping", "lam", "pinv", "ilimit", "slimit", "tol", "tol_on", "joint_limits", "we")


@dataclass(frozen=True, eq=False)
class ReachMap:
    """A reachability map (the arrays of its Zarr store, in the robot's base frame).

    Attributes:
        reach: (X, Y, Z) fraction of the orientations solved at each voxel centre, in [0, 1].
        manipulability: (X, Y, Z) best manipulability (eq 52) among the solutions, NaN if none.
        centers: (X, Y, Z, 3) voxel centres, metres.
        rotations: (K, 3, 3) the orientation set.
        solutions: None, or the lazy Zarr array (X, Y, Z, K, n) of one solution per orientation
            (NaN where unsolved); ``solutions[...]`` reads it.
        attrs: the store's attributes (robot, settings, seed, symkin_version).
        path: the store, or None when it was kept in memory.
        complete: every block is written (False for a run stopped early, read by :func:`open_map`).
        stats: for a run, ``blocks``, ``computed`` and ``skipped`` (already written) blocks,
            ``damaged`` (written blocks computed again because a chunk of theirs could not be read),
            ``seconds`` (wall), ``task_seconds`` (sum over tasks), ``problems`` (IK targets).
    """

    reach: np.ndarray
    manipulability: np.ndarray
    centers: np.ndarray
    rotations: np.ndarray
    solutions: Any
    attrs: dict[str, Any]
    path: str | None
    complete: bool
    stats: dict[str, float] | None = None

    @property
    def resolution(self) -> float:
        return float(self.attrs["settings"]["resolution"])

    def plot(self, path: str | Path, axis: str = "z", at: float | None = None) -> Path:
        """Write a PNG of the slice ``axis = at`` (default: through the ball's centre); see
        :func:`symkin.workspace.plot.plot_slice`."""
        from symkin.workspace.plot import plot_slice

        return plot_slice(self, path, axis=axis, at=at)


def kinematics_of(robot_or_kin: Any, backend: str = "c") -> Any:
    """Compiled kinematics from a Kinematics, a Robot or a robot spec (name, ETS text, file)."""
    from symkin.runtime.kinematics import Kinematics

    if isinstance(robot_or_kin, Kinematics):
        return robot_or_kin
    from symkin.runtime.load import compile as compile_robot

    return compile_robot(robot_or_kin, backend=backend)


def robot_of(robot_or_kin: Any) -> Any:
    """The Robot of a Kinematics, a Robot or a robot spec (name, ETS text, file), without compiling:
    sizes are checked on it before any work."""
    from symkin.model.tree import robot_of as chain_of
    from symkin.runtime.kinematics import Kinematics

    if isinstance(robot_or_kin, Kinematics):
        return robot_or_kin.robot
    if isinstance(robot_or_kin, str):
        from symkin.model.resolve import resolve_robot

        return resolve_robot(robot_or_kin)
    try:
        robot = chain_of(robot_or_kin)  # a Robot itself; None for a Tree
    except TypeError:  # not a model (an ETS)
        robot = None
    return robot if robot is not None else kinematics_of(robot_or_kin).robot


def _rows(axes: str | Sequence[int]) -> tuple[int, ...]:
    if isinstance(axes, str):
        if axes not in _AXES:
            raise WorkspaceError(f"axes must be one of {sorted(_AXES)} or row indices 0-5, not {axes!r}")
        return _AXES[axes]
    rows = tuple(int(r) for r in axes)
    if not rows or len(set(rows)) != len(rows) or not all(0 <= r < 6 for r in rows):
        raise WorkspaceError(f"axes rows must be distinct indices in 0..5, got {axes!r}")
    return rows


def _hashable(x: Any) -> Any:
    if isinstance(x, (list, tuple, np.ndarray)):
        return tuple(_hashable(v) for v in np.asarray(x).tolist()) if np.ndim(x) else np.asarray(x).item()
    return x


def ik_settings(kin: Any, ik_options: Mapping[str, Any] | None) -> tuple[tuple[str, Any], ...]:
    """The map's IK options (``MAP_IK_DEFAULTS`` updated by ``ik_options``), validated."""
    from symkin.runtime.ik import IKOptions

    options = dict(MAP_IK_DEFAULTS)
    for key, value in dict(ik_options or {}).items():
        if key not in _IK_KEYS:
            raise WorkspaceError(
                f"ik_options: unknown or fixed option {key!r}; choose from {', '.join(_IK_KEYS)}"
            )
        options[key] = _hashable(value)
    IKOptions.of(kin, **options)  # raises ValueError for bad values
    return tuple(sorted(options.items()))


def _rotations(orientations: int | Any, seed: int) -> tuple[np.ndarray, Any]:
    """(K, 3, 3) rotations and their description for the settings."""
    if isinstance(orientations, (int, np.integer)) and not isinstance(orientations, bool):
        return so3_uniform(int(orientations), seed), int(orientations)
    R = np.asarray(orientations, dtype=float)
    if R.ndim != 3 or R.shape[1:] != (3, 3) or len(R) == 0:
        raise WorkspaceError(
            f"orientations must be a count or rotation matrices (K, 3, 3), got shape {R.shape}"
        )
    dev = np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max()
    if not np.isfinite(R).all() or dev > 1e-6 or (np.linalg.det(R) <= 0).any():
        raise WorkspaceError("orientations must be proper rotation matrices (R^T R = I, det R = 1)")
    digest = hashlib.sha256(np.ascontiguousarray(R).tobytes()).hexdigest()[:16]
    return R, {"given": len(R), "sha256": digest}


def reachability(
    robot_or_kin: Any,
    resolution: float = 0.05,
    orientations: int | Any = 50,
    *,
    output: str | Path | None = None,
    seed: int = 0,
    solutions: bool = False,
    axes: str | Sequence[int] = "all",
    bounds: Any = None,
    radius: float | None = None,
    chunk: int | None = None,
    backend: str = "c",
    ik_options: Mapping[str, Any] | None = None,
    scheduler: Any = None,
    workers: int | None = None,
    progress: bool | None = None,
    overwrite: bool = False,
    on_block: Callable[[int, dict[str, Any]], None] | None = None,
    collision: Any = None,
) -> ReachMap:
    """Reachability and manipulability map of a robot's workspace, computed on Dask.

    Args:
        robot_or_kin: compiled kinematics, a Robot, or a robot name / ETS text / file.
        resolution: voxel edge, metres. Voxel centres are ``centre + resolution * i`` (integer
            vectors i) over the cube around the ball of ``radius`` (both from the link lengths
            unless given, :func:`symkin.workspace.grid.reach_ball`); centres outside the ball are
            unreachable and get reach 0 without solving.
        orientations: K, the number of orientations per voxel (uniform on SO(3) from ``seed``),
            or the rotation matrices (K, 3, 3) themselves.
        output: the Zarr store (a folder, or a URL zarr opens); None keeps it in memory. An existing
            store of the same map is resumed: its written blocks are kept (those with a damaged,
            unreadable chunk are computed again). Only a new path, an empty folder or a store
            symkin wrote is written to; anything else is refused (WorkspaceError).
        seed: fixes the orientations and every voxel's IK restarts (with the voxel's grid index).
        solutions: also store one solution per orientation (X, Y, Z, K, n) as ``solutions``.
        axes: rows of J0 in the manipulability: ``"all"``, ``"trans"``, ``"rot"`` or indices 0-5
            (e.g. (0, 1, 5) for a planar arm in x-y).
        bounds: ((xmin, xmax), (ymin, ymax), (zmin, zmax)) restricts the grid to a box, metres.
        chunk: voxels per block edge (a block is one task and one Zarr chunk); default: the
            largest edge in 16..4 giving at least 64 blocks. A resumed store keeps its own.
        backend: backend of the kinematics when compiling a robot.
        ik_options: options of ``kin.ik`` (``method``, ``damping``, ``lam``, ``ilimit``,
            ``slimit``, ``tol``, ``we``, ``joint_limits``...); default ``MAP_IK_DEFAULTS``: 10
            searches of 30 iterations, ``|e| < 1e-6``.
        scheduler: where the blocks run (see :mod:`symkin.workspace.run`): None starts a local
            cluster of ``workers`` processes, ``"tcp://host:8786"`` uses an existing cluster,
            ``"synchronous"`` runs here without Dask.
        workers: processes of the local cluster (default: one per core).
        progress: progress bar on stderr (default: when stderr is a terminal).
        overwrite: replace an existing store of symkin's instead of resuming it.
        on_block: called as ``on_block(index, result)`` after each block is written.
        collision: None; ``True`` (only solutions free of self-collision count) or obstacles (an
            Environment, or spheres, capsules and boxes in the base frame: only solutions free
            of self-collision and of them count, ``kin.ik(..., collision=env)``). The robot needs
            collision geometry; the obstacles are part of the map's settings.

    Returns:
        ReachMap. The result does not depend on the scheduler, workers or chunk size.
    """
    require_scale(scheduler)
    if not isinstance(seed, (int, np.integer)) or isinstance(seed, bool):
        raise WorkspaceError(f"seed must be an integer, got {seed!r}")
    seed = int(seed)
    rotations, described = _rotations(orientations, seed)  # sizes are checked before compiling
    robot = robot_of(robot_or_kin)
    centre, ball = reach_ball(robot)
    if radius is not None:
        if not (isinstance(radius, (int, float)) and math.isfinite(radius) and radius > 0):
            raise WorkspaceError(f"radius must be a positive number of metres, got {radius!r}")
        ball = float(radius)
    rows = _rows(axes)
    grid = VoxelGrid.of(centre, ball, resolution, bounds, chunk)
    _check_size(grid, len(rotations), robot.n, bool(solutions), output, ik_options)
    kin = kinematics_of(robot, backend)
    ik = ik_settings(kin, ik_options)
    env = _collision_env(kin, collision)
    settings = {
        "kind": "reachability",
        "resolution": grid.resolution,
        "orientations": described,
        "centre": list(grid.centre),
        "radius": grid.radius,
        "bounds": None if bounds is None else np.asarray(bounds, dtype=float).tolist(),
        "axes_rows": list(rows),
        "ik": dict(ik),
        "solutions": bool(solutions),
        "backend": kin.backend,
    }
    if env is not None:  # only then: the settings (and so resumable stores) of other maps are unchanged
        settings["collision"] = {k: v.tolist() for k, v in env.arrays().items()}
    from symkin.core.version import __version__

    attrs = {"kind": "reachability", "robot": robot_attrs(kin.robot), "settings": settings, "seed": seed,
             "symkin_version": __version__}  # fmt: skip
    group = _open_map_store(output, attrs, grid, rotations, kin.n, bool(solutions), overwrite)
    grid = VoxelGrid(grid.centre, grid.radius, grid.resolution, grid.half, grid.lo, grid.shape,
                     int(group["reach"].chunks[0]))  # fmt: skip
    spec = ReachSpec(grid, rotations, seed, rows, ik, bool(solutions), env)
    arrays = {name: group[name] for name in ("reach", "manipulability")}
    if solutions:
        arrays["solutions"] = group["solutions"]
    done_array = group["done"]
    done, redo = resume_marks(list(arrays.values()), grid.chunks, done_array)
    done = done.astype(bool)
    todo = [i for i in range(grid.n_chunks) if not done[i]]

    written: list[int] = []  # blocks written whose done marks are not yet stored
    flushed = [time.monotonic()]

    def flush() -> None:
        if written:
            mask = done.copy().reshape(grid.chunks)
            mask.ravel()[written] = True
            done_array[...] = mask
            done[written] = True
            written.clear()
        flushed[0] = time.monotonic()

    def write(i: int, result: dict[str, Any]) -> None:
        sl = grid.block(i)
        for name, array in arrays.items():
            data = result[name]
            if name == "reach" and not data.any() or name != "reach" and np.isnan(data).all():
                continue  # all fill value (a block outside the ball): nothing to store
            array[sl] = data
        written.append(i)  # marked done after the data, at most once a second
        if time.monotonic() - flushed[0] > 1.0:
            flush()

    stats: dict[str, float] = {
        "blocks": grid.n_chunks,
        "computed": len(todo),
        "skipped": grid.n_chunks - len(todo),
        "damaged": len(redo),
    }
    if todo:
        with client_for(scheduler, workers) as client:
            try:
                stats.update(run_blocks(reach_block, (kin, spec), todo, write, client, total=grid.n_chunks,
                                        progress=progress, on_block=on_block, desc="reach"))  # fmt: skip
            finally:
                flush()
    return _load_map(group, None if output is None else str(output), stats)


def _check_size(
    grid: VoxelGrid, K: int, n: int, solutions: bool, output: Any, ik_options: Mapping[str, Any] | None
) -> None:
    """WorkspaceError before any work when the map would not fit: its reach, manipulability and
    voxel centres (read into memory), its solutions (``output`` None: in memory, else on the
    store's disk), or a block's K IK problems per voxel (a block of ``grid.chunk`` voxels a side);
    ParameterError for IK search or iteration counts beyond the C solver's."""
    from symkin.core.sizes import count, room, stored
    from symkin.runtime.ik_problem import MAX_ITERATIONS

    for key in ("slimit", "ilimit"):
        if key in dict(ik_options or {}):
            count(dict(ik_options or {})[key], key, maximum=MAX_ITERATIONS)

    voxels = math.prod(grid.shape)
    room(40.0 * voxels, f"a map of {voxels} voxels", WorkspaceError)
    if solutions:
        stored(output, 8.0 * voxels * K * n, f"the solutions of {voxels} voxels x {K} orientations",
               WorkspaceError)  # fmt: skip
    block = grid.chunk**3
    room(8.0 * block * K * (2 * n + 16), f"blocks of {block} voxels x {K} orientations", WorkspaceError)


def _collision_env(kin: Any, collision: Any) -> Any:
    """The obstacles of ``collision`` (an Environment; empty for ``True``), or None when off."""
    if collision is None or collision is False:
        return None
    from symkin.geometry.pairs import as_environment, layout_of
    from symkin.model.geometry import Environment

    layout_of(kin.robot)  # GeometryError now, not in a worker, when the robot has no geometry
    return Environment() if collision is True else as_environment(collision)


def _open_map_store(
    output: Any, attrs: dict, grid: VoxelGrid, rotations: np.ndarray, n: int, solutions: bool, overwrite: bool
) -> Any:
    c = grid.chunk
    arrays = {
        "reach": (grid.shape, (c, c, c), "f8", 0.0),
        "manipulability": (grid.shape, (c, c, c), "f8", np.nan),
        "centers": ((*grid.shape, 3), (c, c, c, 3), "f8", np.nan),
        "rotations": (rotations.shape, rotations.shape, "f8", np.nan),
        "done": (grid.chunks, grid.chunks, "bool", False),
    }
    if solutions:
        K = len(rotations)
        arrays["solutions"] = ((*grid.shape, K, n), (c, c, c, K, n), "f8", np.nan)

    def init(group: Any) -> None:
        group["rotations"][...] = rotations
        centers = group["centers"]
        for i in range(0, grid.shape[0], grid.chunk):  # slabs of blocks: bounded memory
            sl = (slice(i, min(i + grid.chunk, grid.shape[0])), slice(None), slice(None))
            centers[sl] = grid.centers(sl)

    group = open_store(output, attrs, arrays, overwrite=overwrite, init=init)
    if output is not None and (unreadable_chunks(group["centers"]) or unreadable_chunks(group["rotations"])):
        init(group)  # a resumed store whose grid arrays are damaged: write them again
    return group


def _load_map(group: Any, path: str | None, stats: dict[str, float] | None) -> ReachMap:
    attrs = dict(group.attrs)
    return ReachMap(
        reach=read_array(group["reach"], path),
        manipulability=read_array(group["manipulability"], path),
        centers=read_array(group["centers"], path),
        rotations=read_array(group["rotations"], path),
        solutions=group.get("solutions"),
        attrs=attrs,
        path=path,
        complete=bool(read_array(group["done"], path).all()),
        stats=stats,
    )


def open_map(path: str | Path) -> ReachMap:
    """The reachability map stored at ``path`` (complete or not; see ``ReachMap.complete``).

    A damaged chunk is a WorkspaceError naming it (``reachability`` with the same settings on the
    store recomputes its blocks)."""
    return _load_map(open_stored(path, "reachability"), str(path), None)
