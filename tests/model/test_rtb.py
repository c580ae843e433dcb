"""Importing roboticstoolbox-python robots and ETS (the ``compare`` extra; skipped without it): exact
constants, limits, configurations, base and tool carried over, FK equal to the toolbox's own."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import symkin
from symkin.errors import RobotError

rtb = pytest.importorskip("roboticstoolbox")
SE3 = pytest.importorskip("spatialmath").SE3


@pytest.fixture(autouse=True)
def _quiet():  # noqa: ANN202 - the toolbox warns about its own deprecations
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        yield


def test_panda_from_the_toolbox_has_its_limits_configs_and_fk() -> None:
    p = rtb.models.Panda()
    r = symkin.Robot.from_rtb(p)
    assert r.n == 7 and r.name == "panda"
    np.testing.assert_array_equal(r.qlim, p.qlim)
    np.testing.assert_allclose(r.qr, p.qr)
    assert "Rx(-pi/2)" in str(r.ets) and "Rz(-pi/4)" in str(r.ets)  # SE3 constants split and snapped
    assert "e-17" not in str(r.ets)  # no float noise survives
    np.testing.assert_allclose(r.qd_max, p.qdlim[:7])
    for q in r.random_q(20, seed=0):
        np.testing.assert_allclose(r.fkine(q), p.fkine(q).A, atol=1e-14)
        np.testing.assert_allclose(r.jacob0(q), p.jacob0(q), atol=1e-12)


def test_base_and_tool_of_the_robot_are_included() -> None:
    p = rtb.models.Panda()
    p.base = SE3(0.1, 0.2, 0.3) * SE3.Rz(0.5)
    p.tool = SE3.Rx(math.pi / 2) * SE3(0, 0, 0.1)
    r = symkin.Robot.from_rtb(p)
    assert str(r.ets).startswith("tx(0.1) ty(0.2) tz(0.3) Rz(0.5) tz(0.333)")
    for q in r.random_q(10, seed=1):
        np.testing.assert_allclose(r.fkine(q), p.fkine(q).A, atol=1e-14)


def test_dh_robot_with_its_configurations() -> None:
    pu = rtb.models.DH.Puma560()
    r = symkin.Robot.from_rtb(pu)
    assert set(r.configs) == {"qz", "qr", "qs", "qn"}
    assert "tz(0.67183)" in str(r.ets)  # 0.6718299999999999 in the toolbox: decimal noise snapped
    for q in r.random_q(10, seed=2):
        np.testing.assert_allclose(r.fkine(q), pu.fkine(q).A, atol=1e-14)


def test_an_ets_with_flips_prismatic_joints_and_joint_limits() -> None:
    E = rtb.ET.tz(0.333) * rtb.ET.Rz() * rtb.ET.Rx(math.pi / 2) * rtb.ET.Rz(flip=True) * rtb.ET.tx(0.1)
    E = E * rtb.ET.ty(qlim=[-0.5, 0.7])
    r = symkin.Robot.from_rtb(E)
    assert str(r.ets) == "tz(0.333) Rz(q0) Rx(pi/2) Rz(-q1) tx(0.1) ty(q2)"
    np.testing.assert_allclose(r.qlim[:, 2], [-0.5, 0.7])
    for q in r.random_q(10, seed=3):
        np.testing.assert_allclose(r.fkine(q), E.eval(q), atol=1e-15)


def test_a_planar_ets2() -> None:
    E = rtb.ET2.R() * rtb.ET2.tx(1) * rtb.ET2.R(flip=True) * rtb.ET2.tx(0.5)
    r = symkin.Robot.from_rtb(E)
    assert str(r.ets) == "Rz(q0) tx(1) Rz(-q1) tx(0.5)"
    q = np.array([0.2, -0.7])
    np.testing.assert_allclose(r.fkine(q)[np.ix_([0, 1, 3], [0, 1, 3])], E.eval(q), atol=1e-15)


def test_from_ets_points_at_from_rtb_and_names_the_full_type() -> None:
    with pytest.raises(RobotError, match=r"not roboticstoolbox\.ets\.ETS\.ETS; .*Robot\.from_rtb"):
        symkin.Robot.from_ets(rtb.models.Panda().ets())


def test_tool_given_as_toolbox_objects() -> None:
    r = symkin.load("ur5")
    a = r.with_tool(SE3.Rx(math.pi / 2) * SE3(0, 0, 0.1))
    b = r.with_tool(rtb.ET.Rx(math.pi / 2) * rtb.ET.tz(0.1))
    assert str(a.ets).endswith("ty(-0.1) Rx(pi/2)") and str(b.ets).endswith("Rx(pi/2) tz(0.1)")
    Q = r.random_q(5, seed=5)
    np.testing.assert_allclose(a.fkine(Q), b.fkine(Q), atol=1e-15)
    with pytest.raises(RobotError, match="constant"):
        r.with_tool(rtb.ET.Rz() * rtb.ET.tz(0.1))


def test_imported_robot_compiles_and_matches_the_toolbox() -> None:
    p = rtb.models.Panda()
    kin = symkin.compile(symkin.Robot.from_rtb(p), backend="c")
    for q in kin.robot.random_q(5, seed=4):
        np.testing.assert_allclose(kin.jacob0(q), p.jacob0(q), atol=1e-12)


def test_builtin_iiwa14_agrees_with_the_ros_industrial_urdf() -> None:
    """The toolbox's LBR is ROS-Industrial's lbr_iiwa_14_r820 URDF: same axes and zeros, and link
    origins within 0.44 mm (that URDF's x offsets of links 2 and 4) of KUKA's 360/420/400/126 mm."""
    urdf = symkin.Robot.from_rtb(rtb.models.LBR())
    ours = symkin.load("lbr_iiwa14")
    Q = ours.random_q(100, seed=6)
    Tu, To = urdf.fkine(Q), ours.fkine(Q)
    assert np.linalg.norm(Tu[:, :3, 3] - To[:, :3, 3], axis=1).max() < 1e-3
    np.testing.assert_allclose(Tu[:, :3, :3], To[:, :3, :3], atol=1e-12)
    np.testing.assert_allclose(urdf.qlim, ours.qlim, atol=5e-4)  # the URDF cuts 170 deg to 2.9668 rad


def test_builtin_cobra600_is_the_toolbox_model() -> None:
    tb = rtb.models.DH.Cobra600()
    ours = symkin.load("cobra600")
    for q in ours.random_q(20, seed=7):
        np.testing.assert_allclose(ours.fkine(q), tb.fkine(q).A, atol=1e-14)
