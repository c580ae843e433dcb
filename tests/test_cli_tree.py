"""The command line with URDF trees: path.urdf:FRAME, --base-link/--end-link, --frames, list-frames."""

from __future__ import annotations

import json

import pytest

from symkin.cli.common import split_frame
from symkin.cli.main import main
from tests.model.tree_urdfs import GRIPPER, QUADRUPED


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


@pytest.fixture()
def quad(tmp_path):
    path = tmp_path / "quad.urdf"
    path.write_text(QUADRUPED)
    return str(path)


def test_split_frame():
    assert split_frame("a/robot.urdf:tool0") == ("a/robot.urdf", "tool0")
    assert split_frame("robot.urdf") == ("robot.urdf", None)
    assert split_frame("Rz(q) tx(1)") == ("Rz(q) tx(1)", None)
    assert split_frame("panda") == ("panda", None)


def test_list_frames_prints_the_tree(capsys, quad):
    code, out, _ = run(capsys, "list-frames", quad)
    assert code == 0
    assert "8 independent joints, 3 leaf links" in out
    assert "    l_thigh  <- l_hfe (revolute, q1)" in out
    assert "r_hip  <- r_haa (continuous, q5)" in out
    assert "leaf links (the default frames): l_foot,tail_tip,r_foot" in out
    code, out, _ = run(capsys, "list-frames", quad, "--json")
    rows = json.loads(out)
    assert rows[0] == {"depth": 0, "link": "body", "joint": "", "kind": "base"}


def test_list_frames_shows_mimic_joints(capsys, tmp_path):
    path = tmp_path / "g.urdf"
    path.write_text(GRIPPER)
    code, out, _ = run(capsys, "list-frames", str(path), "--base-link", "palm")
    assert code == 0 and "fb  <- finger_b (prismatic, mimics 'finger_a', leaf)" in out


def test_compile_a_tree_with_frames(capsys, quad, tmp_path):
    code, out, _ = run(
        capsys, "compile", quad, "--frames", "r_foot,l_foot", "--backend", "numpy", "-o", str(tmp_path / "g")
    )
    assert code == 0, out
    assert "6 joints and 2 frames: r_foot, l_foot" in out
    assert "max |fkine, jacob0 - numeric reference| = 0.00e+00" in out or "e-1" in out
    assert (tmp_path / "g" / "symkin_quad_tree.py").exists()


def test_compile_reports_a_chain_as_the_tree_of_its_one_frame(capsys, quad):
    """One report: the chain ``quad.urdf:r_foot`` (a Robot) and the one-frame tree ``--frames
    r_foot`` (a Tree) print the same pose, Jacobian, manipulability and check; a tree of several
    frames prints each frame's position; both are checked against the numeric reference."""

    def report(*argv: str) -> list[str]:
        code, out, _ = run(capsys, "compile", *argv, "--backend", "numpy")
        assert code == 0, out
        lines = out.splitlines()
        check = next(ln for ln in lines if ln.startswith("max |fkine, jacob0 - numeric reference| = "))
        assert float(check.rsplit("= ", 1)[1]) < 1e-12
        return lines

    def body(lines: list[str]) -> list[str]:  # what follows the heading, timings and ops, untimed
        return [ln for ln in lines[3:] if "us per call" not in ln and "numeric reference" not in ln]

    chain, one = report(f"{quad}:r_foot"), report(quad, "--frames", "r_foot")
    assert "manipulability: " in "\n".join(body(chain)) and body(chain) == body(one)
    assert chain[0].startswith("quad: 3 joints and 1 frame: ee; ETS (RRR) ")  # a Robot's frame is ee
    assert one[0] == chain[0].replace("frame: ee;", "frame: r_foot;")
    tree = report(quad)
    positions = tree[tree.index("frame positions (m):") + 1 :][:3]
    assert [ln.split()[0] for ln in positions] == ["l_foot", "tail_tip", "r_foot"]


def test_a_branching_urdf_without_a_frame_compiles_every_leaf(capsys, quad):
    code, out, _ = run(capsys, "compile", quad, "--backend", "numpy")
    assert code == 0 and "3 frames: l_foot, tail_tip, r_foot" in out


def test_check_one_frame_and_a_tree(capsys, quad):
    code, out, _ = run(capsys, "check", f"{quad}:r_foot", "--backend", "numpy", "--samples", "3")
    assert code == 0 and "all ok" in out and "symkin check quad" in out
    code, out, _ = run(
        capsys, "check", quad, "--end-link", "l_foot", "--base-link", "l_hip", "--backend", "numpy"
    )
    assert code == 0 and "all ok" in out
    code, out, _ = run(
        capsys, "check", quad, "--frames", "l_foot,tail_tip", "--backend", "numpy", "--samples", "3"
    )
    assert code == 0 and "chain:l_foot" in out and "hessian0 (large q)" in out and "all ok" in out


