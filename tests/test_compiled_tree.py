"""symkin.load_compiled reads back the code of a kinematic tree that write_generated wrote, on every
backend, into the same compiled tree kinematics symkin.compile gives; the manifest rebuilds the
tree exactly without its URDF. (Chains: tests/test_compiled.py.)"""

from __future__ import annotations

import json

import numpy as np
import pytest

import symkin
from symkin import Tree
from symkin.errors import CompileError
from tests.conftest import assert_close
from tests.model.tree_urdfs import GRIPPER, QUADRUPED

BACKENDS = ("c", "numpy", "casadi")
FIELDS = ("name", "base_link", "segments", "slots", "frames", "frame_segments", "joint_names", "source")


@pytest.fixture(scope="module", params=["quadruped", "gripper"])
def tree(request) -> Tree:
    # quadruped: exact atan2 constants, a prismatic joint, a continuous joint without a speed limit;
    # gripper: mimic joints with fractional multipliers and offsets
    return Tree.from_urdf({"quadruped": QUADRUPED, "gripper": GRIPPER}[request.param])


def _same_tree(a: Tree, b: Tree) -> None:
    for name in FIELDS:
        assert getattr(a, name) == getattr(b, name), name
    assert a.key == b.key
    np.testing.assert_array_equal(a.qlim, b.qlim)
    np.testing.assert_array_equal(a.velocity, b.velocity)  # NaN where the URDF gives no speed


@pytest.mark.parametrize("backend", BACKENDS)
def test_a_tree_folder_loads_back_as_its_compiled_kinematics(tmp_path, tree, backend):
    paths = symkin.write_generated(tree, backend, tmp_path)
    manifest = next(p for p in paths if p.name.endswith(".symkin.json"))
    data = json.loads(manifest.read_text())
    assert data["kind"] == "tree" and data["backend"] == backend
    kin = symkin.load_compiled(tmp_path)
    assert isinstance(kin, symkin.Kinematics) and kin.backend == backend
    _same_tree(kin.tree, tree)
    assert kin.files == symkin.compile(tree, backend).files
    Q = tree.random_q(4, seed=3)
    assert_close(kin.fkine_all(Q), tree.fkine_all(Q), 1e-13, "fkine_all")
    assert_close(kin.jacob0_all(Q), tree.jacob0_all(Q), 1e-13, "jacob0_all")
    for f in tree.frames:
        assert_close(kin.fkine(Q[0], frame=f), tree.fkine(Q[0], f), 1e-13, f"fkine {f}")
        assert_close(kin.jacob0(Q, frame=f), tree.jacob0(Q, f), 1e-13, f"jacob0 {f}")


def test_an_edited_tree_file_is_refused_unless_not_verified(tmp_path):
    tree = Tree.from_urdf(QUADRUPED)
    paths = symkin.write_generated(tree, "numpy", tmp_path)
    (module,) = [p for p in paths if p.suffix == ".py"]
    module.write_text(module.read_text().replace("cos(", "sin("))
    with pytest.raises(CompileError, match="differs from what symkin wrote"):
        symkin.load_compiled(tmp_path)
    edited = symkin.load_compiled(tmp_path, verify=False)  # loads the edited code as it is
    q = tree.random_q(seed=1)
    assert np.abs(edited.fkine_all(q) - tree.fkine_all(q)).max() > 1e-3


def test_a_prefixed_tree_among_others_is_chosen_by_name_and_its_c_controllers_run(tmp_path):
    quad, grip = Tree.from_urdf(QUADRUPED), Tree.from_urdf(GRIPPER)
    symkin.write_generated(quad, "c", tmp_path, prefix="legs")
    symkin.write_generated(grip, "numpy", tmp_path)
    symkin.write_generated(symkin.load("planar2"), "c", tmp_path)
    with pytest.raises(CompileError, match="several robots"):
        symkin.load_compiled(tmp_path)
    kin = symkin.load_compiled(tmp_path, name="legs")
    assert kin.c_prefix == "legs" and kin.frames == quad.frames
    assert symkin.load_compiled(tmp_path, name="gripper").backend == "numpy"  # the tree's name
    assert symkin.load_compiled(tmp_path, name="symkin_gripper_tree").tree.name == "gripper"
    assert symkin.load_compiled(tmp_path, name="planar2").robot.name == "planar2"
    q = quad.random_q(seed=2)
    res = kin.ik(quad.fkine(q, "l_foot"), frame="l_foot", q0=q + 0.05, we=[1, 1, 1, 0, 0, 0])
    assert (
        res.success
        and np.abs(quad.fkine(res.q, "l_foot")[:3, 3] - quad.fkine(q, "l_foot")[:3, 3]).max() < 1e-6
    )
    fns = kin.c_controller_functions("l_foot")  # the prefixed entry points of the C controllers
    assert fns is not None and fns["fkine"].__name__ == f"legs_fkine_{quad.frame_position('l_foot')}"


def test_single_precision_tree_code_is_refused_as_for_chains(tmp_path):
    symkin.write_generated(Tree.from_urdf(QUADRUPED), "c", tmp_path / "tree", precision="float")
    symkin.write_generated(symkin.load("planar2"), "c", tmp_path / "chain", precision="float")
    messages = []
    for sub in ("tree", "chain"):
        with pytest.raises(CompileError, match="float-precision C code") as err:
            symkin.load_compiled(tmp_path / sub)
        messages.append(str(err.value).replace(str(tmp_path / sub), "DIR"))
    assert messages[0] == messages[1]


def test_manifests_without_a_kind_are_chains_and_unknown_kinds_or_broken_trees_are_refused(tmp_path):
    robot = symkin.load("planar2")
    paths = symkin.write_generated(robot, "numpy", tmp_path / "old")
    manifest = next(p for p in paths if p.name.endswith(".symkin.json"))
    data = json.loads(manifest.read_text())
    assert data.pop("kind") == "chain"  # as symkin wrote chain manifests before trees had them
    manifest.write_text(json.dumps(data))
    assert symkin.load_compiled(tmp_path / "old").robot.name == "planar2"
    manifest.write_text(json.dumps({**data, "kind": "forest"}))
    with pytest.raises(CompileError, match="unknown kind"):
        symkin.load_compiled(tmp_path / "old")
    paths = symkin.write_generated(Tree.from_urdf(GRIPPER), "numpy", tmp_path / "tree")
    manifest = next(p for p in paths if p.name.endswith(".symkin.json"))
    data = json.loads(manifest.read_text())
    data["robot"]["segments"][0]["ets"] = "tz(0.2) Ry(q7"
    manifest.write_text(json.dumps(data))
    with pytest.raises(CompileError, match="the tree in the manifest is unreadable"):
        symkin.load_compiled(tmp_path / "tree")


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_a_one_frame_tree_through_a_plain_mimic_joint_compiles(backend):
    # finger b follows finger a (off its path) with multiplier 1, as panda_finger_joint2 does in
    # example-robot-data's panda: the path is serial but no chain Robot, so no link_poses
    urdf = GRIPPER.replace(
        '<mimic joint="finger_a" multiplier="-1" offset="0.01"/>', '<mimic joint="finger_a"/>'
    )
    tree = Tree.from_urdf(urdf, frames=["fb"])
    assert any(s.is_mimic for s in tree.slots)
    kin = symkin.compile(tree, backend=backend)
    Q = tree.random_q(5, seed=0)
    for kind in ("fkine", "jacob0", "hessian0"):
        assert_close(getattr(kin, kind)(Q, "fb"), getattr(tree, kind)(Q, "fb"), 1e-12, kind)
