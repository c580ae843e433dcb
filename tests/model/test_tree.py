"""The kinematic tree and its numeric reference: URDF import (order, frames, mimic joints), against
the serial chains of each frame, finite differences, and clear errors."""

from __future__ import annotations

from fractions import Fraction

import numpy as np
import pytest

from symkin import FrameError, Robot, RobotError, Tree, URDFError
from symkin.model.plot import chain_points
from tests.conftest import assert_close
from tests.model.tree_urdfs import ARM_CAMERA, GRIPPER, GRIPPER_FREE, QUADRUPED, fixed, joint, urdf

TREES = {"quadruped": QUADRUPED, "arm_camera": ARM_CAMERA, "gripper": GRIPPER}


def fd_jacobian(fk, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """(6, n) from central differences of the pose: (dp/dq, vee(dR/dq R^T))."""
    T = fk(q)
    cols = []
    for i in range(q.size):
        d = np.zeros(q.size)
        d[i] = h
        dT = (fk(q + d) - fk(q - d)) / (2 * h)
        W = dT[:3, :3] @ T[:3, :3].T
        cols.append(np.r_[dT[:3, 3], W[2, 1], W[0, 2], W[1, 0]])
    return np.array(cols).T


def test_joints_depth_first_children_in_file_order_and_default_frames():
    tree = Tree.from_urdf(QUADRUPED)
    assert tree.joint_names == (
        "l_haa",
        "l_hfe",
        "l_kfe",
        "tail_slide",
        "tail_bend",
        "r_haa",
        "r_hfe",
        "r_kfe",
    )
    assert tree.frames == ("l_foot", "tail_tip", "r_foot")
    assert tree.n == 8 and tree.name == "quad" and tree.base_link == "body"
    assert tree.qlim.shape == (2, 8)
    assert tree.qlim[:, 5].tolist() == pytest.approx([-np.pi, np.pi])  # continuous
    assert tree.qlim[:, 3].tolist() == [0.0, 0.1]
    assert tree.qd_max is None  # the continuous joint gives no velocity
    assert Tree.from_urdf(ARM_CAMERA).qd_max.tolist() == [2.0] * 4


def test_frames_in_the_order_given_and_only_the_joints_they_need():
    tree = Tree.from_urdf(QUADRUPED, frames=["r_foot", "tail2"])
    assert tree.frames == ("r_foot", "tail2")
    assert tree.joint_names == ("tail_slide", "tail_bend", "r_haa", "r_hfe", "r_kfe")
    sub = Tree.from_urdf(QUADRUPED, frames="r_thigh", base_link="r_hip")
    assert sub.joint_names == ("r_hfe",) and sub.base_link == "r_hip"


@pytest.mark.parametrize("name", ["quadruped", "arm_camera"])
def test_each_frame_is_the_serial_chain_robot_from_urdf_imports(name):
    xml = TREES[name]
    tree = Tree.from_urdf(xml)
    Q = tree.random_q(6, seed=1)
    for f in tree.frames:
        robot = tree.chain(f)
        assert robot.ets == Robot.from_urdf(xml, end_link=f).ets
        cols = [tree.slots[k].joint for k in tree.path_slots(f)]
        assert robot.joint_names == tuple(tree.joint_names[c] for c in cols)
        assert_close(tree.fkine(Q, f), robot.fkine(Q[:, cols]), 1e-13, f"T {f}")
        J = tree.jacob0(Q, f)
        assert_close(J[:, :, cols], robot.jacob0(Q[:, cols]), 1e-13, f"J0 {f}")
        assert not np.delete(J, cols, axis=2).any(), "columns of joints off the path are zero"
        assert_close(tree.jacobe(Q, f)[:, :, cols], robot.jacobe(Q[:, cols]), 1e-13, f"Je {f}")


@pytest.mark.parametrize("name", sorted(TREES))
def test_jacobians_are_derivatives_of_the_poses(name):
    tree = Tree.from_urdf(TREES[name])
    q = tree.random_q(seed=2)
    for f in tree.frames:
        J = tree.jacob0(q, f)
        assert_close(J, fd_jacobian(lambda x, f=f: tree.fkine(x, f), q), 1e-8, f"J0 of {f} vs differences")
        R = tree.fkine(q, f)[:3, :3]
        assert_close(tree.jacobe(q, f), np.vstack((R.T @ J[:3], R.T @ J[3:])), 1e-14, "Je = R^T J0")


@pytest.mark.parametrize("name", sorted(TREES))
def test_hessians_are_derivatives_of_the_jacobians(name):
    tree = Tree.from_urdf(TREES[name])
    q = tree.random_q(seed=3)
    h = 1e-6
    for f in tree.frames:
        H = tree.hessian0(q, f)
        for i in range(tree.n):
            d = np.zeros(tree.n)
            d[i] = h
            fd = (tree.jacob0(q + d, f) - tree.jacob0(q - d, f)) / (2 * h)
            assert_close(H[i], fd, 1e-8, f"H0[{i}] of {f}")


def test_all_frames_at_once_match_each_frame_and_batch_shapes():
    tree = Tree.from_urdf(QUADRUPED)
    Q = tree.random_q(4, seed=4)
    T, J = tree.fkine_all(Q), tree.jacob0_all(Q)
    assert T.shape == (4, 3, 4, 4) and J.shape == (4, 3, 6, 8)
    assert tree.fkine_all(Q[0]).shape == (3, 4, 4) and tree.jacob0_all(Q[0]).shape == (3, 6, 8)
    for k, f in enumerate(tree.frames):
        assert np.array_equal(T[:, k], tree.fkine(Q, f))
        assert np.array_equal(J[:, k], tree.jacob0(Q, f))
    T2, J2 = tree.fkine_jacob0_all(Q)
    assert np.array_equal(T2, T) and np.array_equal(J2, J)
    assert tree.fkine(Q[0], "l_foot").shape == (4, 4) and tree.jacob0(Q[0], "l_foot").shape == (6, 8)


def test_segment_poses_are_each_links_pose_and_its_joint_frame():
    tree = Tree.from_urdf(QUADRUPED, frames=["l_foot", "tail1", "tail_tip", "r_foot"])
    Q = tree.random_q(3, seed=8)
    L, P = tree.segment_poses(Q)
    assert L.shape == P.shape == (3, len(tree.segments), 4, 4)
    assert_close(L[:, list(tree.frame_segments)], tree.fkine_all(Q), 1e-12, "links")
    for k, seg in enumerate(tree.segments):
        if seg.slot is None:
            assert np.array_equal(P[:, k], L[:, k]), f"fixed segment {seg.name}: no joint"
    for frame in tree.frames:  # joint frames: the poses just before each joint of the frame's chain
        chain, slots = tree.chain(frame), tree.path_slots(frame)
        for i, q in enumerate(Q):
            joints = chain_points(chain, q[[tree.slots[k].joint for k in slots]])[1]
            P_chain = np.array([T for T, _ in joints])
            assert_close(P[i, [tree.slots[k].segment for k in slots]], P_chain, 1e-12, f"joints to {frame}")
    one = tree.segment_poses(Q[1])
    assert np.array_equal(one[0], L[1]) and np.array_equal(one[1], P[1])


def test_mimic_joints_follow_their_joint_exactly():
    tree = Tree.from_urdf(GRIPPER)
    free = Tree.from_urdf(GRIPPER_FREE)
    assert tree.joint_names == ("shoulder", "wrist", "finger_a")
    assert free.joint_names == ("shoulder", "wrist", "finger_a", "tip_a", "tip_a2", "finger_b")
    slot = {s.name: s for s in tree.slots}
    assert (slot["tip_a"].joint, slot["tip_a"].multiplier, slot["tip_a"].offset) == (1, 2, Fraction(1, 10))
    # a mimic of a mimic composes: tip_a2 = -0.5 (2 wrist + 0.1)
    assert (slot["tip_a2"].joint, slot["tip_a2"].multiplier, slot["tip_a2"].offset) == (
        1,
        -1,
        Fraction(-1, 20),
    )
    assert (slot["finger_b"].joint, slot["finger_b"].multiplier, slot["finger_b"].offset) == (
        2,
        -1,
        Fraction(1, 100),
    )
    for q in tree.random_q(5, seed=5):
        full = np.r_[q, 2 * q[1] + 0.1, -(2 * q[1] + 0.1) / 2, -q[2] + 0.01]
        for f in tree.frames:
            assert_close(tree.fkine(q, f), free.fkine(full, f), 1e-14, f"T {f}")
            # chain rule: dT/dq = sum over the slots q drives of multiplier * their column
            Jf = free.jacob0(full, f)
            A = np.zeros((6, 3))
            A[[0, 1, 2, 3, 4, 5], [0, 1, 2, 1, 1, 2]] = [1, 1, 1, 2, -1, -1]
            assert_close(tree.jacob0(q, f), Jf @ A, 1e-14, f"J0 {f} by the chain rule")


def test_a_chain_through_a_mimic_joint_is_not_a_robot():
    tree = Tree.from_urdf(GRIPPER, frames=["l2", "fa_tip"])
    assert tree.chain("l2").n == 2
    with pytest.raises(URDFError, match="mimic joint 'tip_a'.*wrist"):
        tree.chain("fa_tip")
    # Robot.from_urdf refuses a movable mimic joint on its chain, ignores <mimic> on a fixed one
    with pytest.raises(URDFError, match="mimics"):
        Robot.from_urdf(GRIPPER, end_link="fb")
    fixed_mimic = urdf(["a", "b", "c"], [joint("j", "a", "b"), fixed("f", "b", "c").replace(
        "</joint>", '<mimic joint="j"/></joint>')])  # fmt: skip
    assert Robot.from_urdf(fixed_mimic).n == 1
    assert Tree.from_urdf(fixed_mimic).n == 1


def test_revolute_mask_wraps_only_joints_that_repeat_every_turn():
    tree = Tree.from_urdf(GRIPPER)
    assert tree.revolute.tolist() == [True, True, False]  # wrist drives 2x and -1x: still 2 pi periodic
    half = Tree.from_urdf(
        GRIPPER.replace('multiplier="-0.5"', 'multiplier="0.5"').replace('multiplier="2"', 'multiplier="1.5"')
    )
    assert half.revolute.tolist() == [True, False, False]


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        ({"frames": ["l_foot", "nope"]}, "frame 'nope' is not a link"),
        ({"frames": ["l_foot", "l_foot"]}, "distinct"),
        ({"frames": []}, "empty"),
        ({"frames": ["body"]}, "is the base link"),
        ({"frames": ["l_foot"], "base_link": "r_hip"}, "not below base_link 'r_hip'"),
        ({"base_link": "nowhere"}, "base_link 'nowhere' is not a link"),
    ],
)
def test_bad_frames_are_clear_errors(kwargs, match):
    with pytest.raises(URDFError, match=match):
        Tree.from_urdf(QUADRUPED, **kwargs)


