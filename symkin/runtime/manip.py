"""Manipulability of one configuration without a determinant routine (Haviland and Corke, Manipulator
Differential Kinematics, Part 1, 2023, eq 52; Maximising Manipulability During Resolved-Rate Motion Control,
2020, eq 11).

For one configuration the batched helpers of :mod:`symkin.model.robot` (``numpy.linalg.det`` and
``inv`` over a stack) cost more than the kinematics. Here ``m = sqrt(det(Jr Jr^T))`` comes from the
closed form for the 3 x 3 Gram matrix of ``axes="trans"``/``"rot"`` and, for the 6 x 6 one of
``axes="all"``, from symmetric Gaussian elimination written out as straight-line code (the product
of the pivots; a non-positive pivot means a singular Jacobian and m = 0).
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["manipulability_one", "jacobm_one"]


def manipulability_one(Jr: np.ndarray) -> float:
    """sqrt(det(Jr Jr^T)) (eq 52) of one (r, n) Jacobian, r = 3 or 6 (other r: numpy's det);
    0 where Jr Jr^T is singular, exactly 0 with fewer joints than rows."""
    if Jr.shape[1] < Jr.shape[0]:
        return 0.0
    G = (Jr @ Jr.T).tolist()
    r = len(G)
    if r == 6:
        d = _det6_spd(G)
    elif r == 3:
        (a, b, c), (_, e, f), (_, _, i) = G
        d = a * (e * i - f * f) - b * (b * i - f * c) + c * (b * f - e * c)
    else:
        d = float(np.linalg.det(np.array(G))) if r else 1.0
    return math.sqrt(d) if d > 0.0 else 0.0


def jacobm_one(Jr: np.ndarray, Hr: np.ndarray) -> np.ndarray:
    """Manipulability Jacobian (MMC paper eq 11) of one configuration: Jr (r, n), Hr (n, r, n) -> (n,),
    ``Jm_i = m sum(H_i * (Jr Jr^T)^-1 Jr)``; zeros where Jr Jr^T is singular (m = 0)."""
    m = manipulability_one(Jr)
    if m == 0.0:
        return np.zeros(Hr.shape[0])
    return m * np.einsum("irk,rk->i", Hr, np.linalg.solve(Jr @ Jr.T, Jr))


def _det6_spd(G: list[list[float]]) -> float:
    """det G of a symmetric 6 x 6 G (nested lists) by Gaussian elimination on its upper triangle,
    written out; 0 at a non-positive pivot (G singular or not positive definite)."""
    a00, a01, a02, a03, a04, a05 = G[0]
    _, a11, a12, a13, a14, a15 = G[1]
    _, _, a22, a23, a24, a25 = G[2]
    _, _, _, a33, a34, a35 = G[3]
    _, _, _, _, a44, a45 = G[4]
    _, _, _, _, _, a55 = G[5]
    det = 1.0
    if not a00 > 0.0:
        return 0.0
    det *= a00
    f = a01 / a00
    a11 -= f * a01
    a12 -= f * a02
    a13 -= f * a03
    a14 -= f * a04
    a15 -= f * a05
    f = a02 / a00
    a22 -= f * a02
    a23 -= f * a03
    a24 -= f * a04
    a25 -= f * a05
    f = a03 / a00
    a33 -= f * a03
    a34 -= f * a04
    a35 -= f * a05
    f = a04 / a00
    a44 -= f * a04
    a45 -= f * a05
    f = a05 / a00
    a55 -= f * a05
    if not a11 > 0.0:
        return 0.0
    det *= a11
    f = a12 / a11
    a22 -= f * a12
    a23 -= f * a13
    a24 -= f * a14
    a25 -= f * a15
    f = a13 / a11
    a33 -= f * a13
    a34 -= f * a14
    a35 -= f * a15
    f = a14 / a11
    a44 -= f * a14
    a45 -= f * a15
    f = a15 / a11
    a55 -= f * a15
    if not a22 > 0.0:
        return 0.0
    det *= a22
    f = a23 / a22
    a33 -= f * a23
    a34 -= f * a24
    a35 -= f * a25
    f = a24 / a22
    a44 -= f * a24
    a45 -= f * a25
    f = a25 / a22
    a55 -= f * a25
    if not a33 > 0.0:
        return 0.0
    det *= a33
    f = a34 / a33
    a44 -= f * a34
    a45 -= f * a35
    f = a35 / a33
    a55 -= f * a35
    if not a44 > 0.0:
        return 0.0
    det *= a44
    f = a45 / a44
    a55 -= f * a45
    if not a55 > 0.0:
        return 0.0
    det *= a55
    return det
