"""Rotations and poses for the runtime tests (numpy only)."""

from __future__ import annotations

import math

import numpy as np

from symkin.runtime.ik import angle_axis


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


def geodesic_angle(Ra: np.ndarray, Rb: np.ndarray) -> np.ndarray:
    """Rotation angle(s) of Rb Ra^T."""
    return np.linalg.norm(angle_axis(Rb @ np.swapaxes(Ra, -1, -2)), axis=-1)