def test_unknown_frame_names_the_frames():
    tree = Tree.from_urdf(QUADRUPED)
    q = np.zeros(tree.n)
    with pytest.raises(FrameError, match=r"no frame 'l_fot' \(did you mean 'l_foot'.*'tail_tip'"):
        tree.fkine(q, "l_fot")
    with pytest.raises(FrameError, match="name one with frame="):
        tree.jacob0(q)
    with pytest.raises(FrameError, match="link name"):
        tree.jacob0(q, 0)
    single = Tree.from_urdf(QUADRUPED, frames=["tail_tip"])
    assert single.fkine(np.zeros(2)).shape == (4, 4)  # one frame: frame may be omitted


def test_unsupported_joints_and_bad_mimics_are_refused_with_the_joint_named():
    floating = urdf(
        ["w", "b", "c"], [joint("free", "w", "b", kind="floating", axis=None, limit=""), joint("j", "b", "c")]
    )
    with pytest.raises(URDFError, match="joint 'free' .* is floating.*base_link 'b'"):
        Tree.from_urdf(floating)
    assert Tree.from_urdf(floating, base_link="b").n == 1
    with pytest.raises(URDFError, match="mimics joint 'ghost', which does not exist"):
        Tree.from_urdf(GRIPPER.replace('mimic joint="wrist"', 'mimic joint="ghost"'))
    cyc = GRIPPER.replace('<mimic joint="wrist" multiplier="2" offset="0.1"/>', '<mimic joint="tip_a2"/>')
    with pytest.raises(URDFError, match="cycle"):
        Tree.from_urdf(cyc)
    to_fixed = GRIPPER.replace('mimic joint="wrist"', 'mimic joint="palm_mount"')
    with pytest.raises(URDFError, match="which is fixed"):
        Tree.from_urdf(to_fixed)
    with pytest.raises(URDFError, match="joint names must be unique"):
        Tree.from_urdf(ARM_CAMERA.replace('name="j4"', 'name="j3"'))


@pytest.mark.parametrize("name", ["panda", "ur5", "stanford", "gantry"])
def test_a_chain_is_a_tree_with_one_end_frame(name):
    """Tree.from_robot: the same kinematics through the tree's own walk (segments and slots), and
    Tree.chain gives the robot's ETS back."""
    from symkin.model.robots import load

    robot = load(name)
    tree = Tree.from_robot(robot)
    assert tree.frames == ("ee",) and tree.n == robot.n and tree.joint_names == robot.joint_names
    assert np.array_equal(tree.qlim, robot.qlim)
    assert str(tree.chain("ee").ets) == str(robot.ets)
    Q = robot.random_q(5, seed=2)
    for m in ("fkine", "jacob0", "jacobe", "hessian0", "hessiane", "jacobm", "manipulability"):
        assert np.abs(getattr(tree, m)(Q) - getattr(robot, m)(Q)).max() < 1e-12, m
    with pytest.raises(RobotError, match="other than the links"):
        Tree.from_robot(robot, frame="link1")
