"""Collision geometry from URDF <collision> elements (as a Robot chain and as a Tree), SRDF
disabled pairs, and sphere fitting."""

from __future__ import annotations

import math
import re
import sys
import types
import warnings

import numpy as np
import pytest

import symkin
from symkin.errors import GeometryError, MissingExtraError
from symkin.geometry.fit import fit_spheres
from symkin.geometry.srdf import read_srdf
from symkin.geometry.urdf import box_spheres, geometry_from_urdf, urdf_link_names
from symkin.model.geometry import Capsule, Sphere

# a 3-joint arm: a joint axis off the coordinate axes (symkin's link frame is then turned from the
# URDF's), a prismatic joint, a fixed tool at the end and a camera fixed beside the chain
ARM = """<robot name="arm3">
  <link name="base_link"><collision><origin xyz="0 0 0.05"/>
    <geometry><cylinder radius="0.1" length="0.1"/></geometry></collision></link>
  <link name="l1"><collision><origin xyz="0.01 0 0.1" rpy="0.3 0 0"/>
    <geometry><sphere radius="0.05"/></geometry></collision></link>
  <link name="l2">
    <collision><origin xyz="0.15 0 0" rpy="0 1.5707963 0"/>
      <geometry><cylinder radius="0.04" length="0.3"/></geometry></collision>
    <collision><origin xyz="0.3 0.01 0" rpy="0.1 0.2 0.3"/>
      <geometry><box size="0.08 0.06 0.2"/></geometry></collision></link>
  <link name="l3"><collision><origin xyz="0.1 0.02 0"/>
    <geometry><box size="0.2 0.05 0.05"/></geometry></collision></link>
  <link name="tool"><collision><origin xyz="0 0 0.03"/>
    <geometry><sphere radius="0.02"/></geometry></collision></link>
  <link name="camera"><collision><geometry><sphere radius="0.03"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="l1"/>
    <origin xyz="0 0 0.1"/><axis xyz="0 0 1"/><limit lower="-3" upper="3" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/>
    <origin xyz="0 0.02 0.2" rpy="0.2 0 0.4"/><axis xyz="0 1 1"/>
    <limit lower="-2" upper="2" velocity="1"/></joint>
  <joint name="j3" type="prismatic"><parent link="l2"/><child link="l3"/>
    <origin xyz="0.3 0 0" rpy="0 0 0.5"/><axis xyz="1 0 0"/>
    <limit lower="0" upper="0.2" velocity="1"/></joint>
  <joint name="camera_mount" type="fixed"><parent link="l2"/><child link="camera"/>
    <origin xyz="0.1 0.05 0.05" rpy="0 0.5 0"/></joint>
  <joint name="tool_joint" type="fixed"><parent link="l3"/><child link="tool"/>
    <origin xyz="0.2 0 0" rpy="0 1.5707963 0"/></joint>
</robot>"""

LINKS = ["base_link", "l1", "l2", "l3", "tool", "camera"]
JOINTS = {  # child: (parent, xyz, rpy, kind, axis, joint index)
    "l1": ("base_link", (0, 0, 0.1), (0, 0, 0), "revolute", (0, 0, 1), 0),
    "l2": ("l1", (0, 0.02, 0.2), (0.2, 0, 0.4), "revolute", (0, 1, 1), 1),
    "l3": ("l2", (0.3, 0, 0), (0, 0, 0.5), "prismatic", (1, 0, 0), 2),
    "camera": ("l2", (0.1, 0.05, 0.05), (0, 0.5, 0), "fixed", None, None),
    "tool": ("l3", (0.2, 0, 0), (0, 1.5707963, 0), "fixed", None, None),
}


def rpy_T(xyz, rpy) -> np.ndarray:
    r, p, y = rpy
    Rx = np.array([[1, 0, 0], [0, math.cos(r), -math.sin(r)], [0, math.sin(r), math.cos(r)]])
    Ry = np.array([[math.cos(p), 0, math.sin(p)], [0, 1, 0], [-math.sin(p), 0, math.cos(p)]])
    Rz = np.array([[math.cos(y), -math.sin(y), 0], [math.sin(y), math.cos(y), 0], [0, 0, 1]])
    T = np.eye(4)
    T[:3, :3] = Rz @ Ry @ Rx
    T[:3, 3] = xyz
    return T


