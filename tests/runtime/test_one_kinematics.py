"""One runtime Kinematics for chains and trees: every method takes ``frame=`` on every backend,
with the numeric reference's values, shapes and errors."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import FrameError, ParameterError, Tree
from symkin.model.robots import load
from tests.conftest import assert_close
from tests.model.tree_urdfs import GRIPPER, QUADRUPED

BACKENDS = ("c", "numpy", "casadi")
METHODS = (
    "fkine",
    "jacob0",
    "jacobe",
    "fkine_jacob0",
    "jacob0_hessian0",
    "hessian0",
    "hessiane",
    "manipulability",
    "jacobm",
    "cond",
    "jacobs",
    "jacobb",
)


def _flat(x):
    """The values of a result (tuples joined); inf (cond of a rank-deficient J) as a marker value."""
    a = np.concatenate([np.ravel(a) for a in x]) if isinstance(x, tuple) else np.asarray(x, dtype=float)
    return np.where(np.isposinf(a), -12345.0, a)


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_method_of_a_compiled_chain_takes_a_link_frame(backend):
    robot = load("panda")
    kin = symkin.compile(robot, backend)
    Q = robot.random_q(4, seed=11)
    for frame in (None, 0, 3, robot.n - 1):
        for m in METHODS:
            for q in (Q, Q[1]):
                got, ref = getattr(kin, m)(q, frame), getattr(robot, m)(q, frame)
                assert np.shape(_flat(got)) == np.shape(_flat(ref)), (m, frame)
                assert_close(_flat(got), _flat(ref), 1e-9, f"{backend} {m} frame={frame}")
        qd = np.linspace(-1, 1, robot.n)
        assert_close(kin.jacob0_dot(Q[0], qd, frame), robot.jacob0_dot(Q[0], qd, frame), 1e-10)
    m_ref = robot.manipulability(Q[0], frame=2, axes="trans")
    assert kin.manipulability(Q[0], 2, "trans") == pytest.approx(m_ref)
    assert kin.manipulability(Q[0], "trans") == pytest.approx(robot.manipulability(Q[0], axes="trans"))


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("urdf", [QUADRUPED, GRIPPER], ids=["quadruped", "gripper"])
def test_every_method_of_a_compiled_tree_takes_its_frames(backend, urdf):
    tree = Tree.from_urdf(urdf)
    kin = symkin.compile(tree, backend)
    assert type(kin) is symkin.Kinematics and kin.frames == tree.frames
    Q = tree.random_q(3, seed=12)
    for frame in tree.frames:
        for m in METHODS:
            for q in (Q, Q[0]):
                got, ref = getattr(kin, m)(q, frame), getattr(tree, m)(q, frame)
                assert_close(_flat(got), _flat(ref), 1e-9, f"{backend} {m} frame={frame}")


@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_tree_hessians_are_generated_and_match_finite_differences(backend):
    """Generated from the Jacobian's slot columns along each frame's path (mimic frames too: both
    multipliers per block). Checked against central differences of the reference J."""
    for urdf in (QUADRUPED, GRIPPER):
        tree = Tree.from_urdf(urdf)
        kin = symkin.compile(tree, backend)
        q = tree.random_q(seed=13)
        for frame in tree.frames:
            mimic = any(tree.slots[k].is_mimic for k in tree.path_slots(frame))
            if backend == "numpy":
                J, H = kin.module.jacob0_hessian0(q, frame)  # mimic frames too: from the slot columns
                assert_close(H, tree.hessian0(q, frame), 1e-12, f"{frame}, mimic {mimic}")
            else:
                assert f"jacob0_hessian0_{tree.frame_position(frame)}" in kin.functions
            H = kin.hessian0(q, frame)
            for i in range(tree.n):
                dq = np.zeros(tree.n)
                dq[i] = 1e-6
                fd = (tree.jacob0(q + dq, frame) - tree.jacob0(q - dq, frame)) / 2e-6
                assert_close(H[i], fd, 1e-7, f"{backend} {frame} dJ/dq{i}")


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_chain_and_its_one_frame_tree_compile_to_the_same_kinematics(backend):
    robot = load("ur5")
    chain, tree = symkin.compile(robot, backend), symkin.compile(Tree.from_robot(robot), backend)
    assert type(chain) is type(tree)
    Q = robot.random_q(5, seed=14)
    for m in ("fkine", "jacob0", "jacobe", "hessian0", "jacobm", "manipulability"):
        assert_close(getattr(tree, m)(Q), getattr(chain, m)(Q), 1e-10, m)
        assert_close(getattr(tree, m)(Q, "ee"), getattr(chain, m)(Q, None), 1e-10, m)


@pytest.mark.parametrize("backend", BACKENDS)
def test_the_same_errors_on_chains_and_trees(backend):
    chain = symkin.compile(load("ur5"), backend)
    tree = symkin.compile(Tree.from_urdf(QUADRUPED), backend)
    q, qt = np.zeros(6), np.zeros(tree.n)
    for kin, x, frame in ((chain, q, None), (chain, q, 2), (tree, qt, "l_foot")):
        for m in ("manipulability", "jacobm", "cond"):
            with pytest.raises(ParameterError, match="axes must be one of"):
                getattr(kin, m)(x, frame, "xyz")
    with pytest.raises(FrameError, match="link frames 0..5"):
        chain.hessian0(q, 6)
    with pytest.raises(FrameError, match="link frame index"):
        chain.jacobm(q, frame="l_foot")
    with pytest.raises(FrameError, match="has no frame 'l_fot'.*did you mean 'l_foot'"):
        tree.hessiane(qt, "l_fot")
    with pytest.raises(FrameError, match="name one with frame="):
        tree.jacobm(qt)


def test_ik_and_mmc_on_a_link_frame_of_a_chain():
    robot = load("panda")
    kin = symkin.compile(robot, "c")
    q = robot.random_q(seed=15)
    Tep = robot.fkine(q, frame=5)
    res = kin.ik(Tep, frame=5, q0=q + 0.05)
    assert res.success
    assert_close(robot.fkine(res.q, frame=5), Tep, 1e-6, "the link frame reaches its target")
    assert np.array_equal(res.q[6:], (q + 0.05)[6:]), "the joint after the frame does not move"
    assert kin.select(None) is kin and kin.select(5) is kin.select(5)


def test_servo_and_mmc_on_a_link_frame_of_a_chain():
    """The elbow-like link frame 3 of the Panda servos to a pose; joints after it stay put."""
    from symkin import MMC, servo

    robot = load("panda")
    kin = symkin.compile(robot, "c")
    q0 = robot.qr.copy()
    q_goal = q0 + np.array([0.1, -0.1, 0.1, 0.1, 0.0, 0.0, 0.0])
    Tep = robot.fkine(q_goal, frame=3)
    res = servo(kin, q0, Tep, frame=3, controller="rrmc", max_steps=400)
    assert res.arrived
    assert_close(robot.fkine(res.q[-1], frame=3)[:3, 3], Tep[:3, 3], 1e-2, "frame 3 reaches its target")
    assert np.array_equal(res.q[-1][4:], q0[4:])
    J = robot.jacob0(q0, frame=3)
    nu = J @ np.array([0.05, -0.02, 0.03, 0.04, 0.0, 0.0, 0.0])  # a velocity frame 3 can make
    qd, _ = MMC(kin, frame=3, slack=False).step(q0, nu)
    assert qd.shape == (7,) and np.abs(qd[4:]).max() < 1e-6
    assert_close(J @ qd, nu, 1e-5, "the step makes the commanded velocity (OSQP's tolerance)")
