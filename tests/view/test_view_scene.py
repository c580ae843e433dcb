"""What the live view draws (symkin.view.scene, NumPy only): checked against the numeric reference
of the model, the definition of the velocity ellipsoid and the collision queries."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import symkin
from symkin.model.plot import chain_points
from symkin.view.scene import Scene, capsule_mesh, quaternion, quaternion_z_to, rotation
from tests.conftest import assert_close


@pytest.mark.parametrize("name", ["panda", "puma560", "stanford"])
def test_the_stick_figure_and_frames_match_the_reference_kinematics(name):
    robot = symkin.load(name).with_tool("tz(0.1) Rx(0.3)")
    kin = symkin.compile(robot, backend="numpy")
    scene = Scene(kin)
    for q in robot.random_q(5, seed=3):
        s = scene.state(q)
        origins, joints, links = chain_points(robot, q)  # the ETS walked element by element
        assert_close(s.chain, origins, 1e-12, "chain")
        assert_close(s.joints, np.array([T[:3, 3] for T, _ in joints]), 1e-12, "joints")
        assert_close(s.T_links, np.array(links), 1e-12, "link frames")
        assert_close(s.T_ee, robot.fkine(q), 1e-12, "end effector")
        assert_close(s.J, robot.jacob0(q), 1e-12, "J0")


def test_the_ellipsoid_and_manipulability_follow_their_definitions():
    robot = symkin.load("ur5")
    scene = Scene(symkin.compile(robot, backend="numpy"))
    for q in robot.random_q(5, seed=1):
        s = scene.state(q)
        Jv = robot.jacob0(q)[:3]
        # semi-axes r_i along directions a_i: J_v J_v^T = sum r_i^2 a_i a_i^T
        assert_close(s.axes @ np.diag(s.radii**2) @ s.axes.T, Jv @ Jv.T, 1e-12, "J_v J_v^T")
        assert np.linalg.det(s.axes) == pytest.approx(1.0)
        assert s.m_trans == pytest.approx(float(robot.manipulability(q, axes="trans")), rel=1e-9)
        assert s.m == pytest.approx(float(robot.manipulability(q)), rel=1e-9)
        assert s.m_trans == pytest.approx(float(np.prod(s.radii)), rel=1e-9)


def test_colliding_shapes_are_those_of_pairs_at_negative_distance():
    robot = symkin.load("panda")
    kin = symkin.compile(robot, backend="numpy")
    obstacle = symkin.Environment(spheres=(symkin.Sphere((0.3, 0.0, 0.6), 0.1),))
    scene = Scene(kin, obstacle)
    qs = robot.random_q(40, seed=7)
    hits = 0
    for q in qs:
        s = scene.state(q)
        d = kin.distances(q, obstacle)
        expect = np.zeros(len(robot.geometry.shapes), dtype=bool)
        for (kind, i, j), dk in zip(kin.collision_pairs(obstacle), d):
            if dk < 0:
                expect[i] = True
                expect[j] |= kind == "self"
        assert (s.colliding == expect).all()
        assert s.colliding.any() == bool(kin.in_collision(q, obstacle))
        hits += int(s.colliding.any())
        assert_close(s.shape_points, kin.collision_points(q), 1e-12, "shape points")
    assert 0 < hits < len(qs), "the sample should hold configurations with and without collision"


def test_a_capsule_is_drawn_along_its_segment():
    capsules = tuple(symkin.Capsule((0, 0, 0), (1, 0, 0), 0.05, link=k) for k in range(3))
    robot = symkin.load("planar3").with_geometry(symkin.Geometry(capsules))
    scene = Scene(symkin.compile(robot, backend="numpy"))
    q = np.array([0.3, -0.7, 1.1])
    s = scene.state(q)
    for k, shape in enumerate(scene.shapes):
        assert (shape.kind, shape.length, shape.radius) == ("capsule", 1.0, 0.05)
        centre, wxyz = scene.shape_pose(s, k)
        a, b = s.chain[2 * k + 1], s.chain[2 * k + 2]  # link k runs from joint k to joint k + 1
        assert_close(centre, (a + b) / 2, 1e-12, "capsule centre")
        assert_close(rotation(wxyz)[:, 2], b - a, 1e-12, "capsule axis")


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


def test_a_tree_is_refused_and_bad_joint_values_are_errors():
    kin = symkin.compile(symkin.load("planar3"), backend="numpy")
    with pytest.raises(symkin.ParameterError, match="3 finite joint values"):
        Scene(kin).state([0.0, np.nan, 0.0])


def test_the_view_modules_import_neither_sympy_nor_viser():
    code = (
        "import sys, symkin.view, symkin.cli.view; "
        "print(sorted(m for m in ('sympy', 'viser') if m in sys.modules))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
