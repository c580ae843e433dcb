"""What the live view draws (symkin.view.scene, NumPy only), for chains and trees: checked against
the numeric references of the models (the ETS walk of a chain, a tree's chains to its frames), the
definition of the velocity ellipsoid, the NumPy reference of the collision queries and the
closest points' geometry."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import symkin
from symkin.geometry import reference
from symkin.geometry.distance import box_sdf, point_segment
from symkin.geometry.urdf import geometry_from_urdf
from symkin.model.plot import chain_points
from symkin.view.scene import Scene, capsule_mesh, frame_choices, quaternion, quaternion_z_to, rotation
from tests.conftest import assert_close
from tests.view.conftest import ytree_urdf


@pytest.fixture(scope="module")
def ytree_kin():
    """The Y tree with its URDF collision geometry, compiled (NumPy)."""
    text = ytree_urdf()
    tree = symkin.Tree.from_urdf(text)
    return symkin.compile(tree.with_geometry(geometry_from_urdf(text, tree)), backend="numpy")


def _lines(origins: np.ndarray) -> np.ndarray:
    return np.stack((origins[:-1], origins[1:]), axis=1)


@pytest.mark.parametrize("name", ["panda", "puma560", "stanford"])
def test_a_chain_is_drawn_as_its_reference_kinematics(name):
    robot = symkin.load(name).with_tool("tz(0.1) Rx(0.3)")
    kin = symkin.compile(robot, backend="numpy")
    scene = Scene(kin)
    assert list(scene.frames) == ["ee", *(f"link{k + 1}" for k in range(robot.n))]
    for q in robot.random_q(5, seed=3):
        s = scene.state(q)
        origins, joints, links = chain_points(robot, q)  # the ETS walked element by element
        assert_close(s.stick, _lines(origins), 1e-12, "stick figure")
        assert_close(s.joints, np.array([T[:3, 3] for T, _ in joints]), 1e-12, "joints")
        assert_close(s.T_links, np.array(links), 1e-12, "link frames")
        assert_close(s.T_frame, robot.fkine(q), 1e-12, "end effector")
        assert_close(s.J, robot.jacob0(q), 1e-12, "J0")
        k = 2
        s = scene.state(q, f"link{k + 1}")  # link frame k: right after joint k
        assert_close(s.T_frame, links[k], 1e-12, "link frame")
        assert_close(s.J, robot.jacob0(q, frame=k), 1e-12, "its J0")


def test_a_tree_is_drawn_along_each_frames_chain(ytree_kin):
    tree = ytree_kin.model
    scene = Scene(ytree_kin)
    assert scene.frames == {"head": "head", "l_hand": "l_hand", "r_hand": "r_hand"}
    assert len(scene.state(tree.qz).T_links) == tree.n  # one link frame per joint
    for q in tree.random_q(5, seed=4):
        for frame in tree.frames:
            s = scene.state(q, frame)
            assert s.frame == frame
            assert_close(s.T_frame, tree.fkine(q, frame), 1e-12, f"{frame} pose")
            assert_close(s.J, tree.jacob0(q, frame), 1e-12, f"{frame} J0")
            # the segments on the path to the frame, in order, draw the chain's ETS frame by frame
            chain = tree.chain(frame)
            joints = tree.path_slots(frame)  # the chain's joints are these slots' joints, in order
            origins, chain_joints, _ = chain_points(chain, q[[tree.slots[k].joint for k in joints]])
            starts = np.cumsum([0] + [len(seg.ets) for seg in tree.segments])
            path = np.concatenate([s.stick[starts[k] : starts[k + 1]] for k in tree.path(frame)])
            assert_close(path, _lines(origins), 1e-12, f"stick figure to {frame}")
            slotted = [k for k, seg in enumerate(tree.segments) if seg.slot is not None]
            on_path = [slotted.index(tree.slots[k].segment) for k in joints]
            assert_close(s.joints[on_path], np.array([T[:3, 3] for T, _ in chain_joints]), 1e-12, "joints")
        # the link frames: the frame of each link a joint moves (URDF link frames), as the numeric
        # forward kinematics of a tree whose frames they are
        moved = [seg.link for seg in tree.segments if seg.slot is not None]
        links = symkin.Tree.from_urdf(ytree_urdf(), frames=moved).fkine_all(q)
        assert_close(s.T_links, links, 1e-12, "link frames")


def test_the_ellipsoid_and_manipulability_follow_their_definitions(ytree_kin):
    cases = [(symkin.compile(symkin.load("ur5"), backend="numpy"), None), (ytree_kin, "r_hand")]
    for kin, frame in cases:
        scene = Scene(kin)
        for q in kin.random_q(5, seed=1):
            s = scene.state(q, frame)
            Jv = kin.model.jacob0(q, frame)[:3]
            # semi-axes r_i along directions a_i: J_v J_v^T = sum r_i^2 a_i a_i^T
            assert_close(s.axes @ np.diag(s.radii**2) @ s.axes.T, Jv @ Jv.T, 1e-12, "J_v J_v^T")
            assert np.linalg.det(s.axes) == pytest.approx(1.0)
            assert s.m_trans == pytest.approx(float(np.sqrt(max(np.linalg.det(Jv @ Jv.T), 0))), abs=1e-12)
            assert s.m_trans == pytest.approx(float(np.prod(s.radii)), rel=1e-9, abs=1e-15)


def _numeric_points(model, q):
    """Shape points from the model's numeric forward kinematics: each shape's link pose (a chain's
    link frames and end effector from its ETS walk; a tree's links from trees whose frames they are)."""
    geometry = model.geometry
    if isinstance(model, symkin.Robot):
        poses = {"base": np.eye(4), "ee": model.fkine(q)}
        poses.update({f"link{k + 1}": T for k, T in enumerate(model.link_poses(q))})
    else:
        links = [x for x in geometry.links if x != model.base_link]
        tree = symkin.Tree.from_urdf(ytree_urdf(), frames=links)
        poses = {model.base_link: np.eye(4), **dict(zip(links, tree.fkine_all(q)))}
    return np.array(
        [poses[s.link][:3, :3] @ p + poses[s.link][:3, 3] for s in geometry.shapes for p in s.points]
    )


@pytest.mark.parametrize("which", ["panda", "ytree"])
def test_sphere_centres_are_the_numeric_fk_and_collisions_are_the_negative_distances(which, ytree_kin):
    if which == "panda":
        kin = symkin.compile(symkin.load("panda"), backend="c")
        env = symkin.Environment(spheres=(symkin.Sphere((0.3, 0.0, 0.6), 0.1),))
    else:
        kin = ytree_kin
        env = symkin.Environment(boxes=(symkin.Box((0.35, 0.0, 0.5), (0.05, 0.3, 0.05)),))
    scene = Scene(kin, env)
    qs = kin.random_q(40, seed=7)
    hits = 0
    for q in qs:
        s = scene.state(q)
        assert_close(s.shape_points, _numeric_points(kin.model, q), 1e-12, "shape points")
        d = reference.distances(kin.model, q, env)
        labels = kin.collision_pairs(env)
        expect = np.zeros(len(scene.shapes), dtype=bool)
        for (kind, i, j), dk in zip(labels, d):
            if dk < 0:
                expect[i] = True
                expect[j] |= kind == "self"
        assert (s.colliding == expect).all()
        assert s.obstacles_hit.tolist() == [
            bool(any(dk < 0 for lab, dk in zip(labels, d) if lab[0] != "self"))
        ]
        assert len(s.pairs_hit) == int((d < 0).sum())
        assert_close([p for p, _ in s.pairs_hit], np.sort(d[d < 0]), 1e-12, "overlaps, deepest first")
        assert s.colliding.any() == bool(kin.in_collision(q, env))
        hits += int(s.colliding.any())
    assert 0 < hits < len(qs), "the sample should hold configurations with and without collision"


def _surface_gaps(scene, s, label, a, b, env) -> tuple[float, float]:
    """Signed distances (m) of the witness points from the surfaces of their shapes (> 0 outside)."""
    kind, i, j = label

    def gap(k, p):
        shape = scene.shapes[k]
        ends = s.shape_points[list(shape.points)]
        t = 0.0 if shape.kind == "sphere" else point_segment(p, ends[0], ends[1])
        return np.linalg.norm(p - (ends[0] + t * (ends[-1] - ends[0]))) - shape.radius

    if kind == "self":
        return gap(i, a), gap(j, b)
    o = {"sphere": env.spheres, "capsule": env.capsules, "box": env.boxes}[kind][j]
    if kind == "sphere":
        other = np.linalg.norm(b - np.array(o.center)) - o.radius
    elif kind == "capsule":
        A, B = np.array(o.a), np.array(o.b)
        other = np.linalg.norm(b - (A + point_segment(b, A, B) * (B - A))) - o.radius
    else:
        other = float(box_sdf(b, o.center, o.half_extents, o.R)[0])
    return gap(i, a), other


@pytest.mark.parametrize(
    "env, kind",
    [
        (symkin.Environment(), "self"),
        (symkin.Environment(spheres=(symkin.Sphere((0.4, 0.1, 0.5), 0.08),)), "sphere"),
        (symkin.Environment(capsules=(symkin.Capsule((0.3, -0.3, 0.4), (0.3, 0.3, 0.4), 0.04),)), "capsule"),
        (symkin.Environment(boxes=(symkin.Box((0.45, 0.0, 0.3), (0.05, 0.2, 0.3)),)), "box"),
    ],
    ids=["self", "sphere", "capsule", "box"],
)
def test_the_closest_pair_is_the_references_with_witness_points_on_both_surfaces(env, kind, ytree_kin):
    scene = Scene(ytree_kin, env)
    kinds = set()
    for q in ytree_kin.random_q(30, seed=11):
        s = scene.state(q)
        d = reference.distances(ytree_kin.model, q, env)
        k = int(np.argmin(d))
        c = s.closest
        assert c.label == ytree_kin.collision_pairs(env)[k]
        assert c.distance == pytest.approx(float(d[k]), abs=1e-12)
        assert np.linalg.norm(c.a - c.b) == pytest.approx(abs(c.distance), abs=1e-12)
        ga, gb = _surface_gaps(scene, s, c.label, c.a, c.b, env)
        if c.distance >= 0 or c.label[0] == "self":  # the closest points, or the deepest of two cores
            assert abs(ga) < 1e-9 and abs(gb) < 1e-9, (ga, gb, c)
        else:  # a point of the robot's shape the obstacle's surface is deepest from (a capsule
            assert ga < 1e-9 and abs(gb) < 1e-9, (ga, gb, c)  # in a box: not always on its surface)
        kinds.add(c.label[0])
    assert kinds == {"self", kind}, "the sample should make both a self pair and the obstacle closest"


def test_a_capsule_is_drawn_along_its_segment():
    capsules = tuple(symkin.Capsule((0, 0, 0), (1, 0, 0), 0.05, link=k) for k in range(3))
    robot = symkin.load("planar3").with_geometry(symkin.Geometry(capsules))
    scene = Scene(symkin.compile(robot, backend="numpy"))
    q = np.array([0.3, -0.7, 1.1])
    s = scene.state(q)
    origins = chain_points(robot, q)[0]
    for k, shape in enumerate(scene.shapes):
        assert (shape.kind, shape.length, shape.radius) == ("capsule", 1.0, 0.05)
        centre, wxyz = scene.shape_pose(s, k)
        a, b = origins[2 * k + 1], origins[2 * k + 2]  # link k runs from joint k to joint k + 1
        assert_close(centre, (a + b) / 2, 1e-12, "capsule centre")
        assert_close(rotation(wxyz)[:, 2], b - a, 1e-12, "capsule axis")


def test_frame_choices_ask_the_model():
    chain = symkin.compile(symkin.load("planar3"), backend="numpy")
    assert frame_choices(chain) == {"ee": None, "link1": 0, "link2": 1, "link3": 2}
    tree = symkin.compile(symkin.Tree.from_urdf(ytree_urdf()), backend="numpy")
    assert frame_choices(tree) == {f: f for f in tree.frames}
    with pytest.raises(symkin.FrameError, match="l_hand"):
        Scene(tree).state(tree.model.qz, "l_hnd")


def test_quaternions_round_trip():
    rng = np.random.default_rng(0)
    for _ in range(50):
        R, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        R *= np.sign(np.linalg.det(R))
        assert_close(rotation(quaternion(R)), R, 1e-12, "R")
        d = rng.normal(size=3)
        assert_close(rotation(quaternion_z_to(d))[:, 2], d / np.linalg.norm(d), 1e-12, "z to d")
    assert_close(rotation(quaternion_z_to(np.array([0, 0, -2.0])))[:, 2], [0, 0, -1], 1e-12, "z to -z")


def test_capsule_mesh_spans_the_segment_plus_the_radius():
    V, F = capsule_mesh(0.1, 0.5)
    assert_close(V[:, 2].min(), -0.35, 1e-6, "bottom")
    assert_close(V[:, 2].max(), 0.35, 1e-6, "top")
    assert np.hypot(V[:, 0], V[:, 1]).max() == pytest.approx(0.1, rel=1e-6)
    assert F.max() < len(V) and F.shape[1] == 3


def test_bad_joint_values_are_errors():
    kin = symkin.compile(symkin.load("planar3"), backend="numpy")
    with pytest.raises(symkin.ParameterError, match="3 finite joint values"):
        Scene(kin).state([0.0, np.nan, 0.0])


def test_the_view_modules_import_neither_sympy_nor_viser():
    code = (
        "import sys, symkin.view, symkin.cli.view; "
        "print(sorted(m for m in ('sympy', 'viser', 'trimesh') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