def urdf_fk(q) -> dict[str, np.ndarray]:
    """Base-frame pose of every URDF link (own homogeneous transforms, Rodrigues for the joints)."""
    out = {"base_link": np.eye(4)}
    for child in ("l1", "l2", "l3", "camera", "tool"):
        parent, xyz, rpy, kind, axis, k = JOINTS[child]
        M = np.eye(4)
        if kind != "fixed":
            u = np.array(axis, float) / np.linalg.norm(axis)
            if kind == "prismatic":
                M[:3, 3] = q[k] * u
            else:
                K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
                M[:3, :3] = np.eye(3) + math.sin(q[k]) * K + (1 - math.cos(q[k])) * K @ K
        out[child] = out[parent] @ rpy_T(xyz, rpy) @ M
    return out


def expected(q) -> list[tuple[str, np.ndarray, float, np.ndarray | None]]:
    """(kind, base-frame centre or end a, radius, end b) of the sphere and cylinder elements in file
    order; boxes as ("box", T_box (4x4), half extents)."""
    F = urdf_fk(q)

    def at(link, xyz, rpy, p):
        return (F[link] @ rpy_T(xyz, rpy) @ np.array([*p, 1.0]))[:3]

    return [
        ("capsule", at("base_link", (0, 0, 0.05), (0, 0, 0), (0, 0, -0.05)), 0.1,
         at("base_link", (0, 0, 0.05), (0, 0, 0), (0, 0, 0.05))),
        ("sphere", at("l1", (0.01, 0, 0.1), (0.3, 0, 0), (0, 0, 0)), 0.05, None),
        ("capsule", at("l2", (0.15, 0, 0), (0, 1.5707963, 0), (0, 0, -0.15)), 0.04,
         at("l2", (0.15, 0, 0), (0, 1.5707963, 0), (0, 0, 0.15))),
        ("box", F["l2"] @ rpy_T((0.3, 0.01, 0), (0.1, 0.2, 0.3)), np.array([0.04, 0.03, 0.1]), None),
        ("box", F["l3"] @ rpy_T((0.1, 0.02, 0), (0, 0, 0)), np.array([0.1, 0.025, 0.025]), None),
        ("sphere", at("tool", (0, 0, 0.03), (0, 0, 0), (0, 0, 0)), 0.02, None),
        ("sphere", at("camera", (0, 0, 0), (0, 0, 0), (0, 0, 0)), 0.03, None),
    ]  # fmt: skip


def model_frames(model, q) -> dict[str, np.ndarray]:
    if isinstance(model, symkin.Robot):
        L = model.link_poses(q)
        return {"base": np.eye(4), "ee": model.fkine(q), **{f"link{k + 1}": L[k] for k in range(model.n)}}
    # a tree whose frames are all its links below the base
    T = model.fkine_all(q)
    return {model.base_link: np.eye(4), **dict(zip(model.frames, T))}


def to_base(F, s) -> list[np.ndarray]:
    T = F[s.link]
    return [T[:3, :3] @ np.asarray(p) + T[:3, 3] for p in s.points]


def corners(T: np.ndarray, h: np.ndarray) -> np.ndarray:
    signs = np.array([[a, b, c] for a in (-1, 1) for b in (-1, 1) for c in (-1, 1)], float)
    return (T[:3, :3] @ (signs * h).T).T + T[:3, 3]


