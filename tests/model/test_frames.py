"""Link frames of the numeric reference: ``frame=k`` against independent computations."""

from __future__ import annotations

import numpy as np
import pytest

from symkin import ETS, FrameError, Robot
from symkin.bench.compile import random_chain
from symkin.model.frames import frame_index
from symkin.model.robots import load
from tests.conftest import assert_close


def truncated(robot: Robot, k: int) -> Robot:
    """The chain up to and including the k-th joint (its end effector is link frame k)."""
    pos = [i for i, e in enumerate(robot.ets) if e.is_joint]
    return Robot(ETS(tuple(robot.ets)[: pos[k] + 1]), name="truncated")


@pytest.mark.parametrize("name", ["panda", "stanford", "puma560"])
def test_frame_jacobians_are_those_of_the_truncated_chain(name):
    robot = load(name)
    Q = robot.random_q(5, seed=1)
    for k in range(robot.n):
        sub = truncated(robot, k)
        J0, Je = robot.jacob0(Q, frame=k), robot.jacobe(Q, frame=k)
        assert J0.shape == Je.shape == (5, 6, robot.n)
        assert_close(J0[:, :, : k + 1], sub.jacob0(Q[:, : k + 1]), 1e-12, f"J0 frame {k}")
        assert_close(Je[:, :, : k + 1], sub.jacobe(Q[:, : k + 1]), 1e-12, f"Je frame {k}")
        assert not J0[:, :, k + 1 :].any() and not Je[:, :, k + 1 :].any()
        assert_close(robot.fkine(Q, frame=k), sub.fkine(Q[:, : k + 1]), 1e-12, f"T frame {k}")
        assert_close(robot.fkine(Q[0], frame=k), robot.link_poses(Q[0])[k], 1e-15)


def test_frame_jacobian_is_the_derivative_of_the_frame_pose():
    robot = random_chain(9, seed=2)
    q = robot.random_q(seed=3)
    h = 1e-6
    for k in (0, 4, 8):
        J = robot.jacob0(q, frame=k)
        T = robot.fkine(q, frame=k)
        for i in range(robot.n):
            dq = np.zeros(robot.n)
            dq[i] = h
            dT = (robot.fkine(q + dq, frame=k) - robot.fkine(q - dq, frame=k)) / (2 * h)
            w = dT[:3, :3] @ T[:3, :3].T
            assert_close(J[:, i], np.r_[dT[:3, 3], w[2, 1], w[0, 2], w[1, 0]], 1e-8, f"frame {k} col {i}")


@pytest.mark.parametrize("bad", [7, -1, 2.0, "3", True, None.__class__])
def test_invalid_frames_are_refused_with_the_valid_range(bad):
    robot = load("panda")
    with pytest.raises(FrameError, match=r"0\.\.6"):
        robot.jacob0(robot.qz, frame=bad)


def test_numpy_integers_are_frames():
    assert frame_index(np.int64(3), 7) == 3
    robot = load("ur5")
    assert_close(robot.jacobe(robot.qz, frame=np.int32(2)), robot.jacobe(robot.qz, frame=2), 0)


FRAME_METHODS = ("hessian0", "hessiane", "jacobm", "manipulability", "cond", "jacobs", "jacobb")


@pytest.mark.parametrize("name", ["panda", "stanford"])
def test_every_method_of_a_link_frame_is_that_of_the_truncated_chain(name):
    """hessian0/hessiane/jacobm/... (q, frame=k) of the reference, against the end effector of the
    chain cut after joint k (the O(n) ETS algorithm on its own ETS): columns of later joints 0."""
    robot = load(name)
    Q = robot.random_q(4, seed=7)
    for k in (1, 3, robot.n - 1):
        sub, c = truncated(robot, k), k + 1
        Qs = Q[:, :c]
        H, He = robot.hessian0(Q, frame=k), robot.hessiane(Q, frame=k)
        assert_close(H[:, :c, :, :c], sub.hessian0(Qs), 1e-12, f"H0 frame {k}")
        assert_close(He[:, :c, :, :c], sub.hessiane(Qs), 1e-12, f"He frame {k}")
        assert not H[:, c:].any() and not H[..., c:].any()
        assert_close(robot.jacobm(Q, frame=k, axes="trans")[:, :c], sub.jacobm(Qs, axes="trans"), 1e-9)
        m = robot.manipulability(Q, k, "rot")
        if c >= 3:
            assert_close(m, sub.manipulability(Qs, axes="rot"), 1e-9, "manipulability")
        else:  # 0 for the truncated chain (fewer joints than rows); sqrt of a rounding-level det here
            assert np.abs(m).max() < 1e-7
        cond, cond_sub = robot.cond(Q, k, "trans"), sub.cond(Qs, axes="trans")
        assert np.array_equal(np.isinf(cond), np.isinf(cond_sub))
        assert_close(cond[np.isfinite(cond)], cond_sub[np.isfinite(cond)], 1e-9, "cond")
        assert_close(robot.jacobs(Q, frame=k)[..., :c], sub.jacobs(Qs), 1e-12)
        assert_close(robot.jacobb(Q[0], frame=k)[:, :c], sub.jacobb(Qs[0]), 1e-12)
        qd = np.linspace(-1, 1, robot.n)
        assert_close(robot.jacob0_dot(Q[0], qd, frame=k)[:, :c], sub.jacob0_dot(Qs[0], qd[:c]), 1e-12)


def test_a_link_frame_hessian_is_the_derivative_of_its_jacobian():
    robot = random_chain(8, seed=4)
    q = robot.random_q(seed=5)
    h = 1e-6
    for k in (0, 3, 7):
        H = robot.hessian0(q, frame=k)
        for i in range(robot.n):
            dq = np.zeros(robot.n)
            dq[i] = h
            fd = (robot.jacob0(q + dq, frame=k) - robot.jacob0(q - dq, frame=k)) / (2 * h)
            assert_close(H[i], fd, 1e-7, f"dJ/dq{i}, frame {k}")


def test_axes_may_stand_second_as_before_and_frames_are_checked():
    robot = load("ur5")
    q = robot.qr if "qr" in robot.configs else robot.random_q(seed=1)
    assert robot.manipulability(q, "trans") == robot.manipulability(q, axes="trans")
    assert robot.manipulability(q, None, "trans") == robot.manipulability(q, axes="trans")
    with pytest.raises(ValueError, match="axes given twice"):
        robot.manipulability(q, "trans", "rot")
    with pytest.raises(FrameError, match="link frame index"):
        robot.hessian0(q, frame="tool")
    with pytest.raises(FrameError, match="link frames 0..5"):
        robot.jacobm(q, frame=6)
