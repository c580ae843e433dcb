"""Position-based servoing (seed 000, eqs 37-43): the end-effector velocity command from a pose error.

numpy only. All quantities are in the robot's base frame; spatial velocities and errors have rows
(v, omega) like the base-frame Jacobian ``jacob0``. The pose error of eq 37 is
:func:`symkin.runtime.ik.pose_error` (batched); this module has a single-pose form of it
(:func:`pose_error_1`, 7x faster for one pose, tested to agree) for the control loop.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.errors import PoseError

__all__ = ["p_servo", "servo_velocity", "servo_gain", "pose_error_1", "angle_axis_1"]

_SYM_TOL = 1e-6  # |l| below this (angle within ~1e-6 of 0 or pi): use the symmetric-matrix formulas


def angle_axis_1(R: np.ndarray) -> np.ndarray:
    """Euler vector ``alpha(R)`` (angle times unit axis) of a rotation matrix (eqs 38-40): (3,).

    ``l = (r32 - r23, r13 - r31, r21 - r12)``; ``alpha = atan2(|l|, tr R - 1) l / |l|`` (eq 38-39).
    When ``l`` vanishes, R is symmetric: the identity gives 0 and a half-turn gives pi times the axis
    read off ``(R + I) / 2 = a a^T``, which for a diagonal R is eq 40, ``pi/2 (diag(R) + 1)``. The
    half-turn formula is also used for a symmetric non-diagonal R (a half turn about a
    non-coordinate axis), where eq 40 does not apply, and within 1e-6 of a half turn, where l / |l|
    loses precision; its sign is then chosen to agree with l.
    """
    R = np.asarray(R, dtype=float)
    lx, ly, lz = R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]
    ln = math.sqrt(lx * lx + ly * ly + lz * lz)
    tr = R[0, 0] + R[1, 1] + R[2, 2]
    if ln > _SYM_TOL or tr > 1.0:  # eq 38 (tr > 1: angle below 90 deg, no precision problem)
        if ln == 0.0:
            return np.zeros(3)
        return (math.atan2(ln, tr - 1.0) / ln) * np.array([lx, ly, lz])
    # near a half turn: R ~ 2 a a^T - I, so (R + R^T)/2 + I ~ 2 a a^T
    S = 0.5 * (R + R.T) + np.eye(3)
    k = int(np.argmax(np.diag(S)))
    a = S[:, k] / math.sqrt(max(S[k, k], 1e-300))
    a /= np.linalg.norm(a)
    if a @ np.array([lx, ly, lz]) < 0.0:
        a = -a
    return math.atan2(ln, tr - 1.0) * a


def pose_error_1(Te: np.ndarray, Tep: np.ndarray) -> np.ndarray:
    """Pose error of eq 37, base frame, one pose pair: ``(t(Tep) - t(Te), alpha(R(Tep) R(Te)^T))``, (6,).

    ``Te`` is the current end-effector pose 0T_e, ``Tep`` the desired one 0T_e*, both (4, 4).
    """
    Te = _pose(Te, "Te")
    Tep = _pose(Tep, "Tep")
    e = np.empty(6)
    e[:3] = Tep[:3, 3] - Te[:3, 3]
    e[3:] = angle_axis_1(Tep[:3, :3] @ Te[:3, :3].T)
    return e


def servo_gain(gain: float | Sequence[float] | np.ndarray) -> np.ndarray:
    """The diagonal of the gain matrix k (eq 42) from a scalar, ``(k_t, k_r)`` or six values: (6,)."""
    g = np.asarray(gain, dtype=float)
    if g.ndim == 0:
        k = np.full(6, float(g))
    elif g.shape == (2,):
        k = np.repeat(g, 3)
    elif g.shape == (6,):
        k = g.copy()
    else:
        raise ValueError(f"gain must be a number, (k_t, k_r) or 6 numbers, got shape {g.shape}")
    if not np.isfinite(k).all() or (k < 0).any():
        raise ValueError(f"gain must be finite and non-negative, got {k.tolist()}")
    return k


def p_servo(
    Te: np.ndarray,
    Tep: np.ndarray,
    gain: float | Sequence[float] | np.ndarray = 1.0,
    threshold: float = 0.1,
    nu_max: float | Sequence[float] | None = None,
) -> tuple[np.ndarray, bool]:
    """Position-based servoing step from the current pose ``Te`` to ``Tep`` (both (4, 4), base frame).

    ``servo_velocity(pose_error_1(Te, Tep), gain, threshold, nu_max)``: returns the end-effector
    velocity ``nu`` (6,) and whether the target is reached.
    """
    return servo_velocity(pose_error_1(Te, Tep), gain, threshold, nu_max)


def servo_velocity(
    e: np.ndarray,
    gain: float | Sequence[float] | np.ndarray = 1.0,
    threshold: float = 0.1,
    nu_max: float | Sequence[float] | None = None,
) -> tuple[np.ndarray, bool]:
    """Commanded velocity ``nu`` (6,) for the pose error ``e`` (6,) (eq 37), and whether it is arrived.

    ``nu = k e`` (eq 41) with ``k = diag(gain)`` (eq 42: a scalar, ``(k_t, k_r)`` or six gains).
    ``arrived`` is ``sum |e| < threshold`` (the arrival test of seed 001's experiments); once
    arrived, ``nu = 0`` (eq 43, third case).

    ``nu_max`` caps the commanded velocity (eq 43): a number caps ``|k e|`` over all six rows, which
    mixes m/s with rad/s (Excurse 1); a pair ``(v_max, omega_max)`` caps the translational and
    rotational parts separately, each keeping its direction. ``None`` (default) applies no cap.
    """
    if threshold < 0:
        raise ValueError(f"threshold must be non-negative, got {threshold}")
    if float(np.abs(e).sum()) < threshold:
        return np.zeros(6), True
    nu = servo_gain(gain) * e
    if nu_max is not None:
        cap = np.asarray(nu_max, dtype=float)
        if cap.ndim == 0:
            _cap(nu, slice(0, 6), float(cap))
        elif cap.shape == (2,):
            _cap(nu, slice(0, 3), float(cap[0]))
            _cap(nu, slice(3, 6), float(cap[1]))
        else:
            raise ValueError(f"nu_max must be a number or (v_max, omega_max), got shape {cap.shape}")
    return nu, False


def _cap(nu: np.ndarray, rows: slice, limit: float) -> None:
    if not limit > 0:
        raise ValueError(f"velocity caps must be positive, got {limit}")
    norm = float(np.linalg.norm(nu[rows]))
    if norm > limit:
        nu[rows] *= limit / norm


def _pose(T: Any, what: str) -> np.ndarray:
    T = np.asarray(T, dtype=float)
    if T.shape != (4, 4):
        raise PoseError(f"{what} must be a 4x4 homogeneous transform, got shape {T.shape}")
    if not np.isfinite(T).all():
        raise PoseError(f"{what} contains NaN or inf")
    return T
