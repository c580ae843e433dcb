"""The CasADi examples converge and their solutions satisfy the constraints, checked against the
numeric reference ``robot.fkine`` (not the CasADi functions the examples optimise with)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path
from types import ModuleType

import numpy as np
import pytest

import symkin

pytest.importorskip("casadi")

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
TOL = 1e-8


def load_example(name: str) -> ModuleType:
    spec = importlib.util.spec_from_file_location(f"symkin_example_{name}", EXAMPLES / f"{name}.py")
    assert spec is not None and spec.loader is not None
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while the class is built
    spec.loader.exec_module(module)
    return module


@pytest.fixture(scope="module")
def ik_nlp() -> ModuleType:
    return load_example("ik_nlp_casadi")


@pytest.fixture(scope="module")
def trajectory() -> ModuleType:
    return load_example("trajectory_casadi")


def pose_error(robot: symkin.Robot, q: np.ndarray, T_target: np.ndarray) -> tuple[float, float]:
    """Position (m) and angle (rad) error from the numeric reference fkine."""
    T = robot.fkine(q)
    E = T_target[:3, :3].T @ T[:3, :3]
    s = np.linalg.norm([E[2, 1] - E[1, 2], E[0, 2] - E[2, 0], E[1, 0] - E[0, 1]]) / 2
    return float(np.linalg.norm(T[:3, 3] - T_target[:3, 3])), float(np.arctan2(s, (np.trace(E) - 1) / 2))


def within(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> bool:
    return bool(np.all(x >= lo - TOL) and np.all(x <= hi + TOL))


# -- IK as an NLP -----------------------------------------------------------------------------


def test_ik_nlp_reaches_the_pose_within_limits_and_raises_manipulability(ik_nlp: ModuleType) -> None:
    robot = symkin.load("panda")
    kin = symkin.compile(robot, backend="casadi")
    problem = ik_nlp.build_ik_nlp(kin)
    rng = np.random.default_rng(7)
    for i in range(3):
        T_target = robot.fkine(robot.random_q(seed=rng))
        num = ik_nlp.numerical_ik(kin, T_target, seed=i)
        if num is not None:  # compare with symkin's numerical IK and start from its solution
            assert num.success
            q0 = num.q
        else:  # no numerical IK in this symkin: start near a configuration reaching the target
            q0 = robot.random_q(seed=i)
        sol = ik_nlp.solve_ik_nlp(problem, T_target, q0)
        assert sol.success, sol.status
        assert within(sol.q, *robot.qlim)
        dp, dang = pose_error(robot, sol.q, T_target)
        assert dp < 1e-8 and dang < 1e-8, (dp, dang)
        assert sol.manipulability == pytest.approx(robot.manipulability(sol.q))
        if num is not None:  # redundant arm: moving along the self-motion only raises m
            assert sol.manipulability >= robot.manipulability(num.q) - 1e-9


def test_ik_nlp_from_a_nearby_start_on_a_six_joint_arm(ik_nlp: ModuleType) -> None:
    robot = symkin.load("ur5")
    problem = ik_nlp.build_ik_nlp(symkin.compile(robot, backend="casadi"))
    q_goal = robot.qr + np.array([0.3, -0.2, 0.25, -0.1, 0.2, 0.3])
    T_target = robot.fkine(q_goal)
    sol = ik_nlp.solve_ik_nlp(problem, T_target, robot.qr)
    assert sol.success, sol.status
    dp, dang = pose_error(robot, sol.q, T_target)
    assert dp < 1e-8 and dang < 1e-8


def test_ik_example_main_runs_small(ik_nlp: ModuleType, capsys: pytest.CaptureFixture[str]) -> None:
    rows = ik_nlp.main("panda", small=True)
    assert len(rows) == 2 and all(row["nlp"].success for row in rows)
    assert "nlp" in capsys.readouterr().out


# -- trajectory / MPC -------------------------------------------------------------------------


@pytest.mark.parametrize("name", ["ur5", "panda"])
def test_trajectory_satisfies_dynamics_and_limits_and_reaches_the_target(
    trajectory: ModuleType, name: str
) -> None:
    robot = symkin.load(name)
    problem = trajectory.build_trajectory(symkin.compile(robot, backend="casadi"), horizon=6, dt=0.1)
    q_start = robot.qr
    T_target = trajectory.reachable_target(robot, q_start, spread=0.3, seed=1)
    traj = trajectory.solve_trajectory(problem, q_start, T_target)
    assert traj.success, traj.status
    assert traj.q.shape == (7, robot.n) and traj.qd.shape == (6, robot.n)
    np.testing.assert_allclose(traj.q[0], q_start, atol=TOL)
    np.testing.assert_allclose(traj.q[1:], traj.q[:-1] + 0.1 * traj.qd, atol=TOL)  # q_{k+1} = q_k + dt qd_k
    assert within(traj.q, *robot.qlim)
    assert within(traj.qd, -robot.qd_max, robot.qd_max)
    dp, dang = pose_error(robot, traj.q[-1], T_target)
    assert dp < 1e-4 and dang < 1e-4, (dp, dang)
    assert (dp, dang) == pytest.approx((traj.position_error, traj.angle_error), abs=1e-12)


def test_mpc_closed_loop_stays_feasible_and_approaches_the_target(trajectory: ModuleType) -> None:
    robot = symkin.load("ur5")
    problem = trajectory.build_trajectory(symkin.compile(robot, backend="casadi"), horizon=5, dt=0.1)
    q_start = robot.qr
    T_target = trajectory.reachable_target(robot, q_start, spread=0.4, seed=2)
    qs, qds, solves = trajectory.run_mpc(problem, q_start, T_target, steps=4)
    assert all(s.success for s in solves)
    assert qs.shape == (5, robot.n) and qds.shape == (4, robot.n)
    np.testing.assert_allclose(qs[1:], qs[:-1] + 0.1 * qds, atol=1e-12)
    assert within(qs, *robot.qlim) and within(qds, -robot.qd_max, robot.qd_max)
    errors = [sum(pose_error(robot, q, T_target)) for q in qs]
    assert errors[-1] < 0.5 * errors[0]


def test_trajectory_example_main_runs_small(
    trajectory: ModuleType, capsys: pytest.CaptureFixture[str]
) -> None:
    out = trajectory.main("panda", small=True)
    assert out["trajectory"].success and len(out["mpc_solves"]) == 3
    assert "MPC" in capsys.readouterr().out
