"""Cartesian paths between two poses (RTB's ``ctraj``) and resolved-rate tracking of a Cartesian path.

numpy only. Poses are (4, 4) homogeneous transforms in the robot's base frame, checked by the one pose
rule (:mod:`symkin.core.pose`); spatial velocities and pose errors have rows (v, omega) in the base
frame, as ``jacob0`` and :func:`symkin.runtime.ik.pose_error` (eq 37 of Haviland and Corke, Manipulator
Differential Kinematics, Part 1, 2023). The path parameter of ``ctraj`` follows the trapezoidal
profile of :mod:`symkin.runtime.trajectory`, as RTB's (Corke, Robotics, Vision & Control in Python,
3e, 2023, chap 3).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.core.arrays import MAX_JOINT_VALUE, as_config, name_of, real_array
from symkin.core.pose import as_pose, as_poses
from symkin.errors import ParameterError
from symkin.model.orientation import quaternion, quaternion_matrix
from symkin.runtime.ik_problem import pose_error_of
from symkin.runtime.servo import servo_gain
from symkin.runtime.trajectory import _positive, _times, unit_trapezoidal

__all__ = ["ctraj", "servo_path", "PathResult"]


def _slerp(q0: np.ndarray, q1: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation (N, 4) of unit quaternions along the shorter arc."""
    dot = float(q0 @ q1)
    if dot < 0:  # q and -q are the same rotation: take the short way
        q1, dot = -q1, -dot
    theta = math.acos(min(dot, 1.0))
    if theta < 1e-9:
        q = (1 - s)[:, None] * q0 + s[:, None] * q1
    else:
        q = (np.sin((1 - s) * theta)[:, None] * q0 + np.sin(s * theta)[:, None] * q1) / math.sin(theta)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def ctraj(T0: Any, T1: Any, t: Any = None, s: Any = None) -> np.ndarray:
    """Cartesian path from pose ``T0`` to ``T1`` (both (4, 4) in the same frame): (N, 4, 4) poses.

    The path parameter ``s`` in [0, 1] moves the origin along the straight line ``(1 - s) p0 + s p1``
    and the rotation along the geodesic from R0 to R1 (SLERP of unit quaternions, the shorter way), as
    RTB's ``ctraj`` (``T0.interp(T1, s)``). ``t``: an int N, ``s`` from ``trapezoidal(0, 1, N)`` (rest
    to rest with a constant-speed middle third), or a vector of times, ``s`` from
    ``trapezoidal(0, 1, t / t[-1])``. Or give ``s`` (N,) itself. ``s = 0`` and ``s = 1`` give ``T0``
    and ``T1`` exactly. PoseError for a T0 or T1 that is not SE(3).
    """
    A, B = as_pose(T0, "T0"), as_pose(T1, "T1")
    if (t is None) == (s is None):
        raise ParameterError("give exactly one of t (samples or times) and s (path parameters in [0, 1])")
    if t is not None:
        times, tau, T, _ = _times(t, "zero")  # an int: steps 0..N-1 (RTB's trapezoidal(0, 1, N))
        sv = unit_trapezoidal(tau / T)
    else:
        sv = real_array(s, "s", ParameterError)
        if sv.ndim != 1 or sv.size < 1:
            raise ParameterError(f"s must be a vector of path parameters, got shape {sv.shape}")
        if not (np.isfinite(sv).all() and (sv >= 0).all() and (sv <= 1).all()):
            raise ParameterError("s must hold path parameters in [0, 1] (no NaN)")
    out = np.zeros((len(sv), 4, 4))
    out[:, 3, 3] = 1.0
    out[:, :3, 3] = (1 - sv)[:, None] * A[:3, 3] + sv[:, None] * B[:3, 3]
    out[:, :3, :3] = quaternion_matrix(_slerp(quaternion(A[:3, :3]), quaternion(B[:3, :3]), sv))
    out[sv == 0, :3, :3] = A[:3, :3]
    out[sv == 1, :3, :3] = B[:3, :3]
    return out


# -- tracking a Cartesian path ----------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class PathResult:
    """Resolved-rate tracking of a path of N poses (:func:`servo_path`).

    Attributes:
        q: (N, n) configurations, ``q[0] = q0``, ``q[i + 1] = q[i] + dt qd[i]``.
        qd: (N - 1, n) joint velocities.
        e: (N, 6) base-frame pose error (eq 37) of ``fkine(q[i])`` to ``poses[i]``: rows (position m,
            Euler vector rad).
        position_error: (N,) ``|e[:, :3]|``, metres.
        angle_error: (N,) ``|e[:, 3:]|``, the rotation angle between actual and wanted pose, radians.
        dt: the time step (s; 1.0 for one unit per step when not given).
    """

    q: np.ndarray
    qd: np.ndarray
    e: np.ndarray
    position_error: np.ndarray
    angle_error: np.ndarray
    dt: float

    @property
    def t(self) -> np.ndarray:
        """(N,) time of each configuration."""
        return np.arange(len(self.q)) * self.dt

    @property
    def max_position_error(self) -> float:
        """Largest position error over the path (m)."""
        return float(self.position_error.max())

    @property
    def max_angle_error(self) -> float:
        """Largest orientation error over the path (rad)."""
        return float(self.angle_error.max())

    def __repr__(self) -> str:
        return (
            f"PathResult({len(self.q)} poses, max_position_error={self.max_position_error:.3g} m, "
            f"max_angle_error={self.max_angle_error:.3g} rad)"
        )


