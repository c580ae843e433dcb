"""The voxel grid of a reachability map, its orientation set and the counter-based random numbers.

Everything here is deterministic and independent of how the work is split: a voxel's random
stream, an orientation and a dataset sample are functions of (seed, global index) only, computed
with the SplitMix64 finaliser (Steele, Lea and Flood, Fast Splittable Pseudorandom Number
Generators, OOPSLA 2014), so a map is the same bit for bit with any number of workers or chunks.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.errors import RobotError, WorkspaceError
from symkin.model.kinematics import et_matrix
from symkin.model.orientation import quaternion_matrix

__all__ = [
    "VoxelGrid",
    "reach_ball",
    "so3_uniform",
    "counter_uniform",
    "voxel_seeds",
    "mix64",
]

GOLDEN = np.uint64(0x9E3779B97F4A7C15)
_M1, _M2 = np.uint64(0xBF58476D1CE4E5B9), np.uint64(0x94D049BB133111EB)
# stream tags keep the orientation, voxel and dataset streams of one seed apart
TAG_ORIENTATION, TAG_VOXEL, TAG_SAMPLE = 1, 2, 3


def mix64(z: np.ndarray) -> np.ndarray:
    """The SplitMix64 finaliser on uint64 arrays (wrapping arithmetic)."""
    z = np.asarray(z, dtype=np.uint64)
    z = (z ^ (z >> np.uint64(30))) * _M1
    z = (z ^ (z >> np.uint64(27))) * _M2
    return z ^ (z >> np.uint64(31))


def _key(seed: int, tag: int) -> np.uint64:
    """The uint64 key of stream ``tag`` of ``seed``."""
    s = np.array([int(seed) & 0xFFFFFFFFFFFFFFFF], dtype=np.uint64)
    return mix64(mix64(s) ^ np.uint64(tag))[0]


def counter_uniform(seed: int, tag: int, counters: np.ndarray) -> np.ndarray:
    """Uniform doubles in [0, 1): ``(mix64(key + (c + 1) * GOLDEN) >> 11) * 2**-53`` per counter c.

    Element c of the stream does not depend on which other elements are drawn.
    """
    c = np.asarray(counters, dtype=np.uint64)
    with np.errstate(over="ignore"):
        z = mix64(_key(seed, tag) + (c + np.uint64(1)) * GOLDEN)
    return (z >> np.uint64(11)).astype(np.float64) * 2.0**-53


def voxel_seeds(seed: int, flat_index: np.ndarray) -> np.ndarray:
    """The IK seed of each voxel (uint64), from the map seed and the voxel's global flat index."""
    c = np.asarray(flat_index, dtype=np.uint64)
    with np.errstate(over="ignore"):
        return mix64(_key(seed, TAG_VOXEL) + (c + np.uint64(1)) * GOLDEN)


def so3_uniform(count: int, seed: int = 0) -> np.ndarray:
    """``count`` rotation matrices (count, 3, 3) uniform on SO(3), the fixed orientation set of a map.

    Shoemake's subgroup algorithm (Uniform Random Rotations, Graphics Gems III, 1992): with
    u1, u2, u3 uniform in [0, 1) (:func:`counter_uniform`, stream 1 of ``seed``, counters
    3k .. 3k+2 for rotation k), the unit quaternion (w, x, y, z) =
    (sqrt(u1) cos 2 pi u3, sqrt(1-u1) sin 2 pi u2, sqrt(1-u1) cos 2 pi u2, sqrt(u1) sin 2 pi u3).
    """
    from symkin.core.sizes import count as checked
    from symkin.core.sizes import room

    count = checked(count, "orientations", error=WorkspaceError)
    room(8.0 * 12 * count, f"{count} orientations", WorkspaceError)
    u = counter_uniform(seed, TAG_ORIENTATION, np.arange(3 * count)).reshape(count, 3)
    a, b = np.sqrt(1.0 - u[:, 0]), np.sqrt(u[:, 0])
    x, y = a * np.sin(2 * np.pi * u[:, 1]), a * np.cos(2 * np.pi * u[:, 1])
    z, w = b * np.sin(2 * np.pi * u[:, 2]), b * np.cos(2 * np.pi * u[:, 2])
    return quaternion_matrix(np.stack((w, x, y, z), -1))


def reach_ball(robot: Any) -> tuple[np.ndarray, float]:
    """(centre (3,), radius) of a ball in the base frame that holds every reachable tool position.

    The centre is the origin of the first joint (in chain order) moved along that joint's axis by
    the part of the following link that lies on the axis (a revolute joint leaves that point
    fixed); the radius is the sum of the remaining link lengths (the norm of each run of constant
    transforms between joints) plus the largest |travel| of every prismatic joint.
    """
    ets = robot.ets
    qlim = np.asarray(robot.qlim, dtype=float)
    runs: list[np.ndarray] = [np.eye(4)]
    joints = []
    for e in ets:
        if e.is_joint:
            joints.append(e)
            runs.append(np.eye(4))
        else:
            runs[-1] = runs[-1] @ et_matrix(e.axis, e.const.value)
    if not joints:
        raise RobotError(f"robot {robot.name!r} has no joints: it has no workspace to map")
    T0, first = runs[0], joints[0]
    centre = T0[:3, 3].copy()
    radius = 0.0
    for i, (joint, run) in enumerate(zip(joints, runs[1:])):
        t = run[:3, 3]
        if i == 0 and first.is_revolute:
            along = np.zeros(3)
            along[first.axis.index] = t[first.axis.index]
            centre = centre + T0[:3, :3] @ along
            t = t - along
        radius += float(np.linalg.norm(t))
        if joint.is_prismatic:
            travel = float(np.abs(qlim[:, joint.joint]).max())
            if not math.isfinite(travel):
                raise RobotError(
                    f"prismatic joint q{joint.joint} of {robot.name!r} has unbounded travel: "
                    "give radius= (or bounds=) for its workspace map"
                )
            radius += travel
    return centre, radius


