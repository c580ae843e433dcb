"""The voxel grid, the reach ball, the orientation set and the counter-based random numbers
(no Dask or Zarr needed)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin.errors import WorkspaceError
from symkin.workspace.grid import VoxelGrid, counter_uniform, reach_ball, so3_uniform, voxel_seeds

PLANAR = "Rz(q) tx(0.6) Rz(q) tx(0.25) Rz(q) tx(0.15)"


def test_so3_uniform_is_a_fixed_set_of_rotations_with_zero_mean():
    R = so3_uniform(20000, seed=3)
    assert np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max() < 1e-12
    assert np.allclose(np.linalg.det(R), 1.0)
    # uniform on SO(3) (Haar measure): E[R] = 0; each entry has std 1/sqrt(3), so 20000 samples
    # put the mean within 5 sigma = 0.02 of 0
    assert np.abs(R.mean(axis=0)).max() < 0.02
    # rotation angle density (1 - cos t) / pi on [0, pi]: mean angle pi/2 + 2/pi
    angle = np.arccos(np.clip((np.trace(R, axis1=1, axis2=2) - 1) / 2, -1, 1))
    assert abs(angle.mean() - (math.pi / 2 + 2 / math.pi)) < 0.02
    assert np.array_equal(so3_uniform(50, seed=3), R[:50])  # the first K of a seed never change
    assert not np.array_equal(so3_uniform(50, seed=4), R[:50])
    with pytest.raises(WorkspaceError):
        so3_uniform(0)


def test_counter_streams_do_not_depend_on_which_elements_are_drawn():
    full = counter_uniform(7, 3, np.arange(1000))
    part = counter_uniform(7, 3, np.arange(400, 600))
    assert np.array_equal(full[400:600], part)
    assert ((full >= 0) & (full < 1)).all() and abs(full.mean() - 0.5) < 0.05
    assert not np.array_equal(full, counter_uniform(7, 2, np.arange(1000)))
    seeds = voxel_seeds(0, np.arange(10_000))
    assert len(np.unique(seeds)) == 10_000


@pytest.mark.parametrize(
    "spec", ["ur5", "panda", PLANAR, "tz(0.3) Rz(q) ty(0.2) tz(q) tx(0.1) Ry(q) tx(0.4)"]
)
def test_reach_ball_holds_every_reachable_position(spec):
    robot = symkin.resolve_robot(spec)
    if robot.ets.structure.count("P"):
        robot = symkin.Robot(robot.ets, qlim=[[-3, -0.5, -3], [3, 0.7, 3]])
    centre, radius = reach_ball(robot)
    rng = np.random.default_rng(0)
    Q = rng.uniform(robot.qlim[0], robot.qlim[1], (4000, robot.n))
    p = robot.fkine(Q)[:, :3, 3]  # the numeric ETS reference
    d = np.linalg.norm(p - centre, axis=1)
    assert d.max() <= radius + 1e-12
    assert d.max() > 0.6 * radius  # and the bound is not wildly loose


def test_reach_ball_of_known_robots():
    centre, radius = reach_ball(symkin.Robot.from_ets(PLANAR))
    assert np.allclose(centre, 0) and radius == pytest.approx(1.0)
    centre, radius = reach_ball(symkin.load("ur5"))  # the shoulder height is on the first joint's axis
    assert np.allclose(centre, [0, 0, 0.089159])
    assert radius == pytest.approx(0.425 + 0.39225 + 0.10915 + 0.09465 + 0.0823)


def test_voxel_grid_blocks_cover_the_grid_once_and_bounds_select_a_box():
    grid = VoxelGrid.of(np.zeros(3), 1.0, 0.1, chunk=6)
    assert grid.shape == (21, 21, 21) and grid.chunks == (4, 4, 4)
    count = np.zeros(grid.shape, dtype=int)
    for i in range(grid.n_chunks):
        count[grid.block(i)] += 1
    assert (count == 1).all()
    C = grid.centers()
    assert np.allclose(C[10, 10, 10], 0) and np.allclose(C[0, 0, 0], -1.0)
    flat = grid.flat_index(tuple(slice(0, s) for s in grid.shape))
    assert np.array_equal(flat.ravel(), np.arange(21**3))
    box = VoxelGrid.of(np.zeros(3), 1.0, 0.1, bounds=[[0.05, 0.35], [-1, 1], [-0.01, 0.01]])
    assert box.shape == (3, 21, 1)
    assert np.allclose(box.axes()[0], [0.1, 0.2, 0.3]) and np.allclose(box.axes()[2], [0.0])
    # a voxel has the same global index (so the same random stream) with or without bounds
    sub = box.flat_index(tuple(slice(0, s) for s in box.shape))
    assert np.array_equal(sub, flat[11:14, :, 10:11])
    assert VoxelGrid.of(np.zeros(3), 1.0, 0.1).chunk == 6  # the largest edge giving >= 64 blocks
    with pytest.raises(WorkspaceError):
        VoxelGrid.of(np.zeros(3), 1.0, 0.0)
    with pytest.raises(WorkspaceError):
        VoxelGrid.of(np.zeros(3), 1.0, 0.1, bounds=[[2, 3], [0, 1], [0, 1]])
