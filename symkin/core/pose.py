"""The one rule for poses (leaf module): what every function that takes a homogeneous transform
accepts (IK and servo targets, the Cartesian path's ends and poses, velocity and wrench transforms,
pose errors, tool and base offsets, a PoE home pose, the view's target).

A pose is a (4, 4) matrix ``[[R, t], [0, 1]]`` (or a stack (N, 4, 4) where a function takes
several), converted by :func:`symkin.core.arrays.real_array` (any real dtype, byte order or
layout; complex numbers, strings and numbers beyond a double refused), or a spatialmath ``SE3``
(its ``.A``, one pose or several). It is refused when it holds NaN or inf, when its bottom row
differs from (0, 0, 0, 1) by more than 1e-12, when ``max |R^T R - I| > 1e-6`` (:data:`POSE_ATOL`)
or when R is a reflection (det R <= 0). The C solvers and the C servo loop check the same rule
(``csrc/symkin_pose.h``).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.core.arrays import real_array
from symkin.errors import PoseError, SymkinError

__all__ = ["POSE_ATOL", "BOTTOM_ATOL", "pose_array", "as_poses", "as_pose"]

POSE_ATOL = 1e-6  # max |R^T R - I| of an accepted pose
BOTTOM_ATOL = 1e-12  # max |bottom row - (0, 0, 0, 1)|


def pose_array(T: Any, what: str = "target", error: type[SymkinError] = PoseError) -> np.ndarray:
    """``T`` as a float64 array by the conversion rule, a spatialmath ``SE3`` (one or several
    values) as its matrices (``np.asarray`` of an SE3 holding several poses gives the first alone).
    The values are not checked: see :func:`as_poses`."""
    if not isinstance(T, np.ndarray):
        A = getattr(T, "A", None)  # spatialmath SE3: .A is (4, 4), or a list of them
        if isinstance(A, np.ndarray) or (isinstance(A, list) and A and isinstance(A[0], np.ndarray)):
            T = np.stack(A) if isinstance(A, list) else A
    return real_array(T, _label(what, None), error)


def _label(what: str, i: int | None) -> str:
    """How a message names the pose: "the target", "target [3]", "T0", "poses [3]"."""
    if i is None:
        return "the target" if what == "target" else what
    return f"{what} [{i}]"


def as_poses(
    T: Any, what: str = "target", error: type[SymkinError] = PoseError, batch: bool = True
) -> tuple[np.ndarray, bool]:
    """Validate one pose (4, 4) or, with ``batch``, several (N, 4, 4) -> ((N, 4, 4) float array,
    was_single), or raise ``error`` (PoseError; RobotError for a robot's tool, base or home pose)
    naming ``what`` and, in a stack, the index of the first bad pose. N = 0 is a valid batch."""
    A = pose_array(T, what, error)
    single = A.ndim == 2
    if A.shape[-2:] != (4, 4) or A.ndim not in ((2, 3) if batch else (2,)):
        shapes = "(4, 4) or (N, 4, 4)" if batch else "(4, 4)"
        label = _label(what, None)
        raise error(f"{label} must be a 4x4 homogeneous transform, shape {shapes}, got shape {A.shape}")
    if single:
        A = A[None]

    def where(i: int) -> str:
        return _label(what, None if single else i)

    bad = ~np.isfinite(A).all(axis=(1, 2))
    if bad.any():
        raise error(f"{where(int(np.argmax(bad)))} contains NaN or inf")
    bottom = np.abs(A[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1, initial=0.0) > BOTTOM_ATOL
    if bottom.any():
        i = int(np.argmax(bottom))
        raise error(f"{where(i)} has bottom row {A[i, 3].tolist()}, not [0, 0, 0, 1]")
    R = A[:, :3, :3]
    dev = np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max(axis=(1, 2), initial=0.0)
    if (dev > POSE_ATOL).any():
        i = int(np.argmax(dev > POSE_ATOL))
        raise error(f"{where(i)} rotation is not orthonormal: max |R^T R - I| = {dev[i]:.3g} > {POSE_ATOL:g}")
    det = np.linalg.det(R) if len(R) else np.zeros(0)
    if (det <= 0).any():
        i = int(np.argmax(det <= 0))
        raise error(f"{where(i)} rotation is a reflection (det R = {det[i]:.3g})")
    return A, single


def as_pose(T: Any, what: str = "target", error: type[SymkinError] = PoseError) -> np.ndarray:
    """One validated pose (4, 4) by :func:`as_poses`' rule; a stack is refused."""
    return as_poses(T, what, error, batch=False)[0][0]
