"""The work of one block: the part of a map or dataset that one Dask task computes.

These functions run on the workers. They take the compiled kinematics (which pickle to robot +
backend and are rebuilt from the worker's compile cache), a frozen spec and a block index, and
return plain NumPy arrays; the client writes them to the store. A block's result depends only on
the spec and the block's voxels or samples, never on the worker or on the other blocks.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.model.differential import manipulability_of
from symkin.workspace.grid import TAG_SAMPLE, VoxelGrid, counter_uniform, voxel_seeds

__all__ = ["ReachSpec", "SampleSpec", "reach_block", "sample_block"]


@dataclass(frozen=True, eq=False)
class ReachSpec:
    """What a reachability task needs besides the kinematics.

    Attributes:
        grid: the voxel grid and its blocks.
        rotations: (K, 3, 3) the orientation set, the same for every voxel.
        seed: the map seed (voxel v's IK restarts use ``voxel_seeds(seed, v)``).
        rows: rows of J0 in the manipulability (0-2 translation, 3-5 rotation).
        ik: keyword options of ``kin.ik`` as (name, value) pairs.
        solutions: also return one solution per orientation.
        collision: None, or the obstacles (an Environment) whose collision-free solutions alone
            count (self-collisions too: ``kin.ik(..., collision=env)``).
    """

    grid: VoxelGrid
    rotations: np.ndarray
    seed: int
    rows: tuple[int, ...]
    ik: tuple[tuple[str, Any], ...]
    solutions: bool = False
    collision: Any = None


def reach_block(kin: Any, spec: ReachSpec, index: int) -> dict[str, Any]:
    """Reachability of the voxels of block ``index``.

    For each voxel centre p inside the ball, IK is solved for the K targets (R_k, p) in one batch
    seeded by the voxel; ``reach`` is the fraction solved and ``manipulability`` the largest
    Yoshikawa manipulability sqrt(det(J J^T)) of the chosen rows of J0 over the solutions
    (Haviland and Corke, Manipulator Differential Kinematics, Part 1, IEEE RAM 2023, eq 52), NaN
    when none. Voxels outside the ball are unreachable without solving. Returns ``reach``,
    ``manipulability`` (X, Y, Z), ``solutions`` (X, Y, Z, K, n) NaN where unsolved (if asked),
    ``problems`` (IK targets solved for) and ``seconds`` (time spent).
    """
    t0 = time.perf_counter()
    sl = spec.grid.block(index)
    centers = spec.grid.centers(sl)
    shape = centers.shape[:3]
    P = centers.reshape(-1, 3)
    inside = np.flatnonzero(spec.grid.inside(centers).ravel())
    seeds = voxel_seeds(spec.seed, spec.grid.flat_index(sl)).ravel()
    K, n = len(spec.rotations), kin.n
    reach = np.zeros(len(P))
    manip = np.full(len(P), np.nan)
    sol = np.full((len(P), K, n), np.nan) if spec.solutions else None
    T = np.zeros((K, 4, 4))
    T[:, :3, :3] = spec.rotations
    T[:, 3, 3] = 1.0
    options = dict(spec.ik)
    if spec.collision is not None:
        options["collision"] = spec.collision
    found, owner = [], []
    for v in inside.tolist():
        T[:, :3, 3] = P[v]
        res = kin.ik(T, seed=int(seeds[v]), **options)
        ok = np.asarray(res.success, dtype=bool)
        count = int(ok.sum())
        reach[v] = count / K
        if count:
            found.append(res.q[ok])
            owner.append(np.full(count, v))
            if sol is not None:
                sol[v, ok] = res.q[ok]
    if found:
        np.fmax.at(manip, np.concatenate(owner), _manipulability(kin, np.concatenate(found), spec.rows))
    out: dict[str, Any] = {
        "reach": reach.reshape(shape),
        "manipulability": manip.reshape(shape),
        "problems": len(inside) * K,
    }
    if sol is not None:
        out["solutions"] = sol.reshape((*shape, K, n))
    out["seconds"] = time.perf_counter() - t0
    return out


_NAMED_ROWS = {(0, 1, 2, 3, 4, 5): "all", (0, 1, 2): "trans", (3, 4, 5): "rot"}


def _manipulability(kin: Any, Q: np.ndarray, rows: tuple[int, ...]) -> np.ndarray:
    """Manipulability (eq 52) of the rows of J0 at each q of Q (M, n) -> (M,): the compiled
    ``kin.manipulability`` for the named row sets, else from ``kin.jacob0``."""
    axes = _NAMED_ROWS.get(tuple(rows))
    if axes is not None:
        return np.asarray(kin.manipulability(Q, axes=axes), dtype=float).reshape(len(Q))
    J = np.asarray(kin.jacob0(Q)).reshape(len(Q), 6, kin.n)
    return manipulability_of(J[:, list(rows)])


@dataclass(frozen=True, eq=False)
class SampleSpec:
    """What a dataset task needs: ``n`` samples in blocks of ``chunk``, joint values drawn
    uniformly from ``sample`` (2, n) (the joint limits, infinite ones replaced by +-pi or +-1 m)."""

    n: int
    chunk: int
    seed: int
    sample: np.ndarray


def sample_block(kin: Any, spec: SampleSpec, index: int) -> dict[str, Any]:
    """Samples ``index * chunk`` .. of a (q, pose) dataset: q (m, n) uniform in the joint range
    (element (i, j) uses counter ``i * n + j`` of the seed's sample stream) and pose = fkine(q)
    (m, 4, 4), the tool pose in the base frame."""
    t0 = time.perf_counter()
    start = int(index) * spec.chunk
    stop = min(start + spec.chunk, spec.n)
    n = kin.n
    counters = np.arange(start * n, stop * n, dtype=np.uint64)
    u = counter_uniform(spec.seed, TAG_SAMPLE, counters).reshape(stop - start, n)
    lo, hi = spec.sample
    q = lo + (hi - lo) * u
    pose = np.asarray(kin.fkine(q)).reshape(stop - start, 4, 4)
    return {"q": q, "pose": pose, "problems": stop - start, "seconds": time.perf_counter() - t0}
