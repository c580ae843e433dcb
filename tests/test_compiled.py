"""symkin.load_compiled reads back what `symkin compile -o DIR` (and write_generated) wrote, on every
backend; folders that are not one give a clear error."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

import symkin
from symkin.cli.main import main
from symkin.errors import CompileError
from tests.conftest import assert_close


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_cli_output_loads_back(tmp_path, capsys, backend: str) -> None:
    out = tmp_path / "ur5"
    assert main(["compile", "ur5", "--backend", backend, "--tool", "tz(0.1)", "-o", str(out)]) == 0
    assert "symkin.load_compiled" in capsys.readouterr().out
    kin = symkin.load_compiled(out)
    assert kin.backend == backend and kin.robot.name == "ur5"
    ref = symkin.load("ur5").with_tool("tz(0.1)")
    assert str(kin.robot.ets) == str(ref.ets)
    np.testing.assert_array_equal(kin.robot.qlim, ref.qlim)
    np.testing.assert_array_equal(kin.robot.qd_max, ref.qd_max)
    assert kin.robot.joint_names == ref.joint_names and set(kin.robot.configs) == set(ref.configs)
    Q = ref.random_q(5, seed=0)
    assert_close(kin.fkine(Q), ref.fkine(Q), 1e-12, "fkine")
    assert_close(kin.jacob0(Q[0]), ref.jacob0(Q[0]), 1e-12, "jacob0")
    assert kin.ik(kin.fkine(Q[1])).success


def test_a_prefixed_c_folder_loads_and_solves_ik(tmp_path) -> None:
    robot = symkin.load("ur5")
    symkin.write_generated(robot, "c", tmp_path, prefix="arm_b")
    symkin.write_generated(symkin.load("planar2"), "numpy", tmp_path)
    with pytest.raises(CompileError, match="several robots"):
        symkin.load_compiled(tmp_path)
    kin = symkin.load_compiled(tmp_path, name="arm_b")
    assert kin.c_prefix == "arm_b" and kin.robot.name == "ur5"
    q = robot.random_q(seed=1)
    res = kin.ik(kin.fkine(q))  # the C IK solver finds the prefixed entry points
    assert res.success and np.abs(robot.fkine(res.q) - kin.fkine(q)).max() < 1e-6
    qd, _ = symkin.MMC(kin).step(q, np.array([0.05, 0, 0, 0, 0, 0]))  # and the C controller
    assert_close(robot.jacob0(q) @ qd, [0.05, 0, 0, 0, 0, 0], 1e-9, "MMC on the loaded kinematics")
    assert symkin.load_compiled(tmp_path, name="planar2").backend == "numpy"


def test_not_a_compiled_folder(tmp_path) -> None:
    with pytest.raises(CompileError, match="does not exist"):
        symkin.load_compiled(tmp_path / "nowhere")
    (tmp_path / "file.txt").write_text("x")
    with pytest.raises(CompileError, match="is not a folder"):
        symkin.load_compiled(tmp_path / "file.txt")
    with pytest.raises(CompileError, match="not a folder written by `symkin compile -o DIR`"):
        symkin.load_compiled(tmp_path)


def test_edited_missing_or_broken_files_are_reported(tmp_path) -> None:
    robot = symkin.load("planar2")
    paths = symkin.write_generated(robot, "numpy", tmp_path / "a")
    (module,) = [p for p in paths if p.suffix == ".py"]
    manifest = next(p for p in paths if p.name.endswith(".symkin.json"))
    module.write_text(module.read_text().replace("cos(", "sin("))
    with pytest.raises(CompileError, match="differs from what symkin wrote"):
        symkin.load_compiled(tmp_path / "a")
    edited = symkin.load_compiled(tmp_path / "a", verify=False)  # loads the edited code as it is
    assert np.abs(edited.fkine([0.3, 0.2]) - robot.fkine([0.3, 0.2])).max() > 0.1
    module.unlink()
    with pytest.raises(CompileError, match="lacks"):
        symkin.load_compiled(tmp_path / "a")
    shutil.rmtree(tmp_path / "a")
    paths = symkin.write_generated(robot, "numpy", tmp_path / "b")
    manifest = next(p for p in paths if p.name.endswith(".symkin.json"))
    data = json.loads(manifest.read_text())
    data["files"]["../evil.py"] = "0"
    manifest.write_text(json.dumps(data))
    with pytest.raises(CompileError, match="not a plain file name"):
        symkin.load_compiled(tmp_path / "b")
    manifest.write_text("{not json")
    with pytest.raises(CompileError, match="not a readable symkin manifest"):
        symkin.load_compiled(tmp_path / "b")
