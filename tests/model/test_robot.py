"""The Robot model and its numeric reference: shapes, batches, bad input, frames, Modern Robotics
Jacobians."""

from __future__ import annotations

import numpy as np
import pytest

from symkin import ConfigurationError, Robot, RobotError
from symkin.model.robots import load


@pytest.fixture(scope="module")
def panda() -> Robot:
    return load("panda")


@pytest.mark.parametrize(
    ("method", "shape"),
    [("fkine", (4, 4)), ("jacob0", (6, 7)), ("jacobe", (6, 7)), ("hessian0", (7, 6, 7)),
     ("hessiane", (7, 6, 7)), ("jacobs", (6, 7)), ("jacobb", (6, 7)), ("link_poses", (7, 4, 4)),
     ("jacobm", (7,))],
)  # fmt: skip
def test_shapes_single_and_batched(panda, method, shape):
    f = getattr(panda, method)
    q = panda.random_q(seed=0)
    assert f(q).shape == shape
    Q = panda.random_q(3, seed=1)
    out = f(Q)
    assert out.shape == (3, *shape)
    np.testing.assert_allclose(out[1], f(Q[1]), atol=1e-15)
    assert f(Q[:1]).shape == (1, *shape)


@pytest.mark.parametrize(
    ("q", "message"),
    [
        ([0.0] * 6, r"shape \(7,\) or \(N, 7\).*got shape \(6,\)"),
        (np.zeros((2, 3)), r"got shape \(2, 3\)"),
        (np.zeros((2, 2, 7)), "got shape"),
        ([0, 0, 0, np.nan, 0, 0, 0], r"q\[3\] is nan"),
        (np.array([[0] * 7, [0, 0, 0, 0, 0, np.inf, 0]]), r"q\[1, 5\] is inf"),
        ("abc", "must be an array of 7 numbers"),
        (3.0, "got shape ()"),
    ],
)
def test_bad_q_gets_a_clear_error(panda, q, message):
    for method in (panda.fkine, panda.jacob0, panda.hessian0, panda.manipulability):
        with pytest.raises(ConfigurationError, match=message):
            method(q)


def test_limits_and_named_configurations(panda):
    assert panda.qlim.shape == (2, 7) and (panda.qlim[0] < panda.qlim[1]).all()
    np.testing.assert_array_equal(panda.qz, np.zeros(7))
    assert panda.qr.shape == (7,)
    assert panda.within_limits(panda.qr)
    Q = panda.random_q(50, seed=2)
    assert panda.within_limits(Q).all()
    with pytest.raises(ConfigurationError, match="outside its limits"):
        panda.check_q(panda.qlim[1] + 0.1, limits=True)
    with pytest.raises(AttributeError, match="configurations"):
        panda.qnope  # noqa: B018


def test_robot_validation():
    ets = "Rz(q0) tx(1) Rz(q1) tx(1)"
    with pytest.raises(RobotError, match=r"shape \(2, 2\)"):
        Robot.from_ets(ets, qlim=[[0, 0, 0], [1, 1, 1]])
    with pytest.raises(RobotError, match="lower > upper"):
        Robot.from_ets(ets, qlim=[[1, 0], [0, 1]])
    with pytest.raises(RobotError, match="configuration"):
        Robot.from_ets(ets, configs={"qr": [0.0]})
    with pytest.raises(RobotError, match="unique"):
        Robot.from_ets(ets, joint_names=("a", "a"))


def test_link_poses_end_at_the_last_joint_frame(panda):
    q = panda.random_q(seed=3)
    links = panda.link_poses(q)
    # the last link frame (after Rz(q6)) is followed only by constants: tz(0.1034) Rz(-pi/4)
    tail = Robot.from_ets("Rz(q0) tz(0.1034) Rz(-pi/4)").fkine([0.0])
    np.testing.assert_allclose(links[-1] @ tail, panda.fkine(q), atol=1e-14)
    # the first link frame is tz(0.333) Rz(q0)
    np.testing.assert_allclose(links[0], Robot.from_ets("tz(0.333) Rz(q0)").fkine(q[:1]), atol=1e-15)


def test_space_and_body_jacobians_are_related_by_the_adjoint(panda):
    """Modern Robotics: J_b = [Ad_{T^-1}] J_s, twists ordered (omega, v)."""
    for seed in range(5):
        q = panda.random_q(seed=seed)
        T = panda.fkine(q)
        Ti = np.linalg.inv(T)
        R, p = Ti[:3, :3], Ti[:3, 3]
        px = np.array([[0, -p[2], p[1]], [p[2], 0, -p[0]], [-p[1], p[0], 0]])
        Ad = np.block([[R, np.zeros((3, 3))], [px @ R, R]])
        np.testing.assert_allclose(Ad @ panda.jacobs(q), panda.jacobb(q), atol=1e-13)
        np.testing.assert_allclose(panda.jacobb(q)[:3], panda.jacobe(q)[3:], atol=1e-15)


