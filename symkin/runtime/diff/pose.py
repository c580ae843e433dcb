"""The pose error of the IK in JAX or PyTorch (:mod:`symkin.runtime.diff.ops`), batched and
differentiable: e = (t* - t, alpha(R* R^T)) (Haviland and Corke, Manipulator Differential
Kinematics, Part 1, 2023, eqs 37-40), as :func:`symkin.runtime.ik_problem.pose_error`.

alpha is the Euler vector of eq 38, ``theta / |l| * l`` with ``theta = atan2(|l|, tr R - 1)``;
for |l|^2 below :data:`SMALL` it is the series ``(1/2 + |l|^2 / 48) l`` (the same to rounding,
and its gradient stays finite at R = I, where the IK's solutions are); near a half turn (tr R < 0
and |l| < :data:`symkin.model.orientation.NEAR_PI_L`) the axis comes from the symmetric part of R,
its sign from l, as the NumPy and C code do (eq 40's diagonal matrices included). That branch
carries no gradient (it is never where a solution is).
"""

from __future__ import annotations

from typing import Any

from symkin.model.orientation import NEAR_PI_L
from symkin.runtime.diff.ops import Ops

__all__ = ["angle_axis", "pose_error", "SMALL"]

SMALL = 1e-8  # |l|^2 below which alpha is its series (|l| < 1e-4: the series' error < 1e-17 |l|)


def _near_pi(ops: Ops, R: Any, l: Any, theta: Any) -> Any:
    """alpha of rotations near a half turn: theta times the unit axis from the symmetric part of R
    (the column of its largest diagonal entry), signed as l."""
    xp = ops.xp
    tr = R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2]
    ct = (tr - 1.0) / 2.0
    eye = ops.const([[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]], R)
    denom = xp.where(ct < 1.0 - 1e-12, 1.0 - ct, 1.0)
    M = ((R + xp.swapaxes(R, -1, -2)) / 2.0 - ct[..., None, None] * eye) / denom[..., None, None]
    d = xp.stack((M[..., 0, 0], M[..., 1, 1], M[..., 2, 2]), -1)
    k = xp.argmax(d, -1)[..., None]
    ak = xp.sqrt(xp.where(ops.take(d, k, -1) > 0.0, ops.take(d, k, -1), 1.0))  # (..., 1)
    col = ops.take(M, k[..., None], -1)[..., 0]  # column k, (..., 3)
    ax = col / ak
    ax = xp.where(ops.const([0, 1, 2], R) == k, ak, ax)
    flip = (ax * l).sum(-1, keepdims=True) < 0.0
    return theta[..., None] * xp.where(flip, -ax, ax)


def angle_axis(ops: Ops, R: Any) -> Any:
    """alpha(R) (eqs 38-40), rotations R (..., 3, 3) -> (..., 3)."""
    xp = ops.xp
    l = xp.stack((R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]), -1)
    tr = R[..., 0, 0] + R[..., 1, 1] + R[..., 2, 2]
    s = (l * l).sum(-1)
    small = s < SMALL
    nl = xp.sqrt(xp.where(small, 1.0, s))  # the series' rows take no root (no infinite gradient)
    theta = ops.atan2(nl, tr - 1.0)
    k = xp.where(small, 0.5 + s / 48.0, theta / nl)
    general = k[..., None] * l
    near = (tr < 0.0) & (s < NEAR_PI_L * NEAR_PI_L)
    Rd, ld = ops.detach(R), ops.detach(l)
    pi = _near_pi(ops, Rd, ld, ops.atan2(xp.sqrt(ops.detach(s)), ops.detach(tr) - 1.0))
    return xp.where(near[..., None], pi, general)


def pose_error(ops: Ops, T: Any, Tep: Any) -> Any:
    """e of eq 37 for poses T, Tep (..., 4, 4) (broadcast) -> (..., 6), base frame."""
    xp = ops.xp
    R = Tep[..., :3, :3] @ xp.swapaxes(T[..., :3, :3], -1, -2)
    return xp.concatenate((Tep[..., :3, 3] - T[..., :3, 3], angle_axis(ops, R)), -1)
