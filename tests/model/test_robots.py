"""Built-in robots: published zero poses, independent FK formulas, and the numeric reference
Jacobian/Hessian checked against finite differences on every robot."""

from __future__ import annotations

import math

import numpy as np
import pytest

from symkin.errors import UnknownRobotError
from symkin.model.dh import DHLink
from symkin.model.robot import Robot
from symkin.model.robots import list_robots, load

REQUIRED = [
    "panda",
    "ur3",
    "ur5",
    "ur10",
    "puma560",
    "lbr_iiwa7",
    "lbr_iiwa14",
    "sawyer",
    "planar2",
    "planar3",
    "stanford",
    "cobra600",
    "gantry",
]


def pose(R: list[list[float]], t: list[float]) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = t
    return T


I3 = np.eye(3).tolist()
RX90 = [[1, 0, 0], [0, 0, -1], [0, 1, 0]]  # Rx(pi/2)
RXPI = [[1, 0, 0], [0, -1, 0], [0, 0, -1]]
S2 = math.sqrt(0.5)

# Zero poses worked out by hand from the published parameters (comments give the reasoning).
ZERO_POSES = {
    # UR standard DH at q = 0: x = a2 + a3, y = -(d4 + d6), z = d1 - d5, R = Rx(pi/2)
    "ur5": pose(RX90, [-0.425 - 0.39225, -(0.10915 + 0.0823), 0.089159 - 0.09465]),
    "ur3": pose(RX90, [-0.24365 - 0.21325, -(0.11235 + 0.0819), 0.1519 - 0.08535]),
    "ur10": pose(RX90, [-0.612 - 0.5723, -(0.163941 + 0.0922), 0.1273 - 0.1157]),
    # Corke's Puma 560 at qz: (a2 + a3, -d3, d4) = (0.4521, -0.15005, 0.4318), R = I
    "puma560": pose(I3, [0.4521, -0.15005, 0.4318]),
    # Panda (Fig. 1 of Manipulator Differential Kinematics, Part 1) at qz: x = 0.0825 - 0.0825 + 0.088,
    # z = 0.333 + 0.316 + 0.384 - 0.107 - 0.1034,
    # R = Rx(pi) Rz(-pi/4)
    "panda": pose(
        [[S2, S2, 0], [S2, -S2, 0], [0, 0, -1]], [0.088, 0, 0.333 + 0.316 + 0.384 - 0.107 - 0.1034]
    ),
    # LBR iiwa: straight up, z = 0.34 + 0.4 + 0.4 + 0.126 (iiwa 7), 0.36 + 0.42 + 0.4 + 0.126 (iiwa 14)
    "lbr_iiwa7": pose(I3, [0, 0, 1.266]),
    "lbr_iiwa14": pose(I3, [0, 0, 1.306]),
    # Sawyer at the URDF's zero: the arm stretched out along x, x = a1 + d3 + d5 + d7, y = d2 - d4 + d6,
    # z = d1; the tool axis along x
    "sawyer": pose(
        [[0, 0, 1], [-1, 0, 0], [0, -1, 0]], [0.081 + 0.4 + 0.4 + 0.13375, 0.1925 - 0.1685 + 0.1363, 0.317]
    ),
    # Cobra 600 SCARA: links along x (0.325 + 0.275), flange at the height of joint 2, tool z down
    "cobra600": pose([[1, 0, 0], [0, -1, 0], [0, 0, -1]], [0.6, 0, 0.387]),
    "gantry": pose(I3, [0, 0, 0]),
    # Stanford at q = 0 (d3 = 0): y = d2 - a3, z = d1 + d6, R = Rz(-pi/2)
    "stanford": pose([[0, 1, 0], [-1, 0, 0], [0, 0, 1]], [0, 0.154 - 0.0203, 0.412 + 0.263]),
    "planar2": pose(I3, [2, 0, 0]),
    "planar3": pose(I3, [3, 0, 0]),
}


def test_every_required_robot_is_listed_and_loads() -> None:
    names = list_robots()
    assert set(REQUIRED) <= set(names)
    assert names == sorted(names)
    for name in names:
        r = load(name)
        assert isinstance(r, Robot)
        assert r.name == name and name.isidentifier() and name == name.lower()
        assert r.source, f"{name} has no source"
        assert r.qlim.shape == (2, r.n)
        assert "qz" in r.configs and np.all(r.qz == 0)
        if r.qd_max is not None:
            assert r.qd_max.shape == (r.n,) and (r.qd_max > 0).all()


def test_load_is_case_insensitive_and_cached() -> None:
    assert load("UR5") is load("ur5")
    assert load(" LBR-iiwa7 ") is load("lbr_iiwa7")


@pytest.mark.parametrize("bad, hint", [("pandaa", "'panda'"), ("ur7", "'ur"), ("puma", "'puma560'")])
def test_unknown_robot_names_the_close_matches_and_lists_all(bad: str, hint: str) -> None:
    with pytest.raises(UnknownRobotError) as info:
        load(bad)
    msg = str(info.value)
    assert repr(bad) in msg and "did you mean" in msg and hint in msg
    for name in REQUIRED:
        assert name in msg


