"""Closed-form IK of 7-joint arms with one joint given (kin.ik_all(T, free_joint=(j, values))): every
solution checked by the numeric reference FK of the full arm (Robot.fkine), branches checked
against numerical IK sampling of the remaining arm."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.errors import ConfigurationError, NoAnalyticIKError
from symkin.runtime.free_joint import free_joint_solver

EXACT = 1e-10


def _wrapdiff(a, b):
    return np.remainder(a - b + np.pi, 2 * np.pi) - np.pi


@pytest.mark.parametrize(("name", "j"), [("panda", 6), ("lbr_iiwa7", 0), ("lbr_iiwa7", 6)])
def test_every_solution_reproduces_the_pose(name, j):
    kin = symkin.compile(name)
    robot = kin.robot
    Q = robot.random_q(25, seed=4)
    T = robot.fkine(Q)
    values = np.array([-1.3, 0.4, 2.1])
    for q, Ti in zip(Q, T):
        sols = kin.ik_all(Ti, free_joint=(j, q[j]), joint_limits=False)
        assert np.abs(robot.fkine(sols) - Ti).max() <= EXACT
        assert (sols[:, j] == q[j]).all()
        assert (np.abs(_wrapdiff(sols, q)).max(axis=1) < 1e-7).any(), "the generating q is missing"
        swept = kin.ik_all(Ti, free_joint=(j, values), joint_limits=False)
        if len(swept):
            assert np.abs(robot.fkine(swept) - Ti).max() <= EXACT
            assert np.isin(swept[:, j], values).all()
    batch = kin.ik_all(T, free_joint=(j, values), joint_limits=False)
    S = free_joint_solver(robot, j).max_solutions
    assert batch.shape == (25, 3 * S, 7)
    first = batch[0][~np.isnan(batch[0, :, 0])]
    np.testing.assert_allclose(first, kin.ik_all(T[0], free_joint=(j, values), joint_limits=False))


def test_no_branch_missed_against_sampling():
    """Numerical IK of the remaining 6-joint arm (its own generated kinematics) from many starts finds
    no solution that the closed form misses, and each one, completed with the given value, is a
    solution of the full arm."""
    kin = symkin.compile("panda")
    robot = kin.robot
    fj = free_joint_solver(robot, 6)
    sub = symkin.compile(fj.sub)
    Q = robot.random_q(6, seed=11)
    T = robot.fkine(Q)
    starts = 24
    rng = np.random.default_rng(5)
    for q, Ti in zip(Q, T):
        Tv = fj.targets(Ti[None], np.array([q[6]]))[0, 0]
        res = sub.ik(np.repeat(Tv[None], starts, 0), q0=rng.uniform(-np.pi, np.pi, (starts, 6)), slimit=1,
                     ilimit=60, tol=1e-12, joint_limits=False, seed=1)  # fmt: skip
        sols = kin.ik_all(Ti, free_joint=(6, q[6]), joint_limits=False)
        found = res.q[res.success]
        assert len(found) > 0
        for x in found:
            full = np.append(x, q[6])
            assert np.abs(robot.fkine(full) - Ti).max() < 1e-9
            assert (np.abs(_wrapdiff(sols, full)).max(axis=1) < 1e-6).any(), "branch missed"


def test_ik_sweeps_the_free_joint_to_the_nearest_solution():
    kin = symkin.compile("panda")
    robot = kin.robot
    Q = robot.random_q(4, seed=8)
    q0 = Q + 0.04
    res = kin.ik(robot.fkine(Q), method="analytic", free_joint=6, q0=q0)
    assert res.success.all()
    assert np.abs(robot.fkine(res.q) - robot.fkine(Q)).max() < 1e-10
    # the sweep (and its refinement) gets at least as near q0 as the configuration that made the pose
    assert (np.linalg.norm(res.q - q0, axis=1) <= np.linalg.norm(Q - q0, axis=1) + 0.02).all()
    one = kin.ik(robot.fkine(Q[0]), method="analytic", free_joint=(6, [Q[0, 6]]), q0=Q[0])
    np.testing.assert_allclose(one.q, Q[0], atol=1e-9)
    far = np.eye(4)
    far[:3, 3] = [3.0, 0.0, 0.0]
    miss = kin.ik(far, method="analytic", free_joint=6)
    assert not miss.success and "no closed-form solution" in miss.reason


def test_values_repeated_mod_2pi_give_each_solution_once():
    kin = symkin.compile("lbr_iiwa7")
    q = kin.robot.random_q(1, seed=2)[0]
    T = kin.robot.fkine(q)
    once = kin.ik_all(T, free_joint=(0, q[0]), joint_limits=False)
    twice = kin.ik_all(T, free_joint=(0, [q[0], q[0] + 2 * np.pi, q[0] + 1e-9]), joint_limits=False)
    assert len(twice) == len(once)


def test_errors_name_what_is_wrong():
    iiwa = symkin.compile("lbr_iiwa7")
    T = iiwa.fkine(iiwa.robot.qr if "qr" in iiwa.robot.configs else np.full(7, 0.3))
    with pytest.raises(NoAnalyticIKError, match="middle of the chain"):
        iiwa.ik_all(T, free_joint=(2, 0.3))
    with pytest.raises(NoAnalyticIKError, match="remaining 6-joint arm has no closed form"):
        symkin.compile("panda").ik_all(T, free_joint=(0, 0.3))
    with pytest.raises(ConfigurationError, match="joint index"):
        iiwa.ik_all(T, free_joint=(9, 0.3))
    with pytest.raises(ConfigurationError, match="values"):
        iiwa.ik_all(T, free_joint=0)
    with pytest.raises(ConfigurationError, match="finite"):
        iiwa.ik_all(T, free_joint=(0, [0.1, np.nan]))
    ur5 = symkin.compile("ur5")
    Tu = ur5.fkine(np.full(6, 0.3))
    for _ in range(2):  # before and after kin.ik_all goes straight to the C solver
        with pytest.raises(ConfigurationError, match="redundant arms"):
            ur5.ik_all(Tu, free_joint=(0, 0.3))
        assert len(ur5.ik_all(Tu))


def test_reversed_arm_on_every_backend_agrees_with_c():
    """The remaining arm of the Panda (solved reversed) gives the same rows on the NumPy and plain
    Python backends as in C."""
    robot = symkin.load("panda")
    sub = free_joint_solver(robot, 6).sub
    c = symkin.compile(sub)
    q = sub.random_q(3, seed=9)
    T = sub.fkine(q)
    a = c.ik_all(T, joint_limits=False)
    for backend in ("numpy", "casadi"):
        b = symkin.compile(sub, backend=backend).ik_all(T, joint_limits=False)
        np.testing.assert_allclose(np.nan_to_num(a, nan=9.0), np.nan_to_num(b, nan=9.0), atol=1e-12)
    rows = a.reshape(-1, 6)
    rows = rows[~np.isnan(rows[:, 0])]
    assert (
        len(rows)
        and np.abs(sub.fkine(rows) - np.repeat(T, 8, 0)[~np.isnan(a.reshape(-1, 6)[:, 0])]).max() < 1e-10
    )
