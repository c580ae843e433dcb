"""Closed-form IK (kin.ik_all, kin.ik(method="analytic")): every solution checked by the numeric
reference FK (Robot.fkine), branches checked against sampling with the numerical IK."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import Robot
from symkin.errors import ConfigurationError, NoAnalyticIKError, PoseError

EXACT = 1e-10


def _poses(robot, N, seed):
    Q = robot.random_q(N, seed=seed)
    return Q, robot.fkine(Q)


def _wrapdiff(a, b, rev):
    d = a - b
    return np.where(rev, np.remainder(d + np.pi, 2 * np.pi) - np.pi, d)


@pytest.mark.parametrize("name", ["ur5", "ur10", "puma560", "stanford", "planar2", "planar3"])
def test_every_solution_reproduces_the_pose(name):
    kin = symkin.compile(name)
    robot = kin.robot
    rev = np.array([e.is_revolute for e in robot.ets.joints])
    Q, T = _poses(robot, 60, 1)
    batch = kin.ik_all(T, joint_limits=False)
    assert batch.shape == (60, kin.analytic.max_solutions, robot.n)
    for q, Ti, rows in zip(Q, T, batch):
        sols = rows[~np.isnan(rows[:, 0])]
        assert np.isnan(rows[len(sols) :]).all()
        assert len(sols) >= 1
        assert np.abs(robot.fkine(sols) - Ti).max() <= EXACT
        assert (np.abs(_wrapdiff(sols, q, rev)).max(axis=1) < 1e-7).any(), "the generating q is missing"
        single = kin.ik_all(Ti, joint_limits=False)
        np.testing.assert_allclose(single, sols)


@pytest.mark.parametrize("name", ["ur5", "puma560"])
def test_no_branch_missed_against_sampling(name):
    kin = symkin.compile(name)
    robot = kin.robot
    rev = np.array([e.is_revolute for e in robot.ets.joints])
    _, T = _poses(robot, 12, 7)
    rng = np.random.default_rng(3)
    starts = 24
    res = kin.ik(np.repeat(T, starts, 0), q0=rng.uniform(-np.pi, np.pi, (12 * starts, 6)), slimit=1,
                 ilimit=60, tol=1e-12, joint_limits=False, seed=1)  # fmt: skip
    for i in range(12):
        sols = kin.ik_all(T[i], joint_limits=False)
        found = res.q[i * starts : (i + 1) * starts][res.success[i * starts : (i + 1) * starts]]
        assert len(found) > 0
        for q in found:
            assert (np.abs(_wrapdiff(sols, q, rev)).max(axis=1) < 1e-6).any(), f"pose {i}: branch missed"


@pytest.mark.parametrize("backend", ["numpy", "casadi"])
def test_python_backends_match_c(backend):
    c = symkin.compile("ur5")
    other = symkin.compile("ur5", backend=backend)
    _, T = _poses(c.robot, 5, 2)
    a, b = c.ik_all(T), other.ik_all(T)
    np.testing.assert_allclose(np.nan_to_num(a, nan=9.0), np.nan_to_num(b, nan=9.0), atol=1e-12)
    assert np.abs(c.robot.fkine(b[0][~np.isnan(b[0, :, 0])]) - T[0]).max() <= EXACT


def test_order_limits_and_weights():
    kin = symkin.compile("puma560")
    q = np.array([0.3, 0.7, -0.9, 0.4, 0.6, -0.2])
    T = kin.fkine(q)
    sols = kin.ik_all(T, q0=q)
    np.testing.assert_allclose(sols[0], q, atol=1e-9)
    d = ((sols - q) ** 2).sum(1)
    assert (np.diff(d) >= 0).all()
    assert kin.robot.within_limits(sols).all()
    free = kin.ik_all(T, joint_limits=False)
    assert len(free) >= len(sols)
    res = kin.ik(T, method="analytic", q0=q + 0.01)
    assert res.success and np.abs(res.q - q).max() < 1e-9 and res.residual < 1e-12


def test_ur_wraps_into_its_plus_minus_2pi_limits_near_q0():
    kin = symkin.compile("ur5")
    q = np.array([1.0, -2.0, 1.5, -0.5, 2.0, 3.0])
    q0 = q + np.array([-2 * np.pi, 0, 0, 0, 0, -2 * np.pi])  # same pose, other turns, within +-2 pi
    sols = kin.ik_all(kin.fkine(q), q0=q0)
    np.testing.assert_allclose(sols[0], q0, atol=1e-9)


def test_unreachable_pose_and_limits_reason():
    kin = symkin.compile("puma560")
    T = kin.fkine(np.zeros(6))
    T[0, 3] += 3.0
    assert kin.ik_all(T).shape == (0, 6)
    res = kin.ik(T, method="analytic")
    assert not res.success and "out of reach" in res.reason
    narrow = Robot(kin.robot.ets, name="puma_narrow", qlim=np.array([[-0.1] * 6, [0.1] * 6]))
    kn = symkin.compile(narrow)
    T2 = kn.fkine([1.0, 1.0, -1.0, 0.5, 0.5, 0.5])
    res = kn.ik(T2, method="analytic")
    assert not res.success and "outside the joint limits" in res.reason


@pytest.mark.parametrize(
    ("name", "q"),
    [
        ("ur5", [0.3, -1.0, 1.2, 0.4, 0.0, 0.5]),  # wrist singularity (q5 = 0)
        ("ur5", [0.3, -1.0, 0.0, 0.4, 1.0, 0.5]),  # elbow straight
        ("puma560", [0.3, 0.5, -0.4, 0.7, 0.0, 0.2]),  # wrist singularity
        ("puma560", [0.0, 0.0, -np.pi / 2, 0.0, 0.0, 0.0]),  # elbow straight, wrist singular
    ],
)
def test_singular_poses_give_finite_solutions(name, q):
    kin = symkin.compile(name)
    T = kin.fkine(np.array(q))
    sols = kin.ik_all(T, joint_limits=False)
    assert len(sols) >= 1 and np.isfinite(sols).all()
    assert np.abs(kin.robot.fkine(sols) - T).max() < 1e-6
    batch = kin.ik_all(T[None], joint_limits=False)
    assert np.isfinite(batch[0, : len(sols)]).all()


def test_errors():
    kin = symkin.compile("ur5")
    T = kin.fkine(np.zeros(6))
    with pytest.raises(PoseError):
        kin.ik_all(np.eye(3))
    with pytest.raises(PoseError):
        kin.ik_all(T * 2)
    with pytest.raises(ConfigurationError):
        kin.ik_all(T, q0=[1.0, 2.0])
    with pytest.raises(ConfigurationError):
        kin.ik_all(T, q0=[np.nan] * 6)
    with pytest.raises(TypeError, match="analytic"):
        kin.ik(T, method="analytic", slimit=3)
    panda = symkin.compile("panda")
    assert kin.has_analytic_ik and not panda.has_analytic_ik
    with pytest.raises(NoAnalyticIKError, match="7-joint"):
        panda.ik_all(panda.fkine(panda.robot.qr))


def test_float_model_solutions_reproduce_its_own_fk():
    from tests.symbolic.test_ik_geometry import _ur5_like

    robot = _ur5_like(1.5707963267948966, 1e-12)
    kin = symkin.compile(robot, backend="numpy")
    Q, T = _poses(robot, 10, 5)
    for Ti in T:
        sols = kin.ik_all(Ti, joint_limits=False)
        assert len(sols) and np.abs(robot.fkine(sols) - Ti).max() <= EXACT


def test_matches_eaik_when_installed():
    eaik = pytest.importorskip("eaik")
    assert eaik
    from symkin.bench.analytic_ik import _eaik_robot

    kin = symkin.compile("ur5")
    bot = _eaik_robot(kin.robot)
    rev = np.ones(6, bool)
    _, T = _poses(kin.robot, 10, 4)
    for Ti in T:
        sols = kin.ik_all(Ti, joint_limits=False)
        r = bot.calculate_IK(Ti)
        exact = [q for q, ls in zip(r.Q, r.is_LS) if not ls]
        assert len(exact) == len(sols)
        for q in exact:
            assert (np.abs(_wrapdiff(sols, np.asarray(q), rev)).max(axis=1) < 1e-8).any()