def test_unknown_robot_is_a_key_error() -> None:
    with pytest.raises(KeyError):
        load("nonexistent_robot_xyz")


@pytest.mark.parametrize("name", sorted(ZERO_POSES))
def test_zero_pose_matches_the_hand_computed_pose(name: str) -> None:
    r = load(name)
    np.testing.assert_allclose(r.fkine(r.qz), ZERO_POSES[name], atol=1e-12)


def test_ur5_zero_pose_tool_position_from_the_published_dh() -> None:
    np.testing.assert_allclose(
        load("ur5").fkine(np.zeros(6))[:3, 3], [-0.81725, -0.19145, -0.005491], atol=1e-12
    )


def test_puma560_ready_and_stretched_poses() -> None:
    p = load("puma560")
    # qr: arm straight up, z = a2 + d4, x = a3 (Corke, 'Robotics, Vision and Control')
    np.testing.assert_allclose(p.fkine(p.qr)[:3, 3], [0.0203, -0.15005, 0.8636], atol=1e-12)
    # qs: arm stretched along x: x = a2 + d4, z = -a3
    np.testing.assert_allclose(p.fkine(p.qs)[:3, 3], [0.4318 + 0.4318, -0.15005, -0.0203], atol=1e-12)
    assert p.within_limits(p.qn) and p.within_limits(p.qr)


def test_planar_arms_match_the_textbook_closed_form() -> None:
    rng = np.random.default_rng(4)
    for n in (2, 3):
        r = load(f"planar{n}")
        Q = rng.uniform(-np.pi, np.pi, (20, n))
        c = np.cumsum(Q, axis=1)
        T = r.fkine(Q)
        np.testing.assert_allclose(T[:, 0, 3], np.cos(c).sum(axis=1), atol=1e-12)  # l1 c1 + l2 c12 + l3 c123
        np.testing.assert_allclose(T[:, 1, 3], np.sin(c).sum(axis=1), atol=1e-12)
        np.testing.assert_allclose(T[:, 2, 3], 0, atol=1e-12)
        np.testing.assert_allclose(
            np.arctan2(T[:, 1, 0], T[:, 0, 0]), np.angle(np.exp(1j * c[:, -1])), atol=1e-12
        )


def test_panda_matches_the_rtb_form_of_its_ets() -> None:
    # Corke's RTB Panda written with Rx(+-90deg) conjugations instead of Ry joints and flipped joints
    rtb = Robot.from_ets(
        "tz(0.333) Rz(q) Rx(-pi/2) Rz(q) Rx(pi/2) tz(0.316) Rz(q) tx(0.0825) Rx(pi/2) Rz(q) tx(-0.0825) "
        "Rx(-pi/2) tz(0.384) Rz(q) Rx(pi/2) Rz(q) tx(0.088) Rx(pi/2) tz(0.107) Rz(q) tz(0.1034) Rz(-pi/4)"
    )
    p = load("panda")
    Q = p.random_q(20, seed=0)
    np.testing.assert_allclose(p.fkine(Q), rtb.fkine(Q), atol=1e-12)
    assert sum(e.flip for e in p.ets) == 2  # E7 and E11 of Fig. 1


def test_stanford_has_a_prismatic_third_joint() -> None:
    s = load("stanford")
    assert s.ets.structure == "RRPRRR"
    q = np.zeros(6)
    q[2] = 0.5
    # at q1 = q2 = 0 the prismatic joint moves along the base z axis (Rx(-pi/2) Rx(pi/2) Rz(-pi/2) keeps z)
    np.testing.assert_allclose(s.fkine(q)[:3, 3] - s.fkine(np.zeros(6))[:3, 3], [0, 0, 0.5], atol=1e-12)


# ---------------------------------------------------------------------------------------------
# The numeric reference kinematics (symkin/model/kinematics.py) against finite differences.
# Central differences with step H; the truncation error is O(H^2) ~ 1e-12 and rounding ~ 1e-10.

H = 1e-6
TOL = 1e-7


def vee(S: np.ndarray) -> np.ndarray:
    return np.array([S[2, 1] - S[1, 2], S[0, 2] - S[2, 0], S[1, 0] - S[0, 1]]) / 2


def fd_jacob0(r: Robot, q: np.ndarray) -> np.ndarray:
    """Base-frame Jacobian (rows v, omega) from central differences of FK: omega = vee(dR R^T)."""
    n = r.n
    E = np.eye(n) * H
    Tp, Tm = r.fkine(q + E), r.fkine(q - E)  # (n, 4, 4)
    R = r.fkine(q)[:3, :3]
    J = np.empty((6, n))
    for i in range(n):
        J[:3, i] = (Tp[i, :3, 3] - Tm[i, :3, 3]) / (2 * H)
        J[3:, i] = vee((Tp[i, :3, :3] - Tm[i, :3, :3]) / (2 * H) @ R.T)
    return J


