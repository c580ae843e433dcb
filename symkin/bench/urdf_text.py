"""A serial chain as URDF text, so that a peer that reads only URDF (pytorch_kinematics) runs the
very robot symkin compiled.

Each joint's ``origin`` is the product of the constant transforms since the previous joint (xyz
and roll-pitch-yaw, ``R = Rz(yaw) Ry(pitch) Rx(roll)``), its ``axis`` the joint's unit axis, negated
for a flipped joint; the constants after the last joint go into a fixed joint to the link ``ee``.
Revolute joints without finite limits are ``continuous``. Links are ``base``, ``link1`` .. ``link<n>``
and ``ee``; joints keep the robot's joint names. :func:`symkin.Robot.from_urdf` reads it back to
the same forward kinematics (tested).
"""

from __future__ import annotations

import math
from typing import Any
from xml.sax.saxutils import quoteattr

import numpy as np

from symkin.model.kinematics import et_matrix

__all__ = ["chain_urdf"]


def _origin(C: np.ndarray) -> str:
    R = C[:3, :3]
    roll = math.atan2(R[2, 1], R[2, 2])
    pitch = math.atan2(-R[2, 0], math.hypot(R[2, 1], R[2, 2]))
    yaw = math.atan2(R[1, 0], R[0, 0])
    xyz = " ".join(repr(float(x)) for x in C[:3, 3])
    return f'<origin xyz="{xyz}" rpy="{roll!r} {pitch!r} {yaw!r}"/>'


def chain_urdf(robot: Any) -> str:
    """URDF text of the serial chain ``robot`` (a :class:`symkin.Robot`); see the module docstring."""
    qlim, names = np.asarray(robot.qlim, dtype=float), robot.joint_names
    lines = [f"<robot name={quoteattr(robot.name)}>", '  <link name="base"/>']
    C, parent, k = np.eye(4), "base", 0
    for et in robot.ets:
        if not et.is_joint:
            C = C @ et_matrix(et.axis, et.const.value)
            continue
        k += 1
        j = et.joint
        lo, hi = float(qlim[0, j]), float(qlim[1, j])
        kind = (
            "prismatic" if et.is_prismatic else ("revolute" if np.isfinite([lo, hi]).all() else "continuous")
        )
        axis = [0.0, 0.0, 0.0]
        axis[et.axis.index] = float(et.sign)
        limit = (
            f'<limit lower="{lo!r}" upper="{hi!r}" effort="1" velocity="1"/>' if kind != "continuous" else ""
        )
        lines += [
            f'  <link name="link{k}"/>',
            f'  <joint name={quoteattr(names[j])} type="{kind}"><parent link="{parent}"/>'
            f'<child link="link{k}"/>{_origin(C)}<axis xyz="{" ".join(map(repr, axis))}"/>{limit}</joint>',
        ]
        C, parent = np.eye(4), f"link{k}"
    lines += [
        '  <link name="ee"/>',
        f'  <joint name="ee_fixed" type="fixed"><parent link="{parent}"/><child link="ee"/>'
        f"{_origin(C)}</joint>",
        "</robot>",
    ]
    return "\n".join(lines) + "\n"
