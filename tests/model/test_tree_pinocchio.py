"""Whole robots of example-robot-data against Pinocchio: framesForwardKinematics and
computeFrameJacobian (LOCAL_WORLD_ALIGNED) on every leaf frame, by the numeric reference, and on
the compiled C kernel of the frames a user names. Needs the ``compare`` extra (skipped without)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import Tree

pin = pytest.importorskip("pinocchio")

from symkin.bench.tree import erd_robots_dir, pinocchio_q  # noqa: E402

ROOT = erd_robots_dir()
pytestmark = pytest.mark.skipif(ROOT is None, reason="example-robot-data is not installed")

# (URDF, frames for the compiled kernel, Pinocchio with mimic joints)
ROBOTS = {
    "quadruped": ("solo_description/robots/solo12.urdf", "FL_FOOT,FR_FOOT,HL_FOOT,HR_FOOT", False),
    "humanoid": ("human_description/robots/human.urdf", "left_hand,right_hand,left_foot,right_foot", False),
    "dual_arm": (
        "baxter_description/urdf/baxter.urdf",
        "left_gripper,right_gripper,l_gripper_r_finger_tip",
        True,
    ),
}


def pinocchio_frames(urdf: str, tree: Tree, q: np.ndarray, mimic: bool) -> tuple[np.ndarray, np.ndarray]:
    model = pin.buildModelFromUrdf(str(ROOT / urdf), mimic)
    data = model.createData()
    qp = pinocchio_q(model, tree.joint_names, q)
    pin.framesForwardKinematics(model, data, qp)
    cols = [model.idx_vs[model.getJointId(n)] for n in tree.joint_names]
    T, J = [], []
    for f in tree.frames:
        fid = model.getFrameId(f)
        T.append(data.oMf[fid].homogeneous)
        J.append(pin.computeFrameJacobian(model, data, qp, fid, pin.LOCAL_WORLD_ALIGNED)[:, cols])
    return np.array(T), np.array(J)


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_every_leaf_frame_matches_pinocchio(name):
    urdf, _, mimic = ROBOTS[name]
    tree = Tree.from_urdf(ROOT / urdf)
    for q in tree.random_q(3, seed=1):
        T, J = pinocchio_frames(urdf, tree, q, mimic)
        Tr, Jr = tree.fkine_jacob0_all(q)
        assert np.abs(Tr - T).max() < 1e-10
        assert np.abs(Jr - J).max() < 1e-10


@pytest.mark.parametrize("name", sorted(ROBOTS))
def test_the_compiled_kernel_matches_pinocchio(name):
    urdf, frames, mimic = ROBOTS[name]
    tree = Tree.from_urdf(ROOT / urdf, frames=frames)
    kin = symkin.compile(tree, "c")
    Q = tree.random_q(4, seed=2)
    T, J = kin.fkine_jacob0_all(Q)
    for i, q in enumerate(Q):
        Tp, Jp = pinocchio_frames(urdf, tree, q, mimic)
        assert np.abs(T[i] - Tp).max() < 1e-10
        assert np.abs(J[i] - Jp).max() < 1e-10