def check_against_urdf(model, g, q) -> None:
    F = model_frames(model, q)
    shapes = list(g.shapes)
    for kind, a, r, b in expected(q):
        if kind == "box":
            T, h = a, r
            cells = []
            while shapes and isinstance(shapes[0], Sphere):  # this box's spheres: centres inside it
                c = to_base(F, shapes[0])[0]
                local = T[:3, :3].T @ (c - T[:3, 3])
                if not (np.abs(local) <= h + 1e-9).all():
                    break
                cells.append((c, shapes.pop(0).radius))
            assert 1 <= len(cells) <= 64
            C = np.array([c for c, _ in cells])
            R = np.array([r for _, r in cells])
            pts = np.vstack([corners(T, h), T[:3, 3][None]])
            rng = np.random.default_rng(0)
            pts = np.vstack([pts, (T[:3, :3] @ ((rng.random((200, 3)) * 2 - 1) * h).T).T + T[:3, 3]])
            d = np.linalg.norm(pts[:, None] - C[None], axis=2)
            assert (d <= R + 1e-9).any(1).all(), "box not covered"
            continue
        s = shapes.pop(0)
        assert s.radius == pytest.approx(r)
        got = to_base(F, s)
        if kind == "sphere":
            assert isinstance(s, Sphere)
            np.testing.assert_allclose(got[0], a, atol=1e-9)
        else:
            assert isinstance(s, Capsule)
            np.testing.assert_allclose(got[0], a, atol=1e-9)
            np.testing.assert_allclose(got[1], b, atol=1e-9)
    assert not shapes


@pytest.fixture
def arm_file(tmp_path):
    p = tmp_path / "arm3.urdf"
    p.write_text(ARM)
    return p


def test_robot_from_urdf(arm_file) -> None:
    robot = symkin.Robot.from_urdf(arm_file, end_link="tool")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        g = geometry_from_urdf(arm_file, robot)
    assert {s.link for s in g.shapes} == {"base", "link1", "link2", "link3", "ee"}
    camera = g.shapes[-1]
    assert camera.link == "link2"  # fixed to l2, beside the chain: on l2's body
    assert "arm3.urdf" in g.source and g.disabled == ()
    robot = robot.with_geometry(g)
    # the link frames of symkin's chain agree with the URDF's up to a constant (j2's axis is off
    # the coordinate axes): shapes land where the URDF puts them at random q
    for q in robot.random_q(5, seed=1):
        check_against_urdf(robot, g, q)
    assert urdf_link_names(arm_file, robot) == {
        "base_link": "base", "l1": "link1", "l2": "link2", "l3": "link3", "tool": "ee", "camera": "link2",
    }  # fmt: skip


def test_tree_from_urdf(arm_file) -> None:
    tree = symkin.Tree.from_urdf(arm_file, frames=LINKS[1:])
    g = geometry_from_urdf(ARM, tree)  # XML text works like the file
    assert [s.link for s in g.shapes if isinstance(s, Capsule)] == ["base_link", "l2"]
    tree = tree.with_geometry(g)
    for q in tree.random_q(5, seed=2):
        check_against_urdf(tree, g, q)
    # a tree without the tool and camera frames: their shapes go to l3 and l2 through the fixed joints
    small = symkin.Tree.from_urdf(arm_file, frames=["l3"])
    assert set(small.link_names) == {"base_link", "l1", "l2", "l3"}
    g2 = geometry_from_urdf(arm_file, small)
    assert [s.link for s in g2.shapes][-2:] == ["l3", "l2"]
    for q in small.random_q(3, seed=3):
        F = {"base_link": np.eye(4), "l3": small.fkine(q, "l3")}
        tool = to_base(F, g2.shapes[-2])[0]
        np.testing.assert_allclose(tool, expected(q)[5][1], atol=1e-9)


def test_tree_base_below_root_skips_links_above(arm_file) -> None:
    tree = symkin.Tree.from_urdf(arm_file, frames=["tool"], base_link="l1")
    with pytest.warns(UserWarning, match="'base_link'"):
        g = geometry_from_urdf(arm_file, tree)
    assert "base_link" not in {s.link for s in g.shapes}
    assert "skipped on ['base_link']" in g.source


