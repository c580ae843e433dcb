"""The user guide's command-line path through `examples/ur5.urdf` (docs/guide/robots.md): list the
tree, compile one chain with a tool offset into a folder, load it back, compile the whole tree;
every result against the built-in UR5 (its DH table) with the same constant transforms appended."""

from __future__ import annotations

import numpy as np

import symkin
from symkin.cli.main import main
from tests.test_readme import DOCS, ROOT

PAGE = DOCS / "guide" / "robots.md"  # moved there from the README
URDF = ROOT / "examples" / "ur5.urdf"
TOOL = "0 0 0.1 0 pi/2 0"


def test_the_guide_names_the_shipped_urdf_and_these_commands():
    text = PAGE.read_text()
    assert f'symkin compile examples/ur5.urdf:tool0 --tool "{TOOL}" -o build/arm' in text
    assert "symkin list-frames examples/ur5.urdf" in text and URDF.is_file()


def test_list_frames_shows_both_leaves(capsys):
    assert main(["list-frames", str(URDF)]) == 0
    out = capsys.readouterr().out
    assert "6 independent joints, 2 leaf links" in out and "tool0,camera" in out


def test_a_chain_with_a_tool_compiles_into_a_folder_and_loads_back(capsys, tmp_path):
    out = tmp_path / "arm"
    assert main(["compile", f"{URDF}:tool0", "--tool", TOOL, "-o", str(out)]) == 0
    capsys.readouterr()
    kin = symkin.load_compiled(out)
    ur5 = symkin.load("ur5")
    T_tool = np.eye(4)
    T_tool[:3, :3] = [[0, 0, 1], [0, 1, 0], [-1, 0, 0]]  # pitch pi/2
    T_tool[2, 3] = 0.1
    for q in ur5.random_q(20, seed=4):
        assert np.abs(kin.fkine(q) - ur5.fkine(q) @ T_tool).max() < 1e-12
        assert np.abs(kin.jacob0(q) - ur5.with_tool(TOOL).jacob0(q)).max() < 1e-12


def test_the_tree_compiles_and_its_camera_matches_the_dh_arm(capsys):
    tree = symkin.Tree.from_urdf(URDF)
    assert tree.frames == ("tool0", "camera") and tree.n == 6
    kin = symkin.compile(tree, backend="c")
    ur5 = symkin.load("ur5")
    flange = symkin.Robot.from_ets(str(ur5.ets).removesuffix(" tz(0.0823)"), name="flange")
    camera = flange.with_tool("tx(0.05) tz(0.06) Ry(-pi/2)")
    q = ur5.random_q(50, seed=5)
    T = kin.fkine_all(q)
    assert np.abs(T[:, 0] - ur5.fkine(q)).max() < 1e-12
    assert np.abs(T[:, 1] - camera.fkine(q)).max() < 1e-12
    assert np.abs(kin.jacob0(q, frame="camera") - camera.jacob0(q)).max() < 1e-12
    assert main(["check", f"{URDF}:camera", "--backend", "c", "--samples", "5"]) == 0
