"""Spatial velocity and wrench transforms between frames, and joint torques of a wrench (numpy only).

Velocities and wrenches are 6-vectors with symkin's row order: (v, omega) (m/s, rad/s) like
``jacob0`` and (f, m) (N, N m). Poses follow the one pose rule (:mod:`symkin.core.pose`): PoseError
for a T that is not SE(3).

References: Corke, Robotics, Vision and Control, 3rd ed., 2023, chap 3 and 8; Lynch and Park,
Modern Robotics, 2017, secs 3.3.2 and 3.4 (rows swapped: their twists are (omega, v)).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.core.pose import as_poses

__all__ = ["skew", "velocity_transform", "wrench_transform", "joint_torques"]


def _as_se3(T: Any) -> np.ndarray:
    """T (4, 4) or (N, 4, 4) by the one pose rule (:func:`symkin.core.pose.as_poses`), same shape."""
    A, single = as_poses(T, "T")
    return A[0] if single else A


def skew(p: np.ndarray) -> np.ndarray:
    """The cross-product matrices ``[p]x`` (..., 3, 3) of vectors ``p`` (..., 3)."""
    S = np.zeros((*p.shape[:-1], 3, 3))
    S[..., 0, 1], S[..., 0, 2], S[..., 1, 2] = -p[..., 2], p[..., 1], -p[..., 0]
    S[..., 1, 0], S[..., 2, 0], S[..., 2, 1] = p[..., 2], -p[..., 1], p[..., 0]
    return S


def velocity_transform(T: Any) -> np.ndarray:
    """The (6, 6) matrix (or (N, 6, 6)) ``[[R, [t]x R], [0, R]]`` of ``T = aT_b = (R, t)``: it maps the
    spatial velocity (v, omega) of a rigid body, expressed in frame {B} with v the velocity of the
    body's point at the origin of {B}, to the same motion expressed in frame {A} with v that of the
    body's point at the origin of {A}: ``(v_a, w_a) = (R v_b + t x (R w_b), R w_b)`` (m/s, rad/s).

    This is the adjoint of T with symkin's row order (v, omega) (Corke, Robotics, Vision and Control,
    3rd ed., 2023, chap 3 and 8; Lynch and Park, Modern Robotics, 2017, sec 3.3.2, rows
    swapped). It composes, ``velocity_transform(T1 @ T2) = velocity_transform(T1) @
    velocity_transform(T2)``, and ``velocity_transform(inv(T))`` is its inverse. Note that
    ``jacob0`` and ``jacobe`` describe the velocity of one point (the frame's origin) and differ by
    the rotation ``blkdiag(R, R)`` alone. PoseError for a T that is not SE(3).
    """
    A = _as_se3(T)
    R, t = A[..., :3, :3], A[..., :3, 3]
    X = np.zeros((*A.shape[:-2], 6, 6))
    X[..., :3, :3] = R
    X[..., 3:, 3:] = R
    X[..., :3, 3:] = skew(t) @ R
    return X


def wrench_transform(T: Any) -> np.ndarray:
    """The (6, 6) matrix (or (N, 6, 6)) ``[[R, 0], [[t]x R, R]]`` of ``T = aT_b = (R, t)``, the inverse
    transpose of :func:`velocity_transform`: it maps a wrench (f, m) expressed in {B}, m the moment
    about the origin of {B}, to the same wrench expressed in {A} with the moment about the origin of
    {A}: ``(f_a, m_a) = (R f_b, t x (R f_b) + R m_b)`` (N, N m). The power ``w . v`` of a wrench on
    a motion is the same in both frames (Corke, Robotics, Vision and Control, 3rd ed., 2023, chap
    3 and 8; Lynch and Park, Modern Robotics, 2017, sec 3.4, rows swapped). PoseError for a T
    that is not SE(3).
    """
    X = velocity_transform(T)
    X[..., 3:, :3], X[..., :3, 3:] = X[..., :3, 3:], 0.0  # [t]x R moved to the lower left block
    return X


def joint_torques(kin: Any, q: Any, wrench: Any, frame: Any = None, in_frame: str = "base") -> np.ndarray:
    """``kin.joint_torques(q, wrench, frame, in_frame)``: the joint forces/torques ``tau = J^T w``
    (n,) or (N, n) that hold the wrench ``w`` = (f, m) (6,) or (N, 6) the robot exerts at ``frame``,
    expressed in the base frame (``in_frame="base"``, J = jacob0) or in ``frame`` (``"ee"``, J =
    jacobe); see :meth:`symkin.model.differential.FrameMethods.joint_torques`. ``kin`` is a
    :class:`symkin.Robot`, a :class:`symkin.Tree` or compiled :class:`symkin.Kinematics`.
    """
    return kin.joint_torques(q, wrench, frame=frame, in_frame=in_frame)