def test_ik_and_servo_need_one_frame(capsys, quad):
    code, _, err = run(capsys, "ik", quad, "--from-q", "0.1 0.2 0.3")
    assert code == 2 and "branches: name the frame as" in err and "list-frames" in err
    code, out, _ = run(capsys, "ik", f"{quad}:l_foot", "--from-q", "0.1 0.2 0.3", "--backend", "numpy")
    assert code == 0 and "solved" in out
    argv = ["--from-q", "0.1 0.2 0.3", "--q0", "0.15 0.2 0.3", "--controller", "rrmc", "--backend", "numpy"]
    code, out, _ = run(capsys, "servo", quad, "--end-link", "l_foot", *argv, "--json")
    assert code == 0 and json.loads(out)["arrived"]


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["compile", "{quad}:l_foot", "--end-link", "r_foot"], "give one"),
        (["compile", "panda", "--end-link", "tool"], "apply to URDF files only"),
        (["compile", "panda", "--frames", "a,b"], "--frames applies to URDF files only"),
        (["compile", "{quad}", "--frames", "l_foot", "--end-link", "l_foot"], "give either --frames"),
        (["compile", "{quad}", "--frames", "l_foot,nope"], "frame 'nope' is not a link"),
        (["check", "{quad}:nope"], "end_link 'nope' is not a link"),
        (["list-frames", "{quad}", "--base-link", "nope"], "base_link 'nope' is not a link"),
        (["compile", "{quad}", "--prefix", "q", "--backend", "numpy", "-o", "{quad}.out"], "C backend only"),
        (["compile", "{quad}", "--precision", "float"], "give -o too"),
        (["compile", "{quad}", "--strategy", "expanded"], "a tree compiles as one program"),
        (["check", "{quad}", "--tool", "tz(0.1)"], "--tool/--base change one chain"),
        (["compile", "{quad}", "--frames", "l_foot", "--base", "tz(1)"], "--tool/--base change one chain"),
        (["ik", "{quad}", "--target-q", "0 0 0"], "branches: name the frame"),
        (["bench", "tree", "panda"], "takes no ROBOT"),
    ],
)
def test_mistakes_are_one_line_errors(capsys, quad, argv, message):
    code, _, err = run(capsys, *[a.format(quad=quad) for a in argv])
    assert code == 2
    assert message in err and len(err.strip().splitlines()) == 1


def test_derive_a_tree_shows_the_shared_part_once(capsys, tmp_path):
    from tests.model.tree_urdfs import DUAL_ARM

    path = tmp_path / "dual.urdf"
    path.write_text(DUAL_ARM)
    code, out, _ = run(capsys, "derive", str(path))
    assert code == 0
    assert out.count("joint `waist`") == 1  # the torso, once, serving both tools
    assert "on the path to `l_tool`, `r_tool`" in out
    assert "### Frame `l_tool`" in out and "### Frame `r_tool`" in out
    assert "(tolerance 1e-12): ok" in out and "FAILED" not in out
    code, out, _ = run(capsys, "derive", str(path), "--sections", "fk")  # with the link frames it needs
    assert code == 0 and "## Forward kinematics (eq 1)" in out and "## Link frames (eq 5)" in out
    assert "## The manipulator Jacobian" not in out and "## How the results were checked" not in out


def test_resolve_accepts_a_urdf_frame(quad):
    from symkin.model.resolve import resolve_robot

    robot = resolve_robot(f"{quad}:r_foot")
    assert robot.joint_names == ("r_haa", "r_hfe", "r_kfe")


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_a_compiled_tree_folder_loads_back(capsys, quad, tmp_path, backend):
    """``symkin compile TREE -o DIR`` writes a manifest; ``load_compiled(DIR)`` gives the tree's
    kinematics, equal to the numeric reference on every frame."""
    import numpy as np

    import symkin

    code, out, _ = run(capsys, "compile", quad, "--backend", backend, "-o", str(tmp_path))
    assert code == 0 and "which symkin.load_compiled reads" in out
    kin = symkin.load_compiled(tmp_path)
    tree = symkin.Tree.from_urdf(quad)
    assert kin.frames == tree.frames
    q = tree.random_q(5, seed=3)
    np.testing.assert_allclose(kin.fkine_all(q), tree.fkine_all(q), atol=1e-12)
    np.testing.assert_allclose(kin.jacob0_all(q), tree.jacob0_all(q), atol=1e-12)


def test_a_tree_compiles_with_a_prefix_in_single_precision(capsys, quad, tmp_path):
    code, out, _ = run(
        capsys, "compile", quad, "--prefix", "quad", "--precision", "float", "-o", str(tmp_path)
    )
    assert code == 0, out
    assert (tmp_path / "quad.h").exists() and "single-precision code against double" in out
    assert "--prefix quad --precision float" in (tmp_path / "quad.h").read_text()