@dataclass(frozen=True)
class VoxelGrid:
    """A cubic grid of voxel centres ``centre + resolution * (i - half)`` in the base frame.

    The full grid has ``2 * half + 1`` voxels per axis around the ball (``half = ceil(radius /
    resolution)``); ``lo``/``shape`` select the sub-box kept by ``bounds``. ``chunk`` is the edge
    of the cubic blocks that are stored and computed together. Voxels are identified by their flat
    index in the full grid, which fixes their random streams whatever the bounds or chunks.
    """

    centre: tuple[float, float, float]
    radius: float
    resolution: float
    half: int
    lo: tuple[int, int, int]
    shape: tuple[int, int, int]
    chunk: int

    @classmethod
    def of(
        cls,
        centre: np.ndarray,
        radius: float,
        resolution: float,
        bounds: Any = None,
        chunk: int | None = None,
    ) -> VoxelGrid:
        resolution = float(resolution)
        if not (math.isfinite(resolution) and resolution > 0):
            raise WorkspaceError(f"resolution must be a positive number of metres, got {resolution!r}")
        if not (math.isfinite(radius) and radius > 0):
            raise WorkspaceError(f"the workspace radius must be a positive number, got {radius!r}")
        half = math.ceil(radius / resolution - 1e-9)
        if (2 * half + 1) ** 3 > 2**40:
            raise WorkspaceError(f"resolution {resolution} m gives too many voxels for radius {radius:.3g} m")
        lo, hi = [0, 0, 0], [2 * half + 1] * 3
        if bounds is not None:
            b = np.asarray(bounds, dtype=float)
            if b.shape != (3, 2) or np.isnan(b).any() or (b[:, 0] > b[:, 1]).any():
                raise WorkspaceError(
                    f"bounds must be ((xmin, xmax), (ymin, ymax), (zmin, zmax)) in metres, got {bounds!r}"
                )
            for k in range(3):
                kmin = math.ceil((b[k, 0] - centre[k]) / resolution + half - 1e-9)
                kmax = math.floor((b[k, 1] - centre[k]) / resolution + half + 1e-9)
                lo[k], hi[k] = max(lo[k], kmin), min(hi[k], kmax + 1)
                if hi[k] <= lo[k]:
                    raise WorkspaceError(f"bounds {bounds!r} hold no voxel centre of the workspace grid")
        shape = tuple(h - lo_ for lo_, h in zip(lo, hi))
        if chunk is None:  # the largest block edge in 16..4 that still gives >= 64 blocks
            chunk = next((c for c in range(16, 3, -1) if math.prod(-(-s // c) for s in shape) >= 64), 4)
        from symkin.core.sizes import count

        # a block edge beyond the grid is the grid (Zarr fills a whole chunk in memory to write part)
        chunk = min(count(chunk, "chunk (voxels per block edge)", error=WorkspaceError), max(shape))
        return cls(tuple(float(c) for c in centre), float(radius), resolution, half, tuple(lo), shape,
                   int(chunk))  # type: ignore[arg-type]  # fmt: skip

    @property
    def chunks(self) -> tuple[int, int, int]:
        """Number of blocks per axis."""
        return tuple(-(-s // self.chunk) for s in self.shape)  # type: ignore[return-value]

    @property
    def n_chunks(self) -> int:
        return math.prod(self.chunks)

    def block(self, index: int) -> tuple[slice, slice, slice]:
        """The (local) voxel slices of block ``index`` (C order over :attr:`chunks`)."""
        ijk = np.unravel_index(int(index), self.chunks)
        return tuple(
            slice(int(i) * self.chunk, min((int(i) + 1) * self.chunk, s)) for i, s in zip(ijk, self.shape)
        )  # type: ignore[return-value]

    def axes(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Voxel-centre coordinates along x, y and z (local grid), metres."""
        return tuple(
            self.centre[k] + self.resolution * (np.arange(self.lo[k], self.lo[k] + self.shape[k]) - self.half)
            for k in range(3)
        )  # type: ignore[return-value]

    def centers(self, sl: tuple[slice, slice, slice] | None = None) -> np.ndarray:
        """Voxel centres (X, Y, Z, 3) of the local slices ``sl`` (default: all)."""
        ax = self.axes()
        if sl is not None:
            ax = tuple(a[s] for a, s in zip(ax, sl))
        return np.stack(np.meshgrid(*ax, indexing="ij"), axis=-1)

    def flat_index(self, sl: tuple[slice, slice, slice]) -> np.ndarray:
        """Global flat indices (X, Y, Z) of the voxels of the local slices ``sl``."""
        side = 2 * self.half + 1
        idx = [np.arange(s.start, s.stop) + lo for s, lo in zip(sl, self.lo)]
        I, J, K = np.meshgrid(*idx, indexing="ij")
        return (I.astype(np.int64) * side + J) * side + K

    def inside(self, centers: np.ndarray) -> np.ndarray:
        """Which voxel centres (..., 3) lie in the ball (the others are unreachable)."""
        return np.linalg.norm(centers - np.asarray(self.centre), axis=-1) <= self.radius
