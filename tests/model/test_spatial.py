"""Velocity and wrench transforms and joint torques, exported from symkin (issue 36, item 14): the
names are importable from ``symkin``, ``joint_torques`` is the method's answer, and tau = J^T w is
checked by virtual work against finite differences of fkine (independent of any Jacobian)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.model import differential, spatial


def _omega(R0: np.ndarray, R1: np.ndarray, h: float) -> np.ndarray:
    """The base-frame angular velocity that turns R0 into R1 in time h (central part of R1 R0^T)."""
    W = (R1 @ R0.T - R0 @ R1.T) / (4 * h)  # (R(q + h) - R(q - h)) R^T / (2 h), skew part
    return np.array([W[2, 1], W[0, 2], W[1, 0]])


def test_the_names_are_exported_from_symkin():
    for name in ("velocity_transform", "wrench_transform", "joint_torques"):
        assert name in symkin.__all__ and getattr(symkin, name) is getattr(spatial, name)
    assert differential.velocity_transform is spatial.velocity_transform  # the old import still works


@pytest.mark.parametrize("backend", [None, "c", "numpy"])
def test_joint_torques_by_virtual_work(backend):
    robot = symkin.load("panda")
    kin = robot if backend is None else symkin.compile(robot, backend=backend)
    q = robot.random_q(seed=7)
    w = np.array([3.0, -1.0, 2.0, 0.4, -0.2, 0.1])  # force (N), moment (N m) about the hand, base frame
    tau = symkin.joint_torques(kin, q, w)
    np.testing.assert_array_equal(tau, kin.joint_torques(q, w))
    h = 1e-6
    for j in range(robot.n):
        dq = np.zeros(robot.n)
        dq[j] = h
        Tp, Tm = robot.fkine(q + dq), robot.fkine(q - dq)
        v = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        work = w[:3] @ v + w[3:] @ _omega(Tm[:3, :3], Tp[:3, :3], h)
        assert tau[j] == pytest.approx(work, abs=1e-7)
    R = robot.fkine(q)[:3, :3]
    w_ee = np.r_[R.T @ w[:3], R.T @ w[3:]]  # the same wrench in the end-effector frame
    np.testing.assert_allclose(symkin.joint_torques(kin, q, w_ee, in_frame="ee"), tau, atol=1e-12)
    Q = robot.random_q(3, seed=8)
    assert symkin.joint_torques(kin, Q, w).shape == (3, robot.n)
