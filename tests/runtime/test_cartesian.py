"""Cartesian paths (ctraj) and resolved-rate tracking of a Cartesian path (servo_path).

Independent checks always run (endpoints, straight lines, geodesic rotations, the tracking error);
the comparisons with roboticstoolbox-python run only where it is installed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin.errors import ConfigurationError, ParameterError, PoseError
from symkin.runtime.cartesian import PathResult, ctraj, servo_path
from symkin.runtime.ik import angle_axis
from symkin.runtime.trajectory import trapezoidal
from tests.runtime.rotations import geodesic_angle, pose, rot

# -- ctraj --------------------------------------------------------------------------------------
T0 = pose(rot([1, 2, 3], 0.4), [0.3, -0.2, 0.5])
T1 = pose(rot([-1, 0.5, 2], 1.1) @ rot([1, 2, 3], 0.4), [0.1, 0.4, 0.2])


def test_ctraj_endpoints_linear_positions_and_geodesic_rotations():
    s = np.linspace(0, 1, 21)
    P = ctraj(T0, T1, s=s)
    assert P.shape == (21, 4, 4)
    np.testing.assert_array_equal(P[0], T0)
    np.testing.assert_array_equal(P[-1], T1)
    np.testing.assert_array_equal(P[:, 3], np.tile([0, 0, 0, 1.0], (21, 1)))
    np.testing.assert_allclose(P[:, :3, 3], (1 - s)[:, None] * T0[:3, 3] + s[:, None] * T1[:3, 3], atol=1e-15)
    R = P[:, :3, :3]
    np.testing.assert_allclose(R @ np.swapaxes(R, 1, 2), np.tile(np.eye(3), (21, 1, 1)), atol=1e-14)
    np.testing.assert_allclose(np.linalg.det(R), 1.0, atol=1e-14)
    # geodesic: equal angles between consecutive rotations, about one fixed axis, adding up to the total
    total = geodesic_angle(T0[:3, :3], T1[:3, :3])
    steps = geodesic_angle(R[:-1], R[1:])
    np.testing.assert_allclose(steps, total / 20, rtol=1e-9)
    np.testing.assert_allclose(geodesic_angle(T0[:3, :3], R), s * total, atol=1e-12)
    axes = angle_axis(R[1:] @ np.swapaxes(R[:-1], 1, 2))
    axis = np.array([-1, 0.5, 2]) / np.linalg.norm([-1, 0.5, 2])
    np.testing.assert_allclose(
        axes / np.linalg.norm(axes, axis=1, keepdims=True), np.tile(axis, (20, 1)), atol=1e-9
    )


def test_ctraj_takes_the_shorter_rotation():
    A = pose(np.eye(3), [0, 0, 0])
    B = pose(rot([0, 0, 1], 3.5), [0, 0, 0])  # 3.5 rad one way is 2 pi - 3.5 = 2.78 rad the other
    R = ctraj(A, B, s=np.linspace(0, 1, 11))[:, :3, :3]
    np.testing.assert_allclose(geodesic_angle(R[:-1], R[1:]).sum(), 2 * math.pi - 3.5, rtol=1e-9)
    np.testing.assert_allclose(geodesic_angle(R[:-1], R[1:]), (2 * math.pi - 3.5) / 10, rtol=1e-9)


def test_ctraj_int_and_time_vector_use_the_trapezoidal_profile():
    P = ctraj(T0, T1, 30)
    s = trapezoidal(0.0, 1.0, 30).q
    np.testing.assert_allclose(P[:, :3, 3], (1 - s)[:, None] * T0[:3, 3] + s[:, None] * T1[:3, 3], atol=1e-15)
    np.testing.assert_allclose(ctraj(T0, T1, np.linspace(0, 3, 30)), P, atol=1e-14)
    np.testing.assert_array_equal(P[[0, -1]], [T0, T1])


def test_ctraj_bad_input():
    bad = T1.copy()
    bad[:3, :3] *= 1.01
    with pytest.raises(PoseError, match="T1 rotation is not orthonormal"):
        ctraj(T0, bad, 10)
    bad = T0.copy()
    bad[3] = [0, 0, 1, 1]
    with pytest.raises(PoseError, match="T0 has bottom row"):
        ctraj(bad, T1, 10)
    bad = T0.copy()
    bad[0, 3] = np.nan
    with pytest.raises(PoseError, match="T0 contains NaN"):
        ctraj(bad, T1, 10)
    with pytest.raises(PoseError, match="T1"):
        ctraj(T0, np.eye(3), 10)
    with pytest.raises(PoseError, match="T0 rotation is a reflection"):
        ctraj(np.diag([1.0, 1.0, -1.0, 1.0]), T1, 10)
    with pytest.raises(ParameterError, match=r"in \[0, 1\]"):
        ctraj(T0, T1, s=[0.0, 1.5])
    with pytest.raises(ParameterError, match="exactly one"):
        ctraj(T0, T1)
    with pytest.raises(ParameterError, match="increasing"):
        ctraj(T0, T1, [0.0, 1.0, 1.0])


# -- tracking a Cartesian path ------------------------------------------------------------------
@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


@pytest.fixture(scope="module")
def line(panda):
    """A 10 cm straight line in x from the Panda's ready pose, 50 poses (trapezoidal profile)."""
    q0 = np.asarray(panda.configs["qr"], dtype=float)
    Ta = panda.fkine(q0)
    Tb = Ta.copy()
    Tb[:3, 3] += [0.1, 0.0, 0.0]
    return q0, ctraj(Ta, Tb, 50)