def test_manipulability_and_condition_number(panda):
    q = panda.random_q(seed=4)
    J = panda.jacob0(q)
    assert panda.manipulability(q) == pytest.approx(np.sqrt(np.linalg.det(J @ J.T)), rel=1e-12)
    s = np.linalg.svd(J[:3], compute_uv=False)
    assert panda.cond(q, axes="trans") == pytest.approx(s[0] / s[-1], rel=1e-12)
    planar = load("planar2")
    assert planar.manipulability([0.0, 0.0], axes="trans") == pytest.approx(0.0, abs=1e-15)
    assert planar.cond([0.3, 0.0], axes="trans") == np.inf  # 2 joints cannot span 3 directions
    assert np.isfinite(planar.jacobm([0.0, 0.0], axes="trans")).all()  # singular: finite, not NaN
    with pytest.raises(ValueError, match="axes must be one of"):
        panda.manipulability(q, axes="xyz")


def test_manipulability_jacobian_matches_finite_differences(panda):
    for axes in ("all", "trans", "rot"):
        q = panda.random_q(seed=5)
        h = 1e-6
        fd = [(panda.manipulability(q + h * e, axes) - panda.manipulability(q - h * e, axes)) / (2 * h)
              for e in np.eye(7)]  # fmt: skip
        np.testing.assert_allclose(panda.jacobm(q, axes), fd, atol=1e-8)


def test_reference_jacobian_handles_joints_out_of_chain_order():
    a = Robot.from_ets("Rz(q1) tx(0.5) Ry(q0) tz(0.3) tx(q2)")
    b = Robot.from_ets("Rz(q0) tx(0.5) Ry(q1) tz(0.3) tx(q2)")
    q = np.array([0.3, -0.7, 0.2])
    np.testing.assert_allclose(a.fkine(q[[1, 0, 2]]), b.fkine(q), atol=1e-15)
    np.testing.assert_allclose(a.jacob0(q[[1, 0, 2]])[:, [1, 0, 2]], b.jacob0(q), atol=1e-15)
    Ha, Hb = a.hessian0(q[[1, 0, 2]]), b.hessian0(q)
    np.testing.assert_allclose(Ha[[1, 0, 2]][:, :, [1, 0, 2]], Hb, atol=1e-15)


def test_random_q_stays_usable_when_limits_are_huge_or_infinite():
    # URDFs write "no limit" as 1e16 or 1.7e308; q beyond +-1e15 is refused, so sampling must not go there
    import symkin
    from symkin.runtime.ik import sample_range

    big = 1.7976931348623157e308
    robot = symkin.Robot.from_ets("Rz(q) tx(1) tz(q) Rz(q)", qlim=[[-big, -np.inf, -1e16], [big, 0.5, 2.0]])
    Q = robot.random_q(2000, seed=1)
    assert np.abs(Q[:, 0]).max() <= np.pi and Q[:, 0].min() < -3 and Q[:, 0].max() > 3  # +-pi
    assert Q[:, 1].min() >= 0.5 - 2.0 and Q[:, 1].max() <= 0.5  # 2 m below the finite bound
    assert Q[:, 2].min() >= 2.0 - 2 * np.pi and Q[:, 2].max() <= 2.0  # one turn below
    assert robot.fkine(Q).shape == (2000, 4, 4)  # usable: within +-1e15
    lo, hi = sample_range(robot.qlim, np.array([True, False, True]))
    assert np.allclose(lo, [-np.pi, 0.5 - 2.0, 2.0 - 2 * np.pi]) and np.allclose(hi, [np.pi, 0.5, 2.0])
    tree_xml = (
        '<robot name="t"><link name="a"/><link name="b"/><link name="c"/>'
        '<joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/>'
        '<limit lower="-1e300" upper="1e300" velocity="1" effort="1"/></joint>'
        '<joint name="k" type="prismatic"><parent link="b"/><child link="c"/><axis xyz="1 0 0"/>'
        '<limit lower="-3e16" upper="0.2" velocity="1" effort="1"/></joint></robot>'
    )
    tree = symkin.Tree.from_urdf(tree_xml)
    Q = tree.random_q(500, seed=2)
    assert np.abs(Q[:, 0]).max() <= np.pi and Q[:, 1].min() >= 0.2 - 2.0 and Q[:, 1].max() <= 0.2
    assert tree.fkine_all(Q).shape == (500, 1, 4, 4)