def test_mesh_elements(tmp_path, monkeypatch) -> None:
    (tmp_path / "meshes").mkdir()
    trimesh = pytest.importorskip("trimesh")
    hull = trimesh.convex.convex_hull(np.random.default_rng(4).random((40, 3)) * [0.1, 0.05, 0.2])
    hull.export(tmp_path / "meshes" / "part.stl")
    pts = np.asarray(hull.vertices)
    text = ARM.replace(
        '<link name="camera">',
        '<link name="camera"><collision><origin xyz="0 0 0.1"/><geometry>'
        '<mesh filename="meshes/part.stl" scale="2 2 2"/></geometry></collision>'
        '<collision><geometry><mesh filename="package://arm3/meshes/cam.stl"/></geometry></collision>',
    )
    path = tmp_path / "mesh_arm.urdf"
    path.write_text(text)
    robot = symkin.Robot.from_urdf(path, end_link="tool")
    plain = geometry_from_urdf(arm_file_text := ARM, symkin.Robot.from_urdf(arm_file_text, end_link="tool"))
    with pytest.warns(UserWarning, match="link 'camera'.*mesh"):
        g = geometry_from_urdf(path, robot)  # mesh_spheres=0: skipped
    assert g == plain
    monkeypatch.setitem(sys.modules, "trimesh", None)  # not installed
    with pytest.warns(UserWarning) as record:
        geometry_from_urdf(path, robot, mesh_spheres=3)
    messages = " | ".join(str(w.message) for w in record)
    assert "needs trimesh" in messages and "package:// paths are not resolved" in messages

    monkeypatch.setitem(sys.modules, "trimesh", trimesh)
    with pytest.warns(UserWarning, match="package://"):
        g = geometry_from_urdf(path, robot, mesh_spheres=3)
    fitted = [s for s in g.shapes if s.link == "link2"][-4:-1]  # then the camera's own sphere
    assert len(g) == len(plain) + 3
    q = robot.random_q(seed=5)
    F = model_frames(robot, q)
    cam = urdf_fk(q)["camera"] @ rpy_T((0, 0, 0.1), (0, 0, 0))
    world = (cam[:3, :3] @ (2 * pts).T).T + cam[:3, 3]
    C = np.array([to_base(F, s)[0] for s in fitted])
    R = np.array([s.radius for s in fitted])
    assert (np.linalg.norm(world[:, None] - C[None], axis=2) <= R + 1e-9).any(1).all()


def test_urdf_errors(arm_file) -> None:
    other = symkin.load("panda")
    with pytest.raises(GeometryError, match="not movable joints"):
        geometry_from_urdf(arm_file, other)
    moved = symkin.Robot.from_urdf(arm_file, end_link="tool").with_tool("tz(0.1)")
    with pytest.raises(GeometryError, match="does not move like"):
        geometry_from_urdf(arm_file, moved)
    with pytest.raises(GeometryError, match="Robot or Tree"):
        geometry_from_urdf(arm_file, "arm")
    bad = ARM.replace('<sphere radius="0.05"/>', '<sphere radius="-0.05"/>')
    with pytest.raises(GeometryError, match="radius"):
        geometry_from_urdf(bad, symkin.Tree.from_urdf(bad))
    odd = ARM.replace('<sphere radius="0.05"/>', '<ellipsoid radii="1 2 3"/>')
    with pytest.warns(UserWarning, match="unknown shape <ellipsoid>"):
        geometry_from_urdf(odd, symkin.Tree.from_urdf(odd))


def test_box_spheres() -> None:
    assert len(box_spheres([0.1, 0.1, 0.1])) == 1
    assert box_spheres([0.1, 0.1, 0.1])[0][1] == pytest.approx(0.1 * math.sqrt(3))
    long = box_spheres([0.5, 0.05, 0.05])
    assert len(long) == 10 and all(r == pytest.approx(0.05 * math.sqrt(3)) for _, r in long)
    plate = box_spheres([1.0, 1.0, 0.001], max_spheres=64)
    assert len(plate) <= 64
    one = box_spheres([0.0, 0.0, 0.0])
    assert len(one) == 1 and one[0][1] == 0.0


SRDF = """<robot name="arm3">
  <group name="arm"><chain base_link="base_link" tip_link="tool"/></group>
  <disable_collisions link1="l1" link2="base_link" reason="Adjacent"/>
  <disable_collisions link1="l3" link2="camera" reason="Never"/>
  <disable_collisions link1="tool" link2="l3" reason="Adjacent"/>
  <disable_collisions link1="l3" link2="camera" reason="Never"/>
  <disable_collisions link1="gripper" link2="l1" reason="Never"/>
</robot>"""


