"""A small tree for the view's tests: a torso turning on a base, a head and two two-link arms, with
collision spheres, cylinders (capsules) and a box (spheres), visual boxes, cylinders, spheres and
one mesh file found through ``package://``; and example-robot-data's Solo-12 when it is installed."""

from __future__ import annotations

from pathlib import Path

import pytest

from symkin.bench.tree import erd_robots_dir

_LINK = """<link name="{name}">
  <visual><origin xyz="{vxyz}" rpy="0 0 0"/><geometry>{visual}</geometry>
    <material name="{material}"/></visual>
  {collision}
</link>"""
_JOINT = """<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>
  <origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>
  <limit lower="{lo}" upper="{hi}" effort="1" velocity="1"/>
</joint>"""


def _collision(shape: str, xyz: str = "0 0 0") -> str:
    return f'<collision><origin xyz="{xyz}" rpy="0 0 0"/><geometry>{shape}</geometry></collision>'


_BOX, _SLAB = '<box size="0.3 0.3 0.1"/>', '<box size="0.3 0.05 0.05"/>'
_BALL = '<sphere radius="0.05"/>'
_FOREARM = _collision('<cylinder radius="0.03" length="0.2"/>', "0.125 0 0") + _collision(
    '<sphere radius="0.04"/>', "0.25 0 0"
)


def ytree_urdf(mesh: str = "package://ytree/meshes/hand.obj") -> str:
    """The URDF text of the Y tree; ``mesh``: the hands' visual mesh file name."""
    links = [
        ("base", _BOX, "0 0 0.05", _collision(_BOX, "0 0 0.05")),
        ("torso", '<cylinder radius="0.06" length="0.5"/>', "0 0 0.25",
         _collision('<cylinder radius="0.06" length="0.4"/>', "0 0 0.25")),
        ("head", '<sphere radius="0.08"/>', "0 0 0", _collision('<sphere radius="0.08"/>')),
        ("l_upper", _SLAB, "0.15 0 0", _collision(_BALL, "0.15 0 0")),
        ("l_lower", '<cylinder radius="0.03" length="0.25"/>', "0 0 0", _FOREARM),
        ("l_hand", f'<mesh filename="{mesh}" scale="0.5 0.5 0.5"/>', "0 0 0", ""),
        ("r_upper", _SLAB, "0.15 0 0", _collision(_BALL, "0.15 0 0")),
        ("r_lower", '<cylinder radius="0.03" length="0.25"/>', "0 0 0", _FOREARM),
        ("r_hand", '<sphere radius="0.03"/>', "0 0 0", ""),
    ]  # fmt: skip
    joints = [  # name, kind, parent, child, origin xyz, rpy, axis, limits
        ("torso_yaw", "revolute", "base", "torso", "0 0 0.1", "0 0 0", "0 0 1", "-2.5 2.5"),
        ("neck", "prismatic", "torso", "head", "0 0 0.58", "0 0 0", "0 0 1", "0 0.1"),
        ("l_shoulder", "revolute", "torso", "l_upper", "0 0.1 0.45", "0 0 1.5708", "0 1 0", "-2.5 2.5"),
        ("l_elbow", "revolute", "l_upper", "l_lower", "0.3 0 0", "0 0 0", "0 1 0", "-2.5 2.5"),
        ("l_wrist", "fixed", "l_lower", "l_hand", "0.3 0 0", "0 0 0", "0 0 1", "0 0"),
        ("r_shoulder", "revolute", "torso", "r_upper", "0 -0.1 0.45", "0 0 -1.5708", "0 1 0", "-2.5 2.5"),
        ("r_elbow", "revolute", "r_upper", "r_lower", "0.3 0 0", "0 0 0", "0.6 0 0.8", "-2.5 2.5"),
        ("r_wrist", "fixed", "r_lower", "r_hand", "0.3 0 0", "0 0 0", "0 0 1", "0 0"),
    ]
    text = ['<?xml version="1.0"?>', '<robot name="ytree">',
            '<material name="orange"><color rgba="1 0.5 0 1"/></material>']  # fmt: skip
    for name, visual, vxyz, collision in links:
        text.append(_LINK.format(name=name, visual=visual, vxyz=vxyz, collision=collision, material="orange"))
    for name, kind, parent, child, xyz, rpy, axis, limits in joints:
        lo, hi = limits.split()
        fields = dict(name=name, kind=kind, parent=parent, child=child, xyz=xyz, rpy=rpy, axis=axis)
        text.append(_JOINT.format(**fields, lo=lo, hi=hi))
    text.append("</robot>")
    return "\n".join(text)


# a tetrahedron, 0.1 m on a side along x, as Wavefront OBJ text
HAND_OBJ = "v 0 0 0\nv 0.1 0 0\nv 0 0.1 0\nv 0 0 0.1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n"


@pytest.fixture(scope="session")
def ytree(tmp_path_factory) -> Path:
    """The Y tree's URDF file, in ``ytree/urdf/`` with its mesh in ``ytree/meshes/hand.obj``."""
    root = tmp_path_factory.mktemp("packages") / "ytree"
    (root / "urdf").mkdir(parents=True)
    (root / "meshes").mkdir()
    (root / "meshes" / "hand.obj").write_text(HAND_OBJ)
    path = root / "urdf" / "ytree.urdf"
    path.write_text(ytree_urdf())
    return path


ERD = erd_robots_dir()


@pytest.fixture(scope="session")
def solo12() -> Path:
    """example-robot-data's Solo-12 URDF (skips without it)."""
    if ERD is None or not (ERD / "solo_description/robots/solo12.urdf").is_file():
        pytest.skip("example-robot-data is not installed (the compare extra)")
    return ERD / "solo_description/robots/solo12.urdf"
