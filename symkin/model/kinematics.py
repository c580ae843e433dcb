"""Numeric building blocks of the reference kinematics (numpy only): the 4x4 matrix of an
elementary transform (Fig. 2 of Haviland and Corke, Manipulator Differential Kinematics, Part 1,
2023) and a small cross product; the kernel itself is :mod:`symkin.model.numeric`."""

from __future__ import annotations

import math

import numpy as np

from symkin.model.ets import Axis, Const

__all__ = ["et_matrix", "const_matrix", "cross", "ROT_SLICES"]

ROT_SLICES = {0: (1, 2), 1: (2, 0), 2: (0, 1)}  # rotation about i mixes columns (j, k)


def et_matrix(axis: Axis, value: float) -> np.ndarray:
    """The 4x4 matrix of one elementary transform (Fig. 2) at ``value``."""
    T = np.eye(4)
    i = axis.index
    if axis.is_rotation:
        j, k = ROT_SLICES[i]
        c, s = math.cos(value), math.sin(value)
        T[j, j], T[j, k], T[k, j], T[k, k] = c, -s, s, c
    else:
        T[i, 3] = value
    return T


def const_matrix(axis: Axis, const: Const) -> np.ndarray:
    """Like :func:`et_matrix`, exact (0, +-1 entries) for rotations by multiples of pi/2."""
    k = const.quarter_turns
    if axis.is_rotation and k is not None:
        T = np.eye(4)
        j, l_ = ROT_SLICES[axis.index]
        c, s = ((1, 0), (0, 1), (-1, 0), (0, -1))[k]
        T[j, j], T[j, l_], T[l_, j], T[l_, l_] = c, -s, s, c
        return T
    return et_matrix(axis, const.value)


def cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Cross product along the last axis (faster than np.cross for small arrays)."""
    return np.stack(
        (
            a[..., 1] * b[..., 2] - a[..., 2] * b[..., 1],
            a[..., 2] * b[..., 0] - a[..., 0] * b[..., 2],
            a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0],
        ),
        axis=-1,
    )
