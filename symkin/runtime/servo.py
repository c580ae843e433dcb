"""Position-based servoing (Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, eqs
37-43): the end-effector velocity command from a pose error.

numpy only. Poses are in the robot's base frame; spatial velocities and errors have rows (v, omega),
in the base frame like ``jacob0`` (what the servo loops use), or, from ``p_servo(..., frame="ee")``,
in the end-effector frame like ``jacobe``. The pose error of eq 37 is
:func:`symkin.runtime.ik.pose_error`.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.core.arrays import real_array
from symkin.core.pose import as_pose
from symkin.errors import ParameterError
from symkin.runtime.ik import pose_error_of

__all__ = ["p_servo", "servo_velocity", "servo_gain", "pose_error_checked", "SERVO_FRAMES"]


def pose_error_checked(Te: Any, Tep: Any) -> np.ndarray:
    """Pose error of eq 37 (:func:`symkin.runtime.ik.pose_error`) of one pose pair validated by the
    one pose rule (:func:`symkin.core.pose.as_pose`), (6,)."""
    return pose_error_of(as_pose(Te, "Te"), as_pose(Tep, "Tep"))


def servo_gain(gain: float | Sequence[float] | np.ndarray) -> np.ndarray:
    """The diagonal of the gain matrix k (eq 42) from a scalar, ``(k_t, k_r)`` or six values: (6,)."""
    g = real_array(gain, "gain", ParameterError)
    if g.ndim == 0:
        k = np.full(6, float(g))
    elif g.shape == (2,):
        k = np.repeat(g, 3)
    elif g.shape == (6,):
        k = g.copy()
    else:
        raise ParameterError(f"gain must be a number, (k_t, k_r) or 6 numbers, got shape {g.shape}")
    if not np.isfinite(k).all() or (k < 0).any():
        raise ParameterError(f"gain must be finite and non-negative, got {k.tolist()}")
    return k


SERVO_FRAMES = ("base", "ee")


def p_servo(
    Te: np.ndarray,
    Tep: np.ndarray,
    gain: float | Sequence[float] | np.ndarray = 1.0,
    threshold: float = 0.1,
    nu_max: float | Sequence[float] | None = None,
    *,
    frame: str | None = None,
) -> tuple[np.ndarray, bool]:
    """Position-based servoing step from the current pose ``Te`` to ``Tep`` (both (4, 4), base frame):
    the velocity ``nu`` (6,) that drives the end effector toward ``Tep``, and whether it is there.

    ``frame`` (required, keyword) says in which frame ``nu`` (rows (v, omega)) is expressed:

    - ``"base"``: the base frame, for ``qd = pinv(jacob0(q)) @ nu``: ``servo_velocity(e, gain,
      threshold, nu_max)`` of the pose error e of eq 37 (what :func:`symkin.servo` commands);
    - ``"ee"``: the end-effector frame of ``Te``, for ``qd = pinv(jacobe(q)) @ nu``: the same with
      e rotated into that frame, ``(R^T e_v, R^T e_omega)`` (R the rotation of ``Te``), so the
      gains, the arrival test ``sum |e| < threshold`` and the caps apply to its axes.

    There is no default: roboticstoolbox-python's ``p_servo`` returns an end-effector-frame velocity
    (its default ``method="rpy"``; ``method="angle-axis"`` gives symkin's ``"base"``), so a ported
    ``jacobe`` loop given the base-frame velocity would move the arm the wrong way without an error.
    PoseError when ``Te`` or ``Tep`` is not SE(3) (the one pose rule).
    """
    if frame not in SERVO_FRAMES:
        raise ParameterError(
            f"p_servo needs frame='base' (nu in the base frame, for jacob0) or frame='ee' (in the "
            f"end-effector frame, for jacobe; roboticstoolbox-python's p_servo default), not {frame!r}"
        )
    A = as_pose(Te, "Te")
    e = pose_error_of(A, as_pose(Tep, "Tep"))
    if frame == "ee":
        R = A[:3, :3]
        e = np.concatenate((R.T @ e[:3], R.T @ e[3:]))
    return servo_velocity(e, gain, threshold, nu_max)


def servo_velocity(
    e: np.ndarray,
    gain: float | Sequence[float] | np.ndarray = 1.0,
    threshold: float = 0.1,
    nu_max: float | Sequence[float] | None = None,
) -> tuple[np.ndarray, bool]:
    """Commanded velocity ``nu`` (6,) for the pose error ``e`` (6,) (eq 37), and whether it is arrived.

    ``nu = k e`` (eq 41) with ``k = diag(gain)`` (eq 42: a scalar, ``(k_t, k_r)`` or six gains).
    ``arrived`` is ``sum |e| < threshold`` (the arrival test of the experiments of Haviland and Corke's MMC
    paper, 2020); once arrived, ``nu = 0`` (eq 43, third case).

    ``nu_max`` caps the commanded velocity (eq 43): a number caps ``|k e|`` over all six rows, which
    mixes m/s with rad/s (Excurse 1); a pair ``(v_max, omega_max)`` caps the translational and
    rotational parts separately, each keeping its direction. ``None`` (default) applies no cap.
    """
    check_threshold(threshold)
    if float(np.abs(e).sum()) < threshold:
        return np.zeros(6), True
    nu = servo_gain(gain) * e
    for rows, limit in velocity_caps(nu_max):
        _cap(nu, rows, limit)
    return nu, False


def check_threshold(threshold: Any) -> None:
    """ParameterError unless the arrival threshold is a finite number >= 0."""
    if not (isinstance(threshold, numbers.Real) and math.isfinite(threshold) and threshold >= 0):
        raise ParameterError(f"threshold must be a finite number >= 0, got {threshold!r}")


def velocity_caps(nu_max: Any) -> list[tuple[slice, float]]:
    """The caps of ``nu_max`` (eq 43) as (rows of nu, limit) pairs: none for None, all six rows for a
    number, the translational and rotational rows for ``(v_max, omega_max)``; ParameterError for
    another shape or a limit that is not positive."""
    if nu_max is None:
        return []
    cap = real_array(nu_max, "nu_max", ParameterError)
    if cap.ndim != 0 and cap.shape != (2,):
        raise ParameterError(f"nu_max must be a number or (v_max, omega_max), got shape {cap.shape}")
    if not (cap > 0).all():
        raise ParameterError(f"velocity caps must be positive, got {cap.tolist()}")
    return (
        [(slice(0, 6), float(cap))]
        if cap.ndim == 0
        else [(slice(0, 3), float(cap[0])), (slice(3, 6), float(cap[1]))]
    )


def _cap(nu: np.ndarray, rows: slice, limit: float) -> None:
    s = 0.0
    for v in nu[rows].tolist():  # summed in order, as the C servo loop does
        s += v * v
    norm = math.sqrt(s)
    if norm > limit:
        nu[rows] *= limit / norm