def test_servo_path_tracks_a_straight_line(panda, line):
    q0, P = line
    res = servo_path(panda, P, q0)
    assert isinstance(res, PathResult)
    assert res.q.shape == (50, 7) and res.qd.shape == (49, 7) and res.e.shape == (50, 6)
    np.testing.assert_array_equal(res.q[0], q0)
    # measured: 1.4e-5 m (the linearisation error of one step of up to 3 mm), orientation 4e-16 rad
    assert res.max_position_error < 3e-5
    assert res.max_angle_error < 1e-9
    assert res.position_error[-1] < 1e-7
    np.testing.assert_allclose(panda.fkine(res.q[-1])[:3, 3], P[-1, :3, 3], atol=1e-7)
    # the pieces matter: without feedback the linearisation error accumulates (3.9e-4 m), without
    # the feed-forward the servo lags one step behind (3.1e-3 m), with neither the arm stays put
    assert servo_path(panda, P, q0, gain=0.0).max_position_error > 1e-4
    assert servo_path(panda, P, q0, feedforward=False).max_position_error > 1e-3
    assert servo_path(panda, P, q0, gain=0.0, feedforward=False).max_position_error == pytest.approx(0.1)
    # time steps: dt = 20 ms with gain 1/dt is the same loop as one unit per step with gain 1
    timed = servo_path(panda, P, q0, gain=50.0, dt=0.02)
    np.testing.assert_allclose(timed.q, res.q, atol=1e-12)
    np.testing.assert_allclose(timed.qd, res.qd / 0.02, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(timed.t[-1], 49 * 0.02)


def test_servo_path_rotation_frame_damping_and_compiled(panda, line):
    q0, _ = line
    Ta = panda.fkine(q0)
    Tb = pose(Ta[:3, :3] @ rot([1, 0, 0], 0.3), Ta[:3, 3] + [0.0, 0.05, -0.05])
    res = servo_path(panda, ctraj(Ta, Tb, 50), q0)
    assert res.max_position_error < 3e-5 and res.max_angle_error < 1e-4  # measured 1.2e-5 m, 5.3e-5 rad
    assert servo_path(panda, ctraj(Ta, Tb, 50), q0, feedforward=False).max_angle_error > 5e-3
    damped = servo_path(panda, ctraj(Ta, Tb, 50), q0, damping=0.01)
    assert damped.max_position_error < 1e-4 and damped.max_angle_error < 1e-4
    # link frame 5 of the chain: fkine and jacob0 of that frame
    F0 = panda.fkine(q0, frame=5)
    F1 = pose(F0[:3, :3], F0[:3, 3] + [0.0, 0.0, 0.05])
    res5 = servo_path(panda, ctraj(F0, F1, 20), q0, frame=5)
    assert res5.max_position_error < 3e-5
    np.testing.assert_allclose(panda.fkine(res5.q[-1], frame=5), F1, atol=1e-6)
    np.testing.assert_array_equal(res5.q[:, 6], q0[6])  # the joint after frame 5 does not move
    # compiled kinematics (NumPy backend) take the same steps
    kin = symkin.compile(panda, backend="numpy")
    P = ctraj(Ta, Tb, 50)
    np.testing.assert_allclose(servo_path(kin, P, q0).q, res.q, atol=1e-10)


def test_servo_path_bad_input(panda, line):
    q0, P = line
    with pytest.raises(ConfigurationError):
        servo_path(panda, P, q0[:6])
    with pytest.raises(ConfigurationError):
        servo_path(panda, P, np.r_[q0[:6], np.nan])
    with pytest.raises(ParameterError, match="dt must be"):
        servo_path(panda, P, q0, dt=0.0)
    with pytest.raises(ParameterError, match="dt must be"):
        servo_path(panda, P, q0, dt=-0.1)
    with pytest.raises(ParameterError, match="gain"):
        servo_path(panda, P, q0, gain=-1.0)
    with pytest.raises(ParameterError, match="path of N >= 1 poses"):
        servo_path(panda, P[0], q0)
    bad = P.copy()
    bad[3, :3, :3] *= 2
    with pytest.raises(PoseError, match=r"poses \[3\] rotation is not orthonormal"):
        servo_path(panda, bad, q0)


# -- roboticstoolbox-python, where it is installed ---------------------------------------------
@pytest.fixture(scope="module")
def rtb():
    return pytest.importorskip("roboticstoolbox")


def test_rtb_ctraj(rtb):
    SE3 = pytest.importorskip("spatialmath").SE3
    A, B = SE3(T0, check=False), SE3(T1, check=False)
    np.testing.assert_allclose(ctraj(T0, T1, 20), np.array(rtb.ctraj(A, B, 20).A), atol=1e-12)
    s = np.linspace(0, 1, 15)
    np.testing.assert_allclose(ctraj(T0, T1, s=s), np.array(rtb.ctraj(A, B, s=s).A), atol=1e-12)