@pytest.mark.parametrize("name", REQUIRED)
def test_jacobian_matches_finite_differences_of_fk(name: str) -> None:
    r = load(name)
    for q in r.random_q(4, seed=11):
        np.testing.assert_allclose(r.jacob0(q), fd_jacob0(r, q), atol=TOL, rtol=0)


@pytest.mark.parametrize("name", REQUIRED)
def test_hessian_matches_finite_differences_of_the_jacobian(name: str) -> None:
    r = load(name)
    n = r.n
    E = np.eye(n) * H
    for q in r.random_q(4, seed=12):
        fd = (r.jacob0(q + E) - r.jacob0(q - E)) / (2 * H)  # (n, 6, n): dJ/dq_i
        np.testing.assert_allclose(r.hessian0(q), fd, atol=TOL, rtol=0)


@pytest.mark.parametrize("name", REQUIRED)
def test_end_effector_jacobian_and_hessian_match_finite_differences(name: str) -> None:
    r = load(name)
    n = r.n
    E = np.eye(n) * H
    for q in r.random_q(2, seed=13):
        R = r.fkine(q)[:3, :3]
        Je = np.vstack((R.T @ fd_jacob0(r, q)[:3], R.T @ fd_jacob0(r, q)[3:]))
        np.testing.assert_allclose(r.jacobe(q), Je, atol=TOL, rtol=0)
        fd = (r.jacobe(q + E) - r.jacobe(q - E)) / (2 * H)
        np.testing.assert_allclose(r.hessiane(q), fd, atol=TOL, rtol=0)


@pytest.mark.parametrize("name", REQUIRED)
def test_batched_kinematics_equal_the_single_configuration_results(name: str) -> None:
    r = load(name)
    Q = r.random_q(3, seed=14)
    np.testing.assert_allclose(r.fkine(Q), np.stack([r.fkine(q) for q in Q]), atol=1e-14)
    np.testing.assert_allclose(r.jacob0(Q), np.stack([r.jacob0(q) for q in Q]), atol=1e-14)
    np.testing.assert_allclose(r.hessian0(Q), np.stack([r.hessian0(q) for q in Q]), atol=1e-14)


def test_descriptions_name_sources_not_internal_labels() -> None:
    for name in list_robots():
        src = load(name).source.lower()
        assert "seed" not in src and " lab " not in src, (name, src)
    assert "c123" not in load("planar2").source and "c12" in load("planar2").source
    assert "c123" in load("planar3").source


def test_sawyer_joint_values_are_the_robots_own() -> None:
    """The DH table of Corke's toolbox with Rethink's joint zeros and directions: theta_1 = q_1 - pi/2,
    theta_3 = pi - q_3, theta_5 = q_5 + pi, theta_6 = q_6 + pi/2 (independent construction)."""
    a = [0.081, 0, 0, 0, 0, 0, 0]
    d = [0.317, 0.1925, 0.4, 0.1685, 0.4, 0.1363, 0.13375]
    dh = Robot.from_dh([DHLink(d=d[j], a=a[j], alpha=-math.pi / 2 if j < 6 else 0) for j in range(7)])
    s = load("sawyer")
    Q = s.random_q(20, seed=3)
    theta = Q * [1, 1, 1, -1, 1, 1, 1] + [0, -math.pi / 2, 0, math.pi, 0, math.pi, math.pi / 2]
    np.testing.assert_allclose(s.fkine(Q), dh.fkine(theta), atol=1e-12)
    # Rethink's published limits (rad), not +-pi
    np.testing.assert_allclose(s.qlim[:, 1], [-3.8095, 2.2736])
    np.testing.assert_allclose(s.qlim[1, [0, 6]], [3.0503, 4.7124])


def test_scara_moves_in_the_plane_and_its_quill_down() -> None:
    r = load("cobra600")
    assert r.ets.structure == "RRPR"
    for q in r.random_q(10, seed=4):
        T = r.fkine(q)
        c1, c12 = math.cos(q[0]), math.cos(q[0] + q[1])
        s1, s12 = math.sin(q[0]), math.sin(q[0] + q[1])
        np.testing.assert_allclose(
            T[:3, 3], [0.325 * c1 + 0.275 * c12, 0.325 * s1 + 0.275 * s12, 0.387 - q[2]]
        )
        np.testing.assert_allclose(T[:3, 2], [0, 0, -1], atol=1e-12)  # the tool always points down


def test_gantry_joints_are_the_tool_position() -> None:
    r = load("gantry")
    assert r.ets.structure == "PPP"
    Q = r.random_q(10, seed=5)
    np.testing.assert_allclose(r.fkine(Q)[:, :3, 3], Q, atol=1e-15)
    np.testing.assert_allclose(r.jacob0(Q[0]), np.vstack((np.eye(3), np.zeros((3, 3)))))
    np.testing.assert_allclose(r.qlim, [[0, 0, 0], [0.3, 0.25, 0.035]])
