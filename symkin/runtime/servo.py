"""Position-based servoing (Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, eqs
37-43): the end-effector velocity command from a pose error.

numpy only. All quantities are in the robot's base frame; spatial velocities and errors have rows
(v, omega) like the base-frame Jacobian ``jacob0``. The pose error of eq 37 is
:func:`symkin.runtime.ik.pose_error`.
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.core.arrays import real_array
from symkin.errors import ParameterError, PoseError
from symkin.runtime.ik import pose_error

__all__ = ["p_servo", "servo_velocity", "servo_gain", "pose_error_checked"]


def pose_error_checked(Te: Any, Tep: Any) -> np.ndarray:
    """Pose error of eq 37 (:func:`symkin.runtime.ik.pose_error`) of one validated pose pair, (6,)."""
    return pose_error(_pose(Te, "Te"), _pose(Tep, "Tep"))


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


def p_servo(
    Te: np.ndarray,
    Tep: np.ndarray,
    gain: float | Sequence[float] | np.ndarray = 1.0,
    threshold: float = 0.1,
    nu_max: float | Sequence[float] | None = None,
) -> tuple[np.ndarray, bool]:
    """Position-based servoing step from the current pose ``Te`` to ``Tep`` (both (4, 4), base frame).

    ``servo_velocity(pose_error_checked(Te, Tep), gain, threshold, nu_max)``: returns the end-effector
    velocity ``nu`` (6,) and whether the target is reached.
    """
    return servo_velocity(pose_error_checked(Te, Tep), gain, threshold, nu_max)


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
    if not (isinstance(threshold, numbers.Real) and math.isfinite(threshold) and threshold >= 0):
        raise ParameterError(f"threshold must be a finite number >= 0, got {threshold!r}")
    if float(np.abs(e).sum()) < threshold:
        return np.zeros(6), True
    nu = servo_gain(gain) * e
    if nu_max is not None:
        cap = real_array(nu_max, "nu_max", ParameterError)
        if cap.ndim == 0:
            _cap(nu, slice(0, 6), float(cap))
        elif cap.shape == (2,):
            _cap(nu, slice(0, 3), float(cap[0]))
            _cap(nu, slice(3, 6), float(cap[1]))
        else:
            raise ParameterError(f"nu_max must be a number or (v_max, omega_max), got shape {cap.shape}")
    return nu, False


def _cap(nu: np.ndarray, rows: slice, limit: float) -> None:
    if not limit > 0:
        raise ParameterError(f"velocity caps must be positive, got {limit}")
    s = 0.0
    for v in nu[rows].tolist():  # summed in order, as the C servo loop does
        s += v * v
    norm = math.sqrt(s)
    if norm > limit:
        nu[rows] *= limit / norm


def _pose(T: Any, what: str) -> np.ndarray:
    T = real_array(T, what, PoseError)
    if T.shape != (4, 4):
        raise PoseError(f"{what} must be a 4x4 homogeneous transform, got shape {T.shape}")
    if not np.isfinite(T).all():
        raise PoseError(f"{what} contains NaN or inf")
    return T
