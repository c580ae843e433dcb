"""Small URDF trees for the tree tests (no external data): a quadruped-like body with two legs and
a tail, an arm with a camera beside its tool, and a gripper with mimic joints."""

from __future__ import annotations


def joint(
    name: str,
    parent: str,
    child: str,
    kind: str = "revolute",
    xyz: str = "0 0 0",
    rpy: str = "0 0 0",
    axis: str | None = "0 0 1",
    limit: str = 'lower="-2.5" upper="2.5" velocity="2" effort="1"',
    extra: str = "",
) -> str:
    ax = f'<axis xyz="{axis}"/>' if axis is not None else ""
    lim = f"<limit {limit}/>" if limit else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/>{ax}{lim}{extra}</joint>'
    )


def urdf(links: list[str], joints: list[str], name: str = "test") -> str:
    body = "\n  ".join([f'<link name="{n}"/>' for n in links] + joints)
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n  {body}\n</robot>\n'


def fixed(name: str, parent: str, child: str, xyz: str = "0 0 0", rpy: str = "0 0 0") -> str:
    return joint(name, parent, child, kind="fixed", xyz=xyz, rpy=rpy, axis=None, limit="")


# Two legs (hip about x, hip and knee about y, a fixed foot) and a tail with a prismatic joint
# and an axis in the yz-plane; the right leg's knee axis is general (exact atan2 constants) and
# its hip is continuous. Depth first, children in file order: left leg, tail, right leg.
QUADRUPED = urdf(
    ["body", "l_hip", "l_thigh", "l_shank", "l_foot", "tail1", "tail2", "tail_tip", "r_hip", "r_thigh",
     "r_shank", "r_foot"],
    [
        joint("l_haa", "body", "l_hip", xyz="0.2 0.1 0", axis="1 0 0"),
        joint("l_hfe", "l_hip", "l_thigh", xyz="0 0.05 0", axis="0 1 0"),
        joint("l_kfe", "l_thigh", "l_shank", xyz="0 0 -0.2", rpy="0.1 0 0", axis="0 1 0"),
        fixed("l_ankle", "l_shank", "l_foot", xyz="0 0 -0.2"),
        joint("tail_slide", "body", "tail1", kind="prismatic", xyz="-0.25 0 0.05", axis="-1 0 0",
              limit='lower="0" upper="0.1" velocity="0.5" effort="1"'),
        joint("tail_bend", "tail1", "tail2", xyz="-0.05 0 0", rpy="0 0.3 0", axis="0 0.6 0.8"),
        fixed("tail_end", "tail2", "tail_tip", xyz="-0.1 0 0"),
        joint("r_haa", "body", "r_hip", kind="continuous", xyz="0.2 -0.1 0", rpy="1.5707963267948966 0 0",
              axis="1 0 0", limit=""),
        joint("r_hfe", "r_hip", "r_thigh", xyz="0 -0.05 0", axis="0 0 -1"),
        joint("r_kfe", "r_thigh", "r_shank", xyz="0 -0.2 0", axis="0.2 0.3 0.9"),
        fixed("r_ankle", "r_shank", "r_foot", xyz="0 -0.2 0.01", rpy="0 0 0.2"),
    ],
    name="quad",
)  # fmt: skip

# A 4-joint arm with a camera on its second link beside the tool.
ARM_CAMERA = urdf(
    ["base", "a1", "a2", "camera", "a3", "a4", "tool"],
    [
        joint("j1", "base", "a1", xyz="0 0 0.3"),
        joint("j2", "a1", "a2", rpy="-1.5707963267948966 0 0"),
        fixed("cam_mount", "a2", "camera", xyz="0.05 0.1 0", rpy="0 1.2 0"),
        joint("j3", "a2", "a3", xyz="0.4 0 0"),
        joint("j4", "a3", "a4", xyz="0.3 0 0.02", rpy="1.5707963267948966 0 0"),
        fixed("flange", "a4", "tool", xyz="0 0 0.1"),
    ],
    name="arm_cam",
)

# An arm with a gripper: finger b mimics finger a (multiplier -1, offset 0.01, prismatic); on
# finger a a revolute tip mimics the wrist (multiplier 2, offset 0.1, so its column adds to the
# wrist's on the same path) and a second tip mimics the first (a mimic of a mimic).
GRIPPER = urdf(
    ["base", "l1", "l2", "palm", "fa", "fa_tip", "fa_tip2", "fb"],
    [
        joint("shoulder", "base", "l1", xyz="0 0 0.2", axis="0 1 0"),
        joint("wrist", "l1", "l2", xyz="0.3 0 0", axis="1 0 0"),
        fixed("palm_mount", "l2", "palm", xyz="0.05 0 0"),
        joint("finger_a", "palm", "fa", kind="prismatic", xyz="0.02 0.01 0", axis="0 1 0",
              limit='lower="0" upper="0.04" velocity="0.1" effort="1"'),
        joint("tip_a", "fa", "fa_tip", xyz="0.03 0 0", axis="0 0 1",
              extra='<mimic joint="wrist" multiplier="2" offset="0.1"/>'),
        joint("tip_a2", "fa_tip", "fa_tip2", xyz="0.02 0 0", axis="0 0 1",
              extra='<mimic joint="tip_a" multiplier="-0.5"/>'),
        joint("finger_b", "palm", "fb", kind="prismatic", xyz="0.02 -0.01 0", axis="0 1 0",
              limit='lower="-0.04" upper="0" velocity="0.1" effort="1"',
              extra='<mimic joint="finger_a" multiplier="-1" offset="0.01"/>'),
    ],
    name="gripper",
)  # fmt: skip

# GRIPPER with every mimic joint made independent (the same transforms), to check the mimic rule.
GRIPPER_FREE = (
    GRIPPER.replace('<mimic joint="wrist" multiplier="2" offset="0.1"/>', "")
    .replace('<mimic joint="tip_a" multiplier="-0.5"/>', "")
    .replace('<mimic joint="finger_a" multiplier="-1" offset="0.01"/>', "")
)

# A dual-arm robot: a torso joint, then two 6-joint arms (UR-like axes) with tools.
_ARM_AXES = ["0 0 1", "0 1 0", "0 1 0", "0 1 0", "0 0 1", "0 1 0"]
_ARM_XYZ = ["0 {y} 0.3", "0 0.1 0.1", "0.4 0 0", "0.35 0 0", "0 0.1 0", "0 0 0.1"]


def _arm(side: str, y: str) -> list[str]:
    links = ["torso", *(f"{side}{i}" for i in range(1, 7))]
    out = [
        joint(f"{side}_j{i + 1}", links[i], links[i + 1], xyz=_ARM_XYZ[i].format(y=y), axis=_ARM_AXES[i],
              limit='lower="-3.1" upper="3.1" velocity="3" effort="1"')
        for i in range(6)
    ]  # fmt: skip
    return [*out, fixed(f"{side}_flange", f"{side}6", f"{side}_tool", xyz="0 0 0.08")]


DUAL_ARM = urdf(
    ["base", "torso", *(f"{s}{i}" for s in "lr" for i in range(1, 7)), "l_tool", "r_tool"],
    [joint("waist", "base", "torso", xyz="0 0 0.8", limit='lower="-1" upper="1" velocity="1" effort="1"'),
     *_arm("l", "0.2"), *_arm("r", "-0.2")],
    name="dual",
)  # fmt: skip
