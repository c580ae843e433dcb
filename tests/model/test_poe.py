"""Product of exponentials (Lynch and Park, Modern Robotics): the published UR5 example, space/body
agreement, round trips
through every built-in robot, J_b = Ad_{T^-1} J_s, and rejected screws."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symkin.errors import RobotError
from symkin.model.poe import poe_of
from symkin.model.robot import Robot
from symkin.model.robots import list_robots, load


def skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0, -w[2], w[1]], [w[2], 0, -w[0]], [-w[1], w[0], 0]])


def adjoint(T: np.ndarray) -> np.ndarray:
    """Ad_T for twists ordered (omega, v) (Modern Robotics)."""
    R, p = T[:3, :3], T[:3, 3]
    return np.block([[R, np.zeros((3, 3))], [skew(p) @ R, R]])


def exp_twist(S: np.ndarray, theta: float) -> np.ndarray:
    """e^[S]theta in closed form (Modern Robotics, Prop. 3.25), S = (omega, v)."""
    w, v = S[:3], S[3:]
    T = np.eye(4)
    if np.linalg.norm(w) < 1e-12:
        T[:3, 3] = v * theta
        return T
    K = skew(w)
    T[:3, :3] = np.eye(3) + math.sin(theta) * K + (1 - math.cos(theta)) * K @ K
    G = np.eye(3) * theta + (1 - math.cos(theta)) * K + (theta - math.sin(theta)) * K @ K
    T[:3, 3] = G @ v
    return T


def poe_space(M: np.ndarray, S: np.ndarray, q: np.ndarray) -> np.ndarray:
    T = np.eye(4)
    for Si, qi in zip(S, q):
        T = T @ exp_twist(Si, qi)
    return T @ M


def poe_body(M: np.ndarray, B: np.ndarray, q: np.ndarray) -> np.ndarray:
    T = np.asarray(M, dtype=float)
    for Bi, qi in zip(B, q):
        T = T @ exp_twist(Bi, qi)
    return T


# Modern Robotics Example 4.5: the UR5 in its PoE zero pose.
L1, L2, W1, W2, H1, H2 = 0.425, 0.392, 0.109, 0.082, 0.089, 0.095
M_UR5 = np.array([[-1, 0, 0, L1 + L2], [0, 0, 1, W1 + W2], [0, 1, 0, H1 - H2], [0, 0, 0, 1]], dtype=float)
S_UR5 = np.array(
    [
        [0, 0, 1, 0, 0, 0],
        [0, 1, 0, -H1, 0, 0],
        [0, 1, 0, -H1, 0, L1],
        [0, 1, 0, -H1, 0, L1 + L2],
        [0, 0, -1, -W1, L1 + L2, 0],
        [0, 1, 0, H2 - H1, 0, L1 + L2],
    ],
    dtype=float,
)
B_UR5 = (adjoint(np.linalg.inv(M_UR5)) @ S_UR5.T).T


def test_ur5_example_matches_the_published_pose() -> None:
    r = Robot.from_poe(M_UR5, S_UR5)
    T = r.fkine([0, -math.pi / 2, 0, 0, math.pi / 2, 0])
    expected = np.array([[0, -1, 0, 0.095], [1, 0, 0, 0.109], [0, 0, 1, 0.988], [0, 0, 0, 1]])
    np.testing.assert_allclose(T, expected, atol=1e-12)


def test_axis_aligned_screws_become_single_ets() -> None:
    r = Robot.from_poe(M_UR5, S_UR5)
    assert len([e for e in r.ets if e.is_joint]) == 6
    assert "atan2" not in str(r.ets)
    assert str(r.ets).startswith("Rz(q0) tz(0.089) Ry(q1) tx(0.425) Ry(q2)")  # inverse constants merged
    assert "Rz(-q4)" in str(r.ets)  # omega = -z: a flipped joint


@pytest.mark.parametrize("frame", ["space", "body"])
def test_ur5_example_matches_the_matrix_exponential_product(frame: str) -> None:
    screws = S_UR5 if frame == "space" else B_UR5
    r = Robot.from_poe(M_UR5, screws, frame=frame)
    ref = poe_space if frame == "space" else poe_body
    for q in np.random.default_rng(7).uniform(-3, 3, (10, 6)):
        np.testing.assert_allclose(r.fkine(q), ref(M_UR5, screws, q), atol=1e-12)


def test_space_and_body_forms_agree() -> None:
    rs = Robot.from_poe(M_UR5, S_UR5, frame="space")
    rb = Robot.from_poe(M_UR5, B_UR5, frame="body")
    Q = np.random.default_rng(8).uniform(-3, 3, (20, 6))
    np.testing.assert_allclose(rs.fkine(Q), rb.fkine(Q), atol=1e-12)


def test_tilted_and_prismatic_screws() -> None:
    c = math.sqrt(0.5)
    p = np.array([0.1, -0.2, 0.3])
    w = np.array([0, c, c])
    S = np.array([np.r_[w, -np.cross(w, p)], [0, 0, 0, 0.6, 0, 0.8], [0, 0, 1, 0, 0, 0]])
    M = np.eye(4)
    M[:3, 3] = [0.5, 0, 0.2]
    r = Robot.from_poe(M, S)
    assert "Rx(pi/4) Ry(q0) Rx(-pi/4)" in str(r.ets)
    assert r.ets.structure == "RPR"
    for q in np.random.default_rng(9).uniform(-2, 2, (10, 3)):
        np.testing.assert_allclose(r.fkine(q), poe_space(M, S, q), atol=1e-12)


@pytest.mark.parametrize("name", list_robots())
def test_round_trip_through_the_space_and_body_screws_of_every_builtin(name: str) -> None:
    robot = load(name)
    M, S = poe_of(robot)
    B = (adjoint(np.linalg.inv(M)) @ S.T).T
    Q = robot.random_q(10, seed=10)
    for frame, screws in (("space", S), ("body", B)):
        r = Robot.from_poe(M, screws, frame=frame)
        np.testing.assert_allclose(r.fkine(Q), robot.fkine(Q), atol=1e-12)


def test_poe_about_a_nonzero_configuration() -> None:
    robot = load("panda")
    q0 = robot.qr
    M, S = poe_of(robot, q0)
    r = Robot.from_poe(M, S)
    dQ = np.random.default_rng(11).uniform(-1, 1, (10, 7))
    np.testing.assert_allclose(r.fkine(dQ), robot.fkine(q0 + dQ), atol=1e-12)


@pytest.mark.parametrize("frame", ["space", "body"])
def test_body_jacobian_is_the_adjoint_of_the_space_jacobian(frame: str) -> None:
    r = Robot.from_poe(M_UR5, S_UR5 if frame == "space" else B_UR5, frame=frame)
    np.testing.assert_allclose(r.jacobs(np.zeros(6)), S_UR5.T, atol=1e-12)  # J_s(0) = [S_1 ... S_n]
    np.testing.assert_allclose(r.jacobb(np.zeros(6)), B_UR5.T, atol=1e-12)
    for q in np.random.default_rng(12).uniform(-3, 3, (10, 6)):
        T = r.fkine(q)
        np.testing.assert_allclose(r.jacobb(q), adjoint(np.linalg.inv(T)) @ r.jacobs(q), atol=1e-12)


def test_body_jacobian_adjoint_relation_with_flipped_and_prismatic_joints() -> None:
    for name in ("panda", "stanford"):
        M, S = poe_of(load(name))
        r = Robot.from_poe(M, S)
        for q in r.random_q(5, seed=13):
            T = r.fkine(q)
            np.testing.assert_allclose(r.jacobb(q), adjoint(np.linalg.inv(T)) @ r.jacobs(q), atol=1e-12)


@pytest.mark.parametrize(
    "M, S, kwargs, words",
    [
        (np.eye(4), [[0, 0, 1, 0.1, 0, 0.2]], {}, ["screw 0", "helical", "pitch", "0.2"]),
        (np.eye(4), [[0, 0, 1, 0, 0, 0], [0, 0, 2, 0, 0, 0]], {}, ["screw 1", "|omega| = 2", "unit omega"]),
        (np.eye(4), [[0, 0, 0, 0, 0, 2]], {}, ["screw 0", "prismatic", "|v| = 2", "unit v"]),
        (np.eye(4), [[0, 0, 0, 0, 0, 0]], {}, ["screw 0", "|v| = 0"]),
        (np.eye(4), [[0, 0, 1, 0, 0]], {}, ["shape (n, 6)", "(1, 5)"]),
        (np.eye(4), [[0, 0, float("nan"), 0, 0, 0]], {}, ["screws[0, 2]", "finite"]),
        (np.eye(3), [[0, 0, 1, 0, 0, 0]], {}, ["M must be a 4x4"]),
        (2 * np.eye(4), [[0, 0, 1, 0, 0, 0]], {}, ["bottom row"]),
        (np.diag([1, 1, -1, 1]), [[0, 0, 1, 0, 0, 0]], {}, ["M rotation is a reflection"]),
        (np.eye(4), [[0, 0, 1, 0, 0, 0]], {"frame": "world"}, ["'world'", "'space'", "'body'"]),
    ],
)
def test_bad_poe_input_raises_an_actionable_error(
    M: object, S: object, kwargs: dict, words: list[str]
) -> None:
    with pytest.raises(RobotError) as info:
        Robot.from_poe(M, S, **kwargs)
    for w in words:
        assert w in str(info.value)