def test_read_srdf(tmp_path, arm_file) -> None:
    p = tmp_path / "arm3.srdf"
    p.write_text(SRDF)
    assert read_srdf(p) == (
        ("base_link", "l1"), ("camera", "l3"), ("gripper", "l1"), ("l3", "tool"),
    )  # fmt: skip
    robot = symkin.Robot.from_urdf(arm_file, end_link="tool")
    names = urdf_link_names(arm_file, robot)
    with pytest.warns(UserWarning) as caught:
        pairs = read_srdf(SRDF, names)
    said = " ".join(str(w.message) for w in caught)
    assert re.search(r"1 disable_collisions pairs .*\(gripper, l1\)", said)
    # camera rides on link2 with l2: (camera, l3) alone leaves (link2, link3) checked, and says so
    assert re.search(r"stay checked.*\(link2, link3\)", said)
    assert pairs == (("base", "link1"), ("ee", "link3"))
    with pytest.warns(UserWarning, match="fall on one model link"):  # both on link2
        assert (
            read_srdf('<robot name="x"><disable_collisions link1="l2" link2="camera"/></robot>', names) == ()
        )
    g = geometry_from_urdf(arm_file, robot).with_disabled(pairs)
    assert robot.with_geometry(g).geometry.disabled == pairs
    assert read_srdf(SRDF, lambda n: n.upper())[0] == ("BASE_LINK", "L1")
    with pytest.raises(GeometryError, match="link1 and link2"):
        read_srdf('<robot name="x"><disable_collisions link1="a"/></robot>')
    with pytest.raises(GeometryError, match="SRDF"):
        read_srdf("<robot><oops></robot>")


def test_fit_spheres_covers_points() -> None:
    rng = np.random.default_rng(7)
    P = np.vstack([rng.normal(size=(300, 3)) * [0.2, 0.05, 0.05], rng.normal(size=(300, 3)) * 0.03 + 1.0])
    for n in (1, 2, 5, 12):
        S = fit_spheres(P, n, seed=3)
        assert len(S) == n
        C = np.array([c for c, _ in S])
        R = np.array([r for _, r in S])
        assert C.shape == (n, 3) and (R >= 0).all() and (np.diff(R) <= 0).all()
        assert (np.linalg.norm(P[:, None] - C[None], axis=2) <= R).any(1).all()
    # deterministic for a seed, and more spheres hug the points tighter
    a, b = fit_spheres(P, 6, seed=1), fit_spheres(P, 6, seed=1)
    assert all(np.array_equal(x[0], y[0]) and x[1] == y[1] for x, y in zip(a, b))
    assert max(r for _, r in fit_spheres(P, 12)) < max(r for _, r in fit_spheres(P, 2))
    unshrunk = fit_spheres(P, 6, seed=1, shrink=False)
    assert sum(r for _, r in a) <= sum(r for _, r in unshrunk) + 1e-12
    # fewer distinct points than n: one sphere each; a mesh-like object
    assert len(fit_spheres([[0, 0, 0], [1, 0, 0], [1, 0, 0]], 5)) == 2
    mesh = types.SimpleNamespace(vertices=P[:50])
    assert len(fit_spheres(mesh, 3)) == 3


def test_fit_spheres_errors(monkeypatch) -> None:
    for n in (0, -1, 1.5, True, "2"):
        with pytest.raises(GeometryError, match="n must"):
            fit_spheres(np.zeros((4, 3)), n)
    with pytest.raises(GeometryError, match="at least one point"):
        fit_spheres(np.zeros((0, 3)), 2)
    with pytest.raises(GeometryError, match="NaN"):
        fit_spheres([[0, 0, np.nan]], 1)
    with pytest.raises(GeometryError, match=r"\(N, 3\)"):
        fit_spheres(np.zeros((4, 2)), 1)
    with pytest.raises(GeometryError, match="points"):
        fit_spheres(object(), 1)
    monkeypatch.setitem(sys.modules, "trimesh", None)
    with pytest.raises(MissingExtraError, match=r'pip install "symkin\[geometry\]"'):
        fit_spheres("part.stl", 4)
