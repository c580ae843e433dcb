"""Trajectories (quintic, jtraj, trapezoidal, mstraj, ctraj) and resolved-rate tracking of a Cartesian path.

Independent checks always run (boundary conditions, derivatives against finite differences, the
piecewise structure, geodesic rotations); the comparisons with roboticstoolbox-python run only where it
is installed.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import symkin
from symkin.errors import ConfigurationError, ParameterError, PoseError
from symkin.runtime.ik import angle_axis
from symkin.runtime.trajectory import (
    PathResult,
    Trajectory,
    ctraj,
    jtraj,
    mstraj,
    quintic,
    servo_path,
    trapezoidal,
)


def rot(axis, angle: float) -> np.ndarray:
    """Rotation matrix about a unit axis (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    k = k / np.linalg.norm(k)
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + math.sin(angle) * K + (1 - math.cos(angle)) * K @ K


def pose(R: np.ndarray, p) -> np.ndarray:
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, p
    return T


def central(y: np.ndarray, h: float) -> np.ndarray:
    """Central differences of samples y (N, ...) spaced h apart, at samples 1..N-2."""
    return (y[2:] - y[:-2]) / (2 * h)


def geodesic_angle(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Rotation angle(s) of Rb Ra^T."""
    return np.linalg.norm(angle_axis(Rb @ np.swapaxes(Ra, -1, -2)), axis=-1)


# -- quintic and jtraj --------------------------------------------------------------------------
def test_jtraj_boundary_conditions_and_shapes():
    q0, qf = np.array([0.1, -0.5, 2.0]), np.array([1.0, 0.5, -1.0])
    tr = jtraj(q0, qf, 50)
    assert isinstance(tr, Trajectory) and tr.name == "jtraj" and tr.istime
    assert len(tr) == 50 and tr.naxes == 3
    assert tr.q.shape == tr.qd.shape == tr.qdd.shape == (50, 3)
    np.testing.assert_allclose(tr.t, np.linspace(0, 1, 50))  # an int: normalised time 0..1
    np.testing.assert_allclose(tr.q[0], q0, atol=1e-15)
    np.testing.assert_allclose(tr.q[-1], qf, atol=1e-14)
    np.testing.assert_allclose(tr.qd[[0, -1]], 0, atol=1e-13)
    np.testing.assert_allclose(tr.qdd[[0, -1]], 0, atol=1e-12)
    # symmetric rest-to-rest quintic: midpoint halfway, peak speed 15/8 of the mean there
    np.testing.assert_allclose(jtraj(q0, qf, 51).q[25], (q0 + qf) / 2, atol=1e-14)
    np.testing.assert_allclose(jtraj(q0, qf, 51).qd[25], 15 / 8 * (qf - q0), rtol=1e-12)


def test_jtraj_time_vector_scales_the_polynomial_to_the_final_time():
    q0, qf, T = np.array([0.0, 1.0]), np.array([2.0, -1.0]), 2.5
    unit, timed = jtraj(q0, qf, 41), jtraj(q0, qf, np.linspace(0, T, 41))
    np.testing.assert_allclose(timed.t, np.linspace(0, T, 41))
    np.testing.assert_allclose(timed.q, unit.q, atol=1e-14)
    np.testing.assert_allclose(timed.qd, unit.qd / T, atol=1e-14)
    np.testing.assert_allclose(timed.qdd, unit.qdd / T**2, atol=1e-13)


def test_jtraj_given_boundary_velocities():
    q0, qf, v0, v1 = np.array([0.0, 1.0]), np.array([1.0, 0.0]), np.array([0.5, -1.0]), np.array([2.0, 0.3])
    tr = jtraj(q0, qf, np.linspace(0, 2, 21), qd0=v0, qd1=v1)
    np.testing.assert_allclose(tr.q[[0, -1]], [q0, qf], atol=1e-14)
    np.testing.assert_allclose(tr.qd[[0, -1]], [v0, v1], atol=1e-13)
    np.testing.assert_allclose(tr.qdd[[0, -1]], 0, atol=1e-12)


@pytest.mark.parametrize("make", ["jtraj", "quintic", "quintic-steps", "trapezoidal", "trapezoidal-V"])
def test_velocity_and_acceleration_are_the_derivatives_of_q(make):
    h = 1e-3
    t = np.arange(0, 2001) * h  # 0..2 s
    q0, qf = np.array([0.2, -1.0, 3.0]), np.array([1.5, 0.5, 3.0])
    tr = {
        "jtraj": lambda: jtraj(q0, qf, t, qd0=[0.1, 0, -0.2], qd1=[0, 0.4, 0]),
        "quintic": lambda: quintic(0.2, 1.5, t, qd0=-0.3, qdf=0.2),
        "quintic-steps": lambda: quintic(q0, qf, 2001),  # per step: h = 1
        "trapezoidal": lambda: trapezoidal(q0, qf, t),
        "trapezoidal-V": lambda: trapezoidal(0.2, 1.5, t, V=0.9),
    }[make]()
    h = float(tr.t[1] - tr.t[0])
    ok = np.ones(len(tr) - 2, dtype=bool)
    if make.startswith("trapezoidal"):  # qdd jumps where the blends meet the linear segment
        tb = np.atleast_1d(tr.info["tblend"])
        for b in tb[np.isfinite(tb)]:
            ok &= (np.abs(tr.t[1:-1] - b) > 1.5 * h) & (np.abs(tr.t[1:-1] - (tr.t[-1] - b)) > 1.5 * h)
    assert ok.sum() > 0.99 * len(ok)
    # central differences are exact to h^2 / 6 times the next derivative: 1e-5 of the scale here
    for y, dy in [(tr.q, tr.qd), (tr.qd, tr.qdd)]:
        scale = max(1.0, float(np.abs(dy).max()))
        np.testing.assert_allclose(central(y, h)[ok], dy[1:-1][ok], rtol=0, atol=1e-5 * scale)


def test_quintic_scalar_and_steps_as_rtb():
    tr = quintic(1.0, 2.0, 10)
    assert tr.name == "quintic" and not tr.istime and tr.q.shape == (10,) and tr.naxes == 1
    np.testing.assert_array_equal(tr.t, np.arange(10))  # an int: step numbers, as RTB's quintic
    s = np.arange(10) / 9
    np.testing.assert_allclose(tr.q, 1 + 10 * s**3 - 15 * s**4 + 6 * s**5, atol=1e-14)
    np.testing.assert_allclose(tr.qd, (30 * s**2 - 60 * s**3 + 30 * s**4) / 9, atol=1e-14)  # per step
    assert quintic([0, 1], [1, 3], 5).q.shape == (5, 2)


# -- trapezoidal --------------------------------------------------------------------------------
def test_trapezoidal_piecewise_structure_default_speed():
    t = np.linspace(0, 3, 301)
    tr = trapezoidal(1.0, 4.0, t)
    V, tb, a = 1.5 * 3 / 3, 1.0, 1.5  # V = 1.5 (qf - q0) / tf, tblend = tf / 3, a = V / tb
    assert tr.name == "trapezoidal" and tr.q.shape == (301,)
    assert tr.info["V"] == pytest.approx(V) and tr.info["tblend"] == pytest.approx(tb)
    blend1, blend2 = t < tb - 1e-9, t > 3 - tb + 1e-9
    linear = ~blend1 & ~blend2 & (np.abs(t - tb) > 1e-9) & (np.abs(t - (3 - tb)) > 1e-9)
    np.testing.assert_allclose(tr.qdd[blend1], a)  # constant acceleration in the blends
    np.testing.assert_allclose(tr.qdd[blend2], -a)
    np.testing.assert_allclose(tr.qdd[linear], 0)
    np.testing.assert_allclose(tr.qd[linear], V)  # the speed V is reached and held
    assert tr.qd.max() == pytest.approx(V)
    np.testing.assert_allclose(tr.q[blend1], 1 + a / 2 * t[blend1] ** 2)  # parabola
    np.testing.assert_allclose(np.diff(tr.q[linear]), V * 0.01, rtol=1e-9)  # straight line
    assert tr.q[0] == 1.0 and tr.q[-1] == pytest.approx(4.0, abs=1e-14)
    assert tr.qd[0] == 0 and tr.qd[-1] == pytest.approx(0, abs=1e-12)


def test_trapezoidal_given_speed_per_axis_and_bounds():
    t = np.linspace(0, 2, 201)
    tr = trapezoidal([0.0, 1.0, 5.0], [1.0, -1.0, 5.0], t, V=[0.75, 1.5, 1.0])  # axis 2 does not move
    assert tr.q.shape == (201, 3)
    np.testing.assert_allclose(tr.info["V"], [0.75, -1.5, 0.0])  # V takes the sign of qf - q0
    np.testing.assert_allclose(tr.info["tblend"][:2], [2 / 3, 2 / 3])  # tb = (q0 - qf + V tf) / V
    np.testing.assert_allclose(tr.qd.min(axis=0)[1], -1.5)
    np.testing.assert_allclose(tr.q[-1], [1.0, -1.0, 5.0], atol=1e-14)
    np.testing.assert_array_equal(tr.q[:, 2], 5.0)
    # the bounds: |qf - q0| / tf < |V| <= 2 |qf - q0| / tf
    tri = trapezoidal(0.0, 1.0, t, V=1.0)  # the upper bound: a triangle, blends of tf / 2
    assert tri.info["tblend"] == pytest.approx(1.0) and tri.qd.max() == pytest.approx(1.0)
    with pytest.raises(ParameterError, match="too small"):
        trapezoidal(0.0, 1.0, t, V=0.4)
    with pytest.raises(ParameterError, match="too small"):
        trapezoidal(0.0, 1.0, t, V=0.5)  # exactly |qf - q0| / tf: no time to accelerate
    with pytest.raises(ParameterError, match=r"too large \(axis 1\)"):
        trapezoidal([0.0, 0.0], [1.0, 1.0], t, V=[0.8, 1.01])
    with pytest.raises(ParameterError, match="too small"):
        trapezoidal(0.0, 1.0, t, V=0.0)


def test_trapezoidal_steps_as_rtb():
    tr = trapezoidal(1, 2, 10)
    assert not tr.istime
    np.testing.assert_array_equal(tr.t, np.arange(10))
    np.testing.assert_allclose(
        tr.q, [1, 1.0277778, 1.1111111, 1.25, 1.4166667, 1.5833333, 1.75, 1.8888889, 1.9722222, 2], atol=1e-7
    )


# -- mstraj -------------------------------------------------------------------------------------
VIA = np.array([[0.0, 0.0], [1.0, 2.0], [3.0, 1.0], [2.0, 0.0]])


def test_mstraj_segment_durations_speed_and_duration():
    dt, tacc, qdmax = 0.125, 0.5, np.array([2.0, 1.0])
    tr = mstraj(VIA, dt, tacc, qdmax=qdmax)
    assert tr.name == "mstraj" and tr.q.shape == tr.qd.shape == tr.qdd.shape == (len(tr), 2)
    # segment 0: axis 1 needs 2 / 1 = 2 s, plus the half blend 0.25 s; segments 1, 2: 1 s + 0.5 s
    np.testing.assert_allclose(tr.info["segtime"], [2.25, 1.5, 1.5])
    np.testing.assert_array_equal(tr.info["slowest"], [1, 0, 1])
    np.testing.assert_allclose(tr.info["arrive"], np.cumsum([2.25, 1.5, 1.5]))
    assert tr.t[-1] == pytest.approx(5.25)  # the duration is the sum of the segment times
    np.testing.assert_allclose(np.diff(tr.t), dt)
    np.testing.assert_array_equal(tr.q[0], VIA[0])  # starts at the first row at rest
    np.testing.assert_allclose(tr.q[-1], VIA[-1], atol=1e-14)  # ends at the last at rest
    np.testing.assert_allclose(tr.qd[[0, -1]], 0, atol=1e-12)
    # linear parts (qdd = 0) move at dq / segtime, within qdmax; the slowest axis sets the time
    linear = np.all(tr.qdd == 0, axis=1)
    linear[0] = False
    assert linear.sum() > len(tr) // 2
    assert (np.abs(tr.qd[linear]) <= qdmax + 1e-12).all()
    speeds = {tuple(np.round(v, 12)) for v in tr.qd[linear]}
    expected = [np.diff(VIA, axis=0)[i] / tr.info["segtime"][i] for i in range(3)]
    assert speeds == {tuple(np.round(v, 12)) for v in expected}


def test_mstraj_passes_near_via_points_and_through_them_without_blends():
    dt, qdmax = 0.02, [1.0, 1.0]
    sharp = mstraj(VIA, dt, 0.0, qdmax=qdmax)  # tacc = 0: straight lines through every via point
    for w in VIA[1:]:
        assert np.linalg.norm(sharp.q - w, axis=1).min() < 1e-12
    smooth = mstraj(VIA, dt, 0.4, qdmax=qdmax)
    for w, v_in, v_out in zip(VIA[1:-1], np.diff(VIA, axis=0)[:-1], np.diff(VIA, axis=0)[1:], strict=True):
        miss = np.linalg.norm(smooth.q - w, axis=1).min()
        assert 1e-3 < miss < 0.2 * max(np.linalg.norm(v_in), np.linalg.norm(v_out))  # cuts the corner
    np.testing.assert_allclose(smooth.q[-1], VIA[-1], atol=1e-14)


def test_mstraj_derivatives_and_continuity():
    dt = 0.002
    tr = mstraj(VIA, dt, 0.5, qdmax=[2.0, 1.0], qd0=[0.3, 0.0])
    np.testing.assert_allclose(tr.qd[0], [0.3, 0.0])
    h = dt
    jerk = np.abs(np.diff(tr.qdd, axis=0)).max() / h
    np.testing.assert_allclose(central(tr.q, h), tr.qd[1:-1], rtol=0, atol=1.2 * h**2 / 6 * jerk)  # 3.3e-4
    # qdd is continuous (the blends start and end with zero acceleration) but the jerk jumps where a blend
    # meets a linear part, which central differences of qd blur by h |jerk| / 4: leave those samples out
    linear = np.all(tr.qdd == 0, axis=1)
    ok = linear[:-2] == linear[2:]
    assert (~ok).sum() <= 16  # two samples at each end of each of the 4 blends
    np.testing.assert_allclose(
        central(tr.qd, h)[ok], tr.qdd[1:-1][ok], rtol=0, atol=1e-3 * np.abs(tr.qdd).max()
    )
    assert np.abs(np.diff(tr.qd, axis=0)).max() < 20 * h  # no velocity jumps


def test_mstraj_tsegment_and_q0():
    tr = mstraj(VIA[1:], 0.1, 0.2, tsegment=[3.0, 2.0, 2.0], q0=VIA[0])
    np.testing.assert_allclose(tr.info["segtime"], [3.0, 2.0, 2.0])
    assert tr.t[-1] == pytest.approx(7.0)
    np.testing.assert_array_equal(tr.q[0], VIA[0])
    np.testing.assert_array_equal(tr.info["slowest"], [-1, -1, -1])
    np.testing.assert_allclose(mstraj(VIA, 0.1, 0.2, tsegment=[3.0, 2.0, 2.0]).q, tr.q)


def test_mstraj_bad_input():
    with pytest.raises(ParameterError, match="tacc must be >= 0"):
        mstraj(VIA, 0.1, -0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="dt must be"):
        mstraj(VIA, 0.0, 0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="exactly one of qdmax"):
        mstraj(VIA, 0.1, 0.1)
    with pytest.raises(ParameterError, match="exactly one of qdmax"):
        mstraj(VIA, 0.1, 0.1, qdmax=1.0, tsegment=[1, 1, 1])
    with pytest.raises(ParameterError, match="qdmax must be"):
        mstraj(VIA, 0.1, 0.1, qdmax=[1.0, 0.0])
    with pytest.raises(ParameterError, match="qdmax must be"):
        mstraj(VIA, 0.1, 0.1, qdmax=[1.0, 1.0, 1.0])
    with pytest.raises(ParameterError, match="tsegment must be 3"):
        mstraj(VIA, 0.1, 0.1, tsegment=[1.0, 1.0])
    with pytest.raises(ParameterError, match="too short"):
        mstraj(VIA, 0.1, 1.0, tsegment=[1.0, 1.0, 1.0])
    with pytest.raises(ParameterError, match="finite"):
        mstraj(np.array([[0.0, 0.0], [1.0, np.nan]]), 0.1, 0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="q0 must have shape"):
        mstraj(VIA, 0.1, 0.1, qdmax=1.0, q0=[0.0, 0.0, 0.0])
    with pytest.raises(ParameterError, match="at least 2 rows"):
        mstraj(VIA[:1], 0.1, 0.1, qdmax=1.0)
    with pytest.raises(ParameterError, match="tacc must be a number or 3"):
        mstraj(VIA, 0.1, [0.1, 0.2], qdmax=1.0)


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


# -- input checks shared by the generators --------------------------------------------------------
@pytest.mark.parametrize("fn", [quintic, jtraj, trapezoidal])
def test_bad_times_and_endpoints(fn):
    with pytest.raises(ParameterError, match="strictly increasing"):
        fn([0.0, 1.0], [1.0, 2.0], [0.0, 0.5, 0.5, 1.0])
    with pytest.raises(ParameterError, match="strictly increasing"):
        fn([0.0, 1.0], [1.0, 2.0], [0.0, 1.0, 0.5])
    with pytest.raises(ParameterError, match="finite"):
        fn([0.0, 1.0], [1.0, 2.0], [0.0, np.nan, 1.0])
    with pytest.raises(ParameterError, match="time >= 0"):
        fn([0.0, 1.0], [1.0, 2.0], [-1.0, 0.0, 1.0])
    with pytest.raises(ParameterError, match="at least 2"):
        fn([0.0, 1.0], [1.0, 2.0], 1)
    with pytest.raises(ParameterError, match="at least 2 times"):
        fn([0.0, 1.0], [1.0, 2.0], 2.0)
    with pytest.raises(ParameterError, match="one length"):
        fn([0.0, 1.0], [1.0, 2.0, 3.0], 10)
    with pytest.raises(ParameterError, match="q0 must be finite"):
        fn([0.0, np.nan], [1.0, 2.0], 10)
    with pytest.raises(ParameterError, match="qf must be finite"):
        fn([0.0, 0.0], [np.inf, 2.0], 10)


def test_bad_boundary_velocities():
    with pytest.raises(ParameterError, match="qd0 must be a number or 2"):
        jtraj([0, 1], [1, 2], 10, qd0=[1, 2, 3])
    with pytest.raises(ParameterError, match="qdf must be finite"):
        quintic(0, 1, 10, qdf=np.nan)
    with pytest.raises(ParameterError, match="V must be a number or 2"):
        trapezoidal([0, 1], [1, 2], 10, V=[1, 2, 3])


# -- the Trajectory object ----------------------------------------------------------------------
def test_trajectory_is_frozen_and_read_only():
    tr = jtraj([0, 0], [1, 1], 5)
    with pytest.raises(dataclasses.FrozenInstanceError):
        tr.q = np.zeros((5, 2))  # type: ignore[misc]
    with pytest.raises(ValueError, match="read-only"):
        tr.q[0, 0] = 1.0
    with pytest.raises(TypeError):
        trapezoidal(0, 1, 5).info["V"] = 2  # type: ignore[index]
    assert "jtraj" in repr(tr) and "5 samples x 2 axes" in repr(tr)
    assert tr.s is tr.q and tr.sd is tr.qd and tr.sdd is tr.qdd


def test_plot_returns_a_figure_with_q_qd_qdd():
    pytest.importorskip("matplotlib")
    fig = mstraj(VIA, 0.1, 0.4, qdmax=1.0).plot()
    axes = fig.get_axes()
    assert len(axes) == 3
    assert [len(ax.get_lines()) for ax in axes] == [2, 2, 2]
    assert axes[-1].get_xlabel() == "t (s)"
    assert quintic(0, 1, 10).plot().get_axes()[-1].get_xlabel() == "k (step)"


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


def test_rtb_quintic_jtraj_trapezoidal(rtb):
    q0, qf = np.array([0.1, -0.5, 2.0]), np.array([1.0, 0.5, -1.0])
    v0, v1 = np.array([0.1, 0, 0]), np.array([0, 0.2, 0])
    t = np.linspace(0, 2, 30)
    for ours, theirs in [
        (quintic(0.2, 1.5, 20), rtb.quintic(0.2, 1.5, 20)),
        (quintic(0.2, 1.5, t, qd0=0.3, qdf=-0.1), rtb.quintic(0.2, 1.5, t, qd0=0.3, qdf=-0.1)),
        (trapezoidal(0.2, 1.5, 20), rtb.trapezoidal(0.2, 1.5, 20)),
        (trapezoidal(1.5, 0.2, t, V=1.0), rtb.trapezoidal(1.5, 0.2, t, V=1.0)),
        (jtraj(q0, qf, t, qd0=v0, qd1=v1), rtb.jtraj(q0, qf, t, qd0=v0, qd1=v1)),
    ]:
        np.testing.assert_allclose(ours.t, theirs.t, atol=1e-12)
        for a, b in [(ours.q, theirs.q), (ours.qd, theirs.qd), (ours.qdd, theirs.qdd)]:
            np.testing.assert_allclose(a, b, atol=1e-9)
    ours, theirs = jtraj(q0, qf, 25), rtb.jtraj(q0, qf, 25)  # RTB's t differs (linspace(0, 25, 25))
    for a, b in [(ours.q, theirs.q), (ours.qd, theirs.qd), (ours.qdd, theirs.qdd)]:
        np.testing.assert_allclose(a, b, atol=1e-9)
    assert trapezoidal(0.2, 1.5, t).info["tblend"] == pytest.approx(rtb.trapezoidal(0.2, 1.5, t).tblend)


def test_rtb_mstraj(rtb):
    for kwargs in [{"qdmax": [2.0, 1.0]}, {"tsegment": np.array([3.0, 2.0, 2.0])}]:
        ours, theirs = mstraj(VIA, 0.125, 0.5, **kwargs), rtb.mstraj(VIA, 0.125, 0.5, **kwargs)
        np.testing.assert_allclose(ours.q[1:], theirs.q, atol=1e-12)  # RTB leaves out the start q0
        np.testing.assert_allclose(ours.info["arrive"], theirs.arrive, atol=1e-12)


def test_rtb_ctraj(rtb):
    SE3 = pytest.importorskip("spatialmath").SE3
    A, B = SE3(T0, check=False), SE3(T1, check=False)
    np.testing.assert_allclose(ctraj(T0, T1, 20), np.array(rtb.ctraj(A, B, 20).A), atol=1e-12)
    s = np.linspace(0, 1, 15)
    np.testing.assert_allclose(ctraj(T0, T1, s=s), np.array(rtb.ctraj(A, B, s=s).A), atol=1e-12)
