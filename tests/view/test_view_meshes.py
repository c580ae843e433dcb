"""The URDF meshes the live view draws (symkin.view.meshes): placed on the model's links where the
URDF's joints put them (checked against the joint origins and axes composed here), found through
``package://``, and left out with a note, never an error, when trimesh or a file is missing."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin.view.meshes import box_mesh, cylinder_mesh, resolve_mesh_file, urdf_meshes
from symkin.view.scene import Scene
from tests.conftest import assert_close
from tests.view.conftest import HAND_OBJ, ytree_urdf


def _rot(axis, angle):
    """Rotation (3, 3) by ``angle`` about the unit ``axis`` (Rodrigues)."""
    u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + np.sin(angle) * K + (1 - np.cos(angle)) * K @ K


def _pose(R=None, p=(0, 0, 0)):
    T = np.eye(4)
    T[:3, :3] = np.eye(3) if R is None else R
    T[:3, 3] = p
    return T


def _ytree_fk(q):
    """Base-frame poses of the Y tree's links from its URDF joints (origin, then the motion about
    or along the axis), composed here: the reference the meshes are placed against."""
    torso = _pose(p=(0, 0, 0.1)) @ _pose(_rot((0, 0, 1), q[0]))
    head = torso @ _pose(p=(0, 0, 0.58 + q[1]))
    l_upper = torso @ _pose(_rot((0, 0, 1), 1.5708), (0, 0.1, 0.45)) @ _pose(_rot((0, 1, 0), q[2]))
    l_lower = l_upper @ _pose(p=(0.3, 0, 0)) @ _pose(_rot((0, 1, 0), q[3]))
    r_upper = torso @ _pose(_rot((0, 0, 1), -1.5708), (0, -0.1, 0.45)) @ _pose(_rot((0, 1, 0), q[4]))
    r_lower = r_upper @ _pose(p=(0.3, 0, 0)) @ _pose(_rot((0.6, 0, 0.8), q[5]))
    return {
        "base": np.eye(4), "torso": torso, "head": head, "l_upper": l_upper, "l_lower": l_lower,
        "l_hand": l_lower @ _pose(p=(0.3, 0, 0)), "r_upper": r_upper, "r_lower": r_lower,
        "r_hand": r_lower @ _pose(p=(0.3, 0, 0)),
    }  # fmt: skip


# per link: where its visual is centred in the link's frame (its <origin xyz>)
_VISUAL_AT = {
    "base": (0, 0, 0.05), "torso": (0, 0, 0.25), "head": (0, 0, 0), "l_upper": (0.15, 0, 0),
    "l_lower": (0, 0, 0), "r_upper": (0.15, 0, 0), "r_lower": (0, 0, 0), "r_hand": (0, 0, 0),
}  # fmt: skip


def test_visuals_are_placed_where_the_urdf_joints_put_them(ytree):
    pytest.importorskip("trimesh", reason="the hand's mesh file is read with trimesh")
    tree = symkin.Tree.from_urdf(ytree)
    parts, notes = urdf_meshes(ytree, tree, "visual")
    assert notes == []
    assert sorted(p.name.split()[0] for p in parts) == sorted([*_VISUAL_AT, "l_hand"])
    assert all(p.color == (255, 128, 0) for p in parts), "the named material's colour"
    scene = Scene(symkin.compile(tree, backend="numpy"), meshes=parts)
    for q in tree.random_q(4, seed=2):
        state, fk = scene.state(q), _ytree_fk(q)
        for part, T in zip(parts, state.mesh_poses):
            world = part.vertices @ T[:3, :3].T + T[:3, 3]
            link = part.name.split()[0]
            if link == "l_hand":  # the tetrahedron, scaled by 0.5, in the hand's frame
                local = 0.5 * np.array(
                    [[float(x) for x in line.split()[1:]] for line in HAND_OBJ.splitlines()[:4]]
                )
                expect = local @ fk[link][:3, :3].T + fk[link][:3, 3]
                assert_close(world, expect, 1e-6, "hand mesh")
            else:  # boxes, cylinders and spheres are symmetric about their centres
                centre = fk[link][:3, :3] @ np.array(_VISUAL_AT[link]) + fk[link][:3, 3]
                assert_close(world.mean(axis=0), centre, 1e-6, f"{link} visual centre")


def test_collision_elements_can_be_drawn_instead(ytree):
    tree = symkin.Tree.from_urdf(ytree)
    parts, notes = urdf_meshes(ytree, tree, "collision")
    assert notes == []
    assert len(parts) == 9  # the collision elements of ytree_urdf
    assert urdf_meshes(ytree, tree, "none") == ([], [])
    with pytest.raises(ValueError, match="visual"):
        urdf_meshes(ytree, tree, "both")


def test_missing_files_and_trimesh_are_notes_not_errors(ytree, tmp_path, monkeypatch):
    tree = symkin.Tree.from_urdf(ytree)
    for mesh, says in [
        ("package://nowhere/hand.obj", "no folder named after its package"),
        ("meshes/absent.stl", "does not exist"),
    ]:
        path = tmp_path / "robot.urdf"
        path.write_text(ytree_urdf(mesh))
        parts, notes = urdf_meshes(path, tree, "visual")
        assert len(parts) == len(_VISUAL_AT) and len(notes) == 1
        assert "l_hand" in notes[0] and says in notes[0], notes
    monkeypatch.setitem(sys.modules, "trimesh", None)  # as when trimesh is not installed
    parts, notes = urdf_meshes(ytree, tree, "visual")
    assert len(parts) == len(_VISUAL_AT), "the boxes, cylinders and spheres need no trimesh"
    assert len(notes) == 1 and "trimesh" in notes[0] and "symkin[geometry]" in notes[0]


def test_a_model_the_urdf_does_not_describe_is_a_note(ytree):
    parts, notes = urdf_meshes(ytree, symkin.load("panda"), "visual")
    assert parts == [] and len(notes) == 1 and notes[0].startswith("no meshes drawn:")


def test_package_paths_resolve_to_the_nearest_folder_of_that_name(tmp_path):
    folder = tmp_path / "share" / "pkg" / "robots" / "urdf"
    folder.mkdir(parents=True)
    assert (
        resolve_mesh_file("package://pkg/meshes/a.stl", folder)
        == (tmp_path / "share/pkg/meshes/a.stl").resolve()
    )
    assert resolve_mesh_file("package://other/a.stl", folder) is None
    assert resolve_mesh_file("file:///abs/a.stl", folder) == Path("/abs/a.stl")
    assert resolve_mesh_file("m/a.stl", folder) == folder / "m" / "a.stl"


def test_primitive_meshes_have_their_sizes():
    V, F = box_mesh((0.2, 0.4, 0.6))
    assert_close(V.max(axis=0), [0.1, 0.2, 0.3], 1e-7, "box") and assert_close(
        V.min(axis=0), [-0.1, -0.2, -0.3], 1e-7, "box"
    )
    # outward winding: every face normal points away from the centre
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert (np.einsum("ij,ij->i", n, V[F].mean(axis=1)) > 0).all()
    V, F = cylinder_mesh(0.05, 0.3)
    assert np.hypot(V[:, 0], V[:, 1]).max() == pytest.approx(0.05, rel=1e-6)
    assert_close([V[:, 2].min(), V[:, 2].max()], [-0.15, 0.15], 1e-7, "cylinder ends")
    n = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert (np.einsum("ij,ij->i", n, V[F].mean(axis=1)) > 0).all()


def test_solo12_meshes_load_from_example_robot_data(solo12):
    pytest.importorskip("trimesh")
    tree = symkin.Tree.from_urdf(solo12)
    for kind in ("visual", "collision"):
        parts, notes = urdf_meshes(solo12, tree, kind)
        assert notes == [] and len(parts) == 17
        assert {p.link for p in parts} <= set(tree.link_names)
