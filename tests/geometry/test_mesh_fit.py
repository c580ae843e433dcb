"""fit_urdf on small URDFs written here: meshes and boxes covered link by link in the model's
frames, a gripper finger on a prismatic joint the chain does not have covered over its whole
travel, package:// paths resolved, unreadable meshes skipped naming file and link; and the
``symkin geometry`` command on them."""

from __future__ import annotations

import json

import numpy as np
import pytest

import symkin
from symkin.cli.main import main
from symkin.errors import GeometryError
from symkin.geometry.mesh_fit import coverage, fit_urdf

trimesh = pytest.importorskip("trimesh")

URDF = """<robot name="grip">
  <link name="base_link"><collision><geometry><box size="0.08 0.08 0.04"/></geometry></collision></link>
  <link name="arm"><collision><origin xyz="0 0 0.15" rpy="0.3 0 0"/>
    <geometry><mesh filename="package://grip_pkg/meshes/arm.stl" scale="1 1 1.5"/></geometry>
  </collision></link>
  <link name="finger"><collision><geometry><box size="0.02 0.01 0.04"/></geometry></collision></link>
  <joint name="j1" type="revolute"><parent link="base_link"/><child link="arm"/><origin xyz="0 0 0.05"/>
    <axis xyz="0 0 1"/><limit lower="-2" upper="2"/></joint>
  <joint name="slide" type="prismatic"><parent link="arm"/><child link="finger"/>
    <origin xyz="0.03 0 0.3" rpy="0 0 0.5"/>
    <axis xyz="0 1 0"/><limit lower="-0.01" upper="0.03"/></joint>
</robot>"""


@pytest.fixture
def grip(tmp_path):
    pkg = tmp_path / "grip_pkg"
    (pkg / "meshes").mkdir(parents=True)
    (pkg / "urdf").mkdir()
    trimesh.creation.capsule(height=0.15, radius=0.03, count=[8, 8]).export(pkg / "meshes" / "arm.stl")
    path = pkg / "urdf" / "grip.urdf"
    path.write_text(URDF)
    return path


def test_chain_fit_covers_the_arm_and_the_finger_over_its_travel(grip):
    robot = symkin.Robot.from_urdf(grip, end_link="arm")
    fit = fit_urdf(grip, robot, 0.015, progress=False)
    assert {p.link for p in fit.parts} == {"base", "link1"}
    finger = [p for p in fit.parts if p.urdf_link == "finger"][0]
    assert finger.stroke is not None and np.linalg.norm(finger.stroke) == pytest.approx(0.04)
    cov = coverage(fit.geometry, fit.parts, samples=5000)
    assert all(c[0] == 1.0 for c in cov.values())
    # independently: the finger box where the URDF puts it, at several openings, in link1's frame
    C = np.array([s.center for s in fit.geometry.shapes if s.link == "link1"])
    R = np.array([s.radius for s in fit.geometry.shapes if s.link == "link1"])
    q = np.array([0.7])
    link1 = robot.link_poses(q)[0]
    rng = np.random.default_rng(0)
    signs = rng.uniform(-1, 1, size=(2000, 3))  # points on the box's faces (its surface is covered)
    signs[np.arange(2000), rng.integers(3, size=2000)] = rng.choice([-1.0, 1.0], size=2000)
    box = signs * [0.01, 0.005, 0.02]
    c, s = np.cos(0.7), np.sin(0.7)
    Rz = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]])
    c5, s5 = np.cos(0.5), np.sin(0.5)
    R5 = np.array([[c5, -s5, 0], [s5, c5, 0], [0, 0, 1]])
    for opening in (-0.01, 0.0, 0.013, 0.03):
        world = (Rz @ (R5 @ (box + [0, opening, 0]).T + np.array([[0.03], [0], [0.3]]))).T + [0, 0, 0.05]
        local = (world - link1[:3, 3]) @ link1[:3, :3]
        assert (np.linalg.norm(local[:, None] - C[None], axis=2) <= R).any(1).all(), opening


def test_package_paths_resolve_from_a_folder_above_or_from_packages(grip, tmp_path):
    tree = symkin.Tree.from_urdf(grip)
    fit = fit_urdf(grip, tree, 0.03, progress=False)
    assert any(p.urdf_link == "arm" for p in fit.parts)
    moved = tmp_path / "elsewhere.urdf"
    moved.write_text(URDF)
    with pytest.warns(UserWarning, match="package://"):
        fit_urdf(moved, symkin.Tree.from_urdf(moved), 0.03, progress=False)
    packages = {"grip_pkg": grip.parent.parent}
    fit = fit_urdf(moved, symkin.Tree.from_urdf(moved), 0.03, packages, progress=False)
    assert any(p.urdf_link == "arm" for p in fit.parts)


def test_unreadable_mesh_is_skipped_naming_file_and_link(grip):
    (grip.parent.parent / "meshes" / "arm.stl").write_bytes(b"")
    with pytest.warns(UserWarning, match=r"link 'arm'.*arm\.stl"):
        fit = fit_urdf(grip, symkin.Tree.from_urdf(grip), 0.03, progress=False)
    assert [p.urdf_link for p in fit.parts] == ["base_link", "finger"]
    assert len(fit.skipped) == 1


def test_no_mesh_at_all_is_an_error(tmp_path):
    path = tmp_path / "bare.urdf"
    path.write_text('<robot name="b"><link name="a"/><link name="b"/><joint name="j" type="revolute">'
                    '<parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint></robot>')  # fmt: skip
    with pytest.raises(GeometryError, match="no collision mesh"):
        fit_urdf(path, progress=False)


def test_cli_fit_reports_count_coverage_and_excess(grip, tmp_path, capsys):
    out = tmp_path / "spheres.json"
    args = ["geometry", "fit", str(grip), "--max-excess", "0.02", "--samples", "2000", "--json"]
    args += ["-o", str(out)]
    code = main(args)
    assert code == 0
    data = json.loads(capsys.readouterr().out)
    assert data == json.loads(out.read_text())
    assert data["max_excess"] == 0.02 and data["spheres"] == len(data["sphere_list"]) > 0
    for row in data["links"]:
        assert row["coverage"] == 1.0 and row["excess_bound"] <= 0.02 + 3e-6
    assert main(["geometry", "fit", str(grip), "--max-excess", "0.03", "--samples", "500"]) == 0
    text = capsys.readouterr().out
    assert "spheres" in text and "coverage of" in text and "100.000%" in text


@pytest.mark.parametrize(
    "args",
    [
        ["geometry", "fit", "nosuchrobot"],
        ["geometry", "fit", "missing.urdf"],
        ["geometry", "fit", "panda", "--max-excess", "0"],
        ["geometry", "fit", "panda", "--max-excess", "-1"],
        ["geometry", "fit", "panda", "--max-excess", "nan"],
        ["geometry", "fit", "x.urdf", "--package", "novalue"],
        ["geometry", "builtins", "puma560"],
        ["geometry"],
    ],
)
def test_cli_mistakes_are_one_line_exit_2(args, capsys):
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 or err[-1].startswith("symkin: error")


def test_cli_builtins_prints_the_stored_figures(capsys):
    assert main(["geometry", "builtins"]) == 0
    text = capsys.readouterr().out
    for name in ("panda", "ur3", "ur5", "ur10", "lbr_iiwa14"):
        assert f"{name}: " in text