def servo_path(
    kin: Any,
    poses: Any,
    q0: Any,
    gain: float | Any = 1.0,
    dt: float | None = None,
    frame: Any = None,
    feedforward: bool = True,
    damping: float = 0.0,
) -> PathResult:
    """Track the Cartesian path ``poses`` (N, 4, 4) (base frame, e.g. from :func:`ctraj`) with
    resolved-rate motion control from configuration ``q0`` (n,).

    At step i: the pose error ``e_i`` (eq 37, :func:`symkin.runtime.ik.pose_error`) of
    ``kin.fkine(q_i, frame=frame)`` to ``poses[i]``; the commanded base-frame spatial velocity
    ``nu = nu_ff + k e_i`` with the feed-forward ``nu_ff = pose_error(poses[i], poses[i + 1]) / dt``
    (the velocity that carries pose i to pose i + 1 in dt) and the feedback gain ``k`` (eq 42: a
    number, ``(k_t, k_r)`` or six values, 1/s); ``qd_i`` the least-squares (minimum-norm) solution of
    ``J0(q_i) qd = nu`` with ``J0 = kin.jacob0(q_i, frame=frame)`` (or the damped least-squares
    ``J^T (J J^T + damping^2 I)^-1 nu``); ``q_{i+1} = q_i + dt qd_i``.

    ``dt`` (s) is the time between consecutive poses; None means one time unit per pose, so that
    ``gain = 1`` corrects the whole error of a step in the next one. ``feedforward=False`` drops
    ``nu_ff`` (a pure position-based servo chasing each pose, one step behind). ``kin`` is any object
    with ``n``, ``fkine`` and ``jacob0`` (a :class:`symkin.Robot`, compiled kinematics, a tree with
    ``frame``); ``frame`` is passed to both when given. There are no joint limits or speed limits.
    """
    n = int(kin.n)
    q = as_config(q0, n, name_of(kin), "q0").copy()
    P, single = as_poses(poses, "poses")  # the one pose rule (a spatialmath SE3 with N values too)
    if single or len(P) == 0:
        raise ParameterError(f"poses must be a path of N >= 1 poses, shape (N, 4, 4), got {np.shape(poses)}")
    dt = 1.0 if dt is None else _positive(dt, "dt")
    k = servo_gain(gain)
    lam = _positive(damping, "damping", allow_zero=True)
    kw = {} if frame is None else {"frame": frame}
    N = len(P)
    Q, QD, E = np.zeros((N, n)), np.zeros((N - 1, n)), np.zeros((N, 6))
    for i in range(N):
        Q[i] = q
        with np.errstate(over="ignore", invalid="ignore"):
            E[i] = pose_error_of(np.asarray(kin.fkine(q, **kw), dtype=float), P[i])
            if i == N - 1:
                _finite_step(i, E[i], np.zeros(n), q)
                break
            nu = k * E[i]
            if feedforward:
                nu = nu + pose_error_of(P[i], P[i + 1]) / dt
            J = np.asarray(kin.jacob0(q, **kw), dtype=float)
            qd = np.full(n, math.nan)
            if np.isfinite(nu).all():
                if lam > 0:
                    qd = J.T @ np.linalg.solve(J @ J.T + lam**2 * np.eye(6), nu)
                else:
                    qd = np.linalg.lstsq(J, nu, rcond=None)[0]
            q = q + dt * qd
        _finite_step(i, nu, qd, q)
        QD[i] = qd
    pos, ang = np.linalg.norm(E[:, :3], axis=1), np.linalg.norm(E[:, 3:], axis=1)
    return PathResult(Q, QD, E, pos, ang, dt)


def _finite_step(i: int, nu: np.ndarray, qd: np.ndarray, q: np.ndarray) -> None:
    """ParameterError unless step i's command nu (or pose error), joint velocity qd and next joint
    values q are finite and q within +-1e15 (the joint-value rule): a path too far from the robot or
    too fast for its dt and gain, never a NaN configuration."""
    if not (np.isfinite(nu).all() and np.isfinite(qd).all() and (np.abs(q) <= MAX_JOINT_VALUE).all()):
        raise ParameterError(
            f"servo_path: at pose {i} the pose error, command or joint velocity exceeds the range of a "
            f"double or the joint values leave +-{MAX_JOINT_VALUE:g}: the poses are too far from the robot "
            "or apart for dt and gain"
        )
