"""Every `symkin` command runs; user mistakes exit non-zero with a one-line message."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin.cli.main import main
from symkin.model.robots import list_robots, load

ROOT = Path(__file__).resolve().parents[1]


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    out = capsys.readouterr()
    return code, out.out, out.err


def test_list(capsys):
    code, out, _ = run(capsys, "list")
    assert code == 0
    for name in list_robots():
        assert name in out
    code, out, _ = run(capsys, "list", "--json")
    assert {r["name"] for r in json.loads(out)} == set(list_robots())


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_compile_writes_files_and_shows_the_robot(capsys, tmp_path, backend):
    code, out, _ = run(capsys, "compile", "planar3", "--backend", backend, "-o", str(tmp_path))
    assert code == 0, out
    assert "fkine" in out and "jacob0" in out and "us per call" in out
    written = sorted(p.name for p in tmp_path.iterdir())
    assert written and all("planar3" in name for name in written)


def test_compile_accepts_an_ets_string_a_dh_file_and_a_urdf(capsys, tmp_path):
    code, out, _ = run(capsys, "compile", "Rz(q) tx(0.5) Rz(q) tx(0.25)", "--backend", "numpy")
    assert code == 0 and "2 joints" in out
    dh = tmp_path / "arm.dh"
    dh.write_text("# symkin dh: standard\n# name: twolink\ntype d a alpha\nR 0 1 0\nR 0 1 0\n")
    code, out, _ = run(capsys, "compile", str(dh), "--backend", "numpy")
    assert code == 0 and "twolink" in out
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(
        "<robot name='onelink'><link name='a'/><link name='b'/>"
        "<joint name='j' type='revolute'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
        "<limit lower='-1' upper='1' effort='1' velocity='1'/></joint></robot>"
    )
    code, out, _ = run(capsys, "compile", str(urdf), "--backend", "numpy")
    assert code == 0 and "onelink" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["compile", "pandaa"], "panda"),  # unknown robot: suggests the close match
        (["compile", "Rz(q) foo(1)"], "unknown token"),
        (["compile", "/nonexistent/robot.urdf"], "robot.urdf"),
        (["compile", "planar2", "--backend", "numpy", "-o", "/proc/forbidden/x"], ""),
        (["ik", "ur5", "--pose", "1 2 3"], "6 numbers"),
        (["ik", "ur5"], "exactly one of"),
        (["ik", "ur5", "--target-q", "0 0 nan 0 0 0"], "finite"),
        (["compile", "ur5", "--tool", "tz(q)"], "joint"),
        (["compile", "ur5", "--base", "1 2 3 4"], "4 numbers"),
        (["derive", "planar2", "--sections", "fk,jacobians"], "unknown section(s) ['jacobians']"),
        (["ik", "ur5", "--target-q", "0 0 0 0 0 0", "--we", "1 1 1"], "6 numbers"),
        (["ik", "ur5", "--target-q", "0 0 0 0 0 0", "--we", "0 0 0 0 0 0"], "not all 0"),
        (["ik", "ur5", "--target-q", "0 0 0 0 0 0", "--all", "--lam", "0.1"], "numerical methods"),
        (["plot", "ur5", "--q", "1 2"], "6 numbers"),
        (["bench", "kin", "--tool", "tz(0.1)"], "ROBOT"),
        (["check", "nosuchrobot"], "nosuchrobot"),
    ],
)
def test_user_errors_exit_2_with_one_line(capsys, argv, message):
    code, out, err = run(capsys, *argv)
    assert code == 2
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("symkin: error:"), err
    assert message in lines[0]


def test_check_passes_and_reports_json(capsys):
    code, out, _ = run(capsys, "check", "planar3", "--backend", "numpy", "--samples", "5")
    assert code == 0 and "all ok" in out
    code, out, _ = run(capsys, "check", "planar3", "--backend", "c", "--samples", "5", "--json")
    data = json.loads(out)
    assert code == 0 and data["ok"] and data["rows"]


def test_ik_solves_a_pose_given_on_the_command_line(capsys):
    robot = load("ur5")
    q = robot.random_q(seed=5)
    code, out, _ = run(capsys, "ik", "ur5", "--target-q", " ".join(map(str, q)), "--json")
    assert code == 0
    res = json.loads(out)
    assert res["success"]
    np.testing.assert_allclose(robot.fkine(res["q"]), robot.fkine(q), atol=1e-6)
    T = robot.fkine(q)
    code, out, _ = run(capsys, "ik", "ur5", "--matrix", " ".join(map(str, T.ravel())), "--method", "GN")
    assert code == 0 and "solved" in out


@pytest.mark.parametrize("command", ["ik", "servo"])
def test_a_matrix_that_is_not_se3_is_refused_naming_the_option(capsys, command):
    """The one pose rule on --matrix (issue 36, item 6): one line naming the option, exit 2."""
    T = load("ur5").fkine(load("ur5").qr)
    for bad, why in (([1, 0, 0, 1], "bottom row"), ([0, 0, 0, 2], "bottom row")):
        M = np.vstack([T[:3], bad])
        code, _, err = run(capsys, command, "ur5", "--matrix", " ".join(map(str, M.ravel())))
        assert code == 2 and f"--matrix has {why}" in err and len(err.strip().splitlines()) == 1
    M = T.copy()
    M[:3, :3] *= -1  # a reflection
    code, _, err = run(capsys, command, "ur5", "--matrix", " ".join(map(str, M.ravel())))
    assert code == 2 and "--matrix rotation is a reflection" in err


def test_ik_unreachable_target_exits_1(capsys):
    code, out, _ = run(capsys, "ik", "planar2", "--pose", "5 0 0 0 0 0", "--json")
    assert code == 1 and json.loads(out)["success"] is False


def test_generate_check_reports_stale_folder(capsys, tmp_path):
    code, out, _ = run(capsys, "generate", "--check", "-o", str(tmp_path))
    assert code == 1 and "out of date" in out


def test_bench_kin_runs_small(capsys):
    code, out, _ = run(capsys, "bench", "kin", "planar2", "--batch", "1000", "--json")
    assert code == 0
    data = json.loads(out)
    assert data["per_call_us"]["c (extension)"]["jacob0"] > 0
    assert data["batched_M_per_s"]["c"]["fkine"] > 0


def test_bench_ik_runs_small(capsys):
    code, out, _ = run(capsys, "bench", "ik", "-n", "20")
    assert code == 0 and "Table 1" in out and "LM (Chan lambda=0.1)" in out


def test_python_m_symkin_and_help():
    res = subprocess.run([sys.executable, "-m", "symkin", "--help"], capture_output=True, text=True, cwd=ROOT)
    assert res.returncode == 0
    for cmd in ("compile", "derive", "check", "ik", "servo", "bench", "list"):
        assert cmd in res.stdout
    res = subprocess.run(
        [sys.executable, "-m", "symkin", "frobnicate"], capture_output=True, text=True, cwd=ROOT
    )
    assert res.returncode == 2


@pytest.mark.parametrize("controller", ["mmc", "rrmc", "qrmc"])
def test_servo_arrives_and_plots(capsys, tmp_path, controller):
    robot = load("panda")
    target = robot.qr + np.array([0.2, -0.1, 0.1, 0.2, 0.0, 0.1, 0.0])
    png = tmp_path / "servo.png"
    argv = ["servo", "panda", "--target-q", " ".join(map(str, target)), "--controller", controller]
    code, out, _ = run(capsys, *argv, "--plot", str(png), "--json")
    data = json.loads(out)
    assert code == 0 and data["arrived"], data
    assert png.stat().st_size > 1000
    np.testing.assert_allclose(robot.fkine(data["q_final"])[:3, 3], robot.fkine(target)[:3, 3], atol=0.05)
    assert data["max_speed_over_limit"]["applied"] <= 1.0 + 1e-12


def test_servo_says_why_it_did_not_arrive(capsys):
    """A target out of the UR5's reach: exit 1, the joint speeds and the last step's status."""
    argv = ["servo", "ur5", "--q0", "0 -1 0 -1 1 0.3", "--pose", "1.5 0 0.3 0 0 0", "--controller", "qrmc"]
    code, out, _ = run(capsys, *argv, "--max-steps", "60")
    assert code == 1 and "did not arrive after 60 steps" in out
    assert "joint speeds up to" in out and "the last step was" in out


def test_bench_qrmc_runs_and_plots(capsys, tmp_path):
    png = tmp_path / "qrmc.png"
    code, out, _ = run(capsys, "bench", "qrmc", "--plot", str(png))
    assert code == 0 and png.stat().st_size > 1000
    for task in ("lost direction", "finish at a singularity", "start and finish at singularities"):
        assert task in out
    code, out, _ = run(capsys, "bench", "qrmc", "--json")
    rows = json.loads(out)["singular"]["tasks"]["lost direction"]
    assert rows["qrmc"]["arrived"] and rows["qrmc"]["max_requested_over_limit"] <= 1.0


def test_bench_mmc_runs_small(capsys, tmp_path):
    png = tmp_path / "fig3.png"
    code, out, _ = run(capsys, "bench", "mmc", "planar3", "-n", "2", "--plot", str(png))
    assert code == 0 and "Table I" in out and png.exists()


def test_derive_prints_markdown_and_writes_latex(capsys, tmp_path):
    code, out, _ = run(capsys, "derive", "planar3", "--symbolic-constants")
    assert code == 0 and "l_{1}" in out and "$$" in out
    tex = tmp_path / "planar3.tex"
    code, out, _ = run(capsys, "derive", "planar2", "--format", "latex", "-o", str(tex))
    text = tex.read_text()
    assert code == 0 and text.startswith("\\documentclass") and text.rstrip().endswith("\\end{document}")


def test_ik_all_prints_every_closed_form_solution(capsys):
    code, out, _ = run(capsys, "ik", "puma560", "--target-q", "0.3 0.7 -0.9 0.4 0.6 -0.2", "--all")
    assert code == 0 and "solution(s)" in out
    code, out, _ = run(capsys, "ik", "ur5", "--pose", "0.4 0.2 0.3 0 3.14159 0", "--all", "--json")
    data = json.loads(out)
    assert code == 0 and len(data["solutions"]) == 8 and max(data["fk_error"]) < 1e-10
    code, out, _ = run(capsys, "ik", "ur5", "--pose", "3 0 0 0 0 0", "--method", "analytic")
    assert code == 1 and "out of reach" in out


def test_ik_all_refuses_a_redundant_arm(capsys):
    code, _, err = run(capsys, "ik", "panda", "--pose", "0.4 0.2 0.3 0 3.14159 0", "--all")
    assert code == 2 and "numerical IK" in err and len(err.strip().splitlines()) == 1


def test_derive_ik(capsys):
    code, out, _ = run(capsys, "derive", "ur5", "--ik")
    assert code == 0 and "Subproblem 4" in out and "Branches" in out
    code, out, _ = run(capsys, "derive", "stanford", "--ik", "--format", "latex")
    assert code == 0 and out.lstrip().startswith("\\documentclass") and "\\[" in out


def test_derive_long_chain_shows_named_intermediates(capsys):
    ets = " ".join(f"R{'xyz'[j % 3]}(q{j}) tx(0.1) tz(0.05)" for j in range(10))
    code, out, _ = run(capsys, "derive", ets)
    assert code == 0 and "\\zeta_{" in out and "one from the previous" in out
    code, out, _ = run(capsys, "derive", "planar3", "--form", "program")
    assert code == 0 and "\\zeta_{" in out


def test_bench_compile_runs_small(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    plot = tmp_path / "compile.png"
    code, out, _ = run(capsys, "bench", "compile", "planar2", "--joints", "3,11", "--plot", str(plot))
    assert code == 0, out
    assert "planar2" in out and "chain3_0" in out and "chain11_0" in out and "program" in out
    assert plot.stat().st_size > 1000
    code, out, err = run(capsys, "bench", "compile", "--joints", "6,x")
    assert code == 2 and "--joints" in err


def test_compile_single_precision_and_libm(capsys, tmp_path):
    code, out, _ = run(
        capsys, "compile", "planar3", "--precision", "float", "--prefix", "p3f", "-o", str(tmp_path)
    )
    assert code == 0, out
    assert "single-precision code against double" in out
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p3f.c", "p3f.h", "p3f.symkin.json"]
    with pytest.raises(symkin.CompileError, match="float-precision C code"):
        symkin.load_compiled(tmp_path)
    code, _, err = run(capsys, "compile", "planar3", "--libm")
    assert code == 2 and "-o DIR" in err
    code, _, err = run(
        capsys, "compile", "planar3", "--backend", "numpy", "--precision", "float", "-o", str(tmp_path)
    )
    assert code == 2 and "C backend only" in err


def _options():  # noqa: ANN202
    import argparse

    from symkin.cli.main import build_parser

    parser = build_parser()
    (sub,) = [a for a in parser._actions if isinstance(a, argparse._SubParsersAction)]
    for name, cmd in sub.choices.items():
        for action in cmd._actions:
            if action.option_strings and action.help != argparse.SUPPRESS and action.dest != "help":
                yield name, cmd, action


def test_every_option_has_help_and_shows_its_default():
    import argparse

    seen = 0
    for name, cmd, action in _options():
        seen += 1
        assert action.help, f"symkin {name} {action.option_strings[0]} has no help"
        text = cmd.formatter_class(prog="x")._get_help_string(action)
        if action.default is not None and action.default is not False and action.default != argparse.SUPPRESS:
            assert "default" in text.lower(), f"symkin {name} {action.option_strings[0]} hides its default"
    assert seen > 40
    help_text = subprocess.run(
        [sys.executable, "-m", "symkin", "ik", "--help"], capture_output=True, text=True, cwd=ROOT
    ).stdout
    assert "--target-q" in help_text and "--from-q" not in help_text
    assert "(default: LM)" in help_text and "--we" in help_text and "--ilimit" in help_text
    assert "seed of the random restarts (default: 0)" in " ".join(help_text.split())


def test_every_command_with_a_robot_takes_tool_and_base():
    import argparse

    from symkin.cli.main import build_parser

    (sub,) = [a for a in build_parser()._actions if isinstance(a, argparse._SubParsersAction)]
    with_robot = []
    for name, cmd in sub.choices.items():
        dests = {a.dest for a in cmd._actions}
        if "robot" in dests:
            with_robot.append(name)
            assert {"tool", "base"} <= dests, f"symkin {name} lacks --tool/--base"
    assert {"compile", "check", "derive", "ik", "servo", "plot", "bench"} <= set(with_robot)


def test_from_q_still_works_but_says_it_is_renamed(capsys):
    q = "0.3 -1.2 1.4 -0.6 1.1 0.4"
    code, out, err = run(capsys, "ik", "ur5", "--from-q", q, "--json")
    assert code == 0 and json.loads(out)["success"]
    assert "--from-q is deprecated; use --target-q" in err


def test_ik_options_reach_the_solver(capsys):
    robot = load("ur5")
    q = np.array([0.3, -1.2, 1.4, -0.6, 1.1, 0.4])
    target = " ".join(map(str, q))
    # position only: the position is reached, the orientation is free
    code, out, _ = run(capsys, "ik", "ur5", "--target-q", target, "--we", "position", "--json")
    res = json.loads(out)
    assert code == 0 and res["success"]
    np.testing.assert_allclose(robot.fkine(res["q"])[:3, 3], robot.fkine(q)[:3, 3], atol=1e-6)
    # a loose tolerance is met with a larger residual than the default's
    code, out, _ = run(
        capsys, "ik", "ur5", "--target-q", target, "--tol", "1e-2", "--q0", "0.2 -1 1.2 -0.5 1 0.3", "--json"
    )
    loose = json.loads(out)
    assert code == 0 and loose["success"] and 1e-9 < loose["residual"] < 1e-2
    # one search of one iteration cannot solve it
    code, out, _ = run(
        capsys, "ik", "ur5", "--target-q", target, "--ilimit", "1", "--slimit", "1", "--lam", "0.5", "--json"
    )
    res = json.loads(out)
    assert code == 1 and res["iterations"] == 1 and res["searches"] == 1


def test_compile_a_urdf_chain_with_a_tool_offset(capsys, tmp_path):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text(
        "<robot name='arm'><link name='a'/><link name='b'/><link name='c'/>"
        "<joint name='j1' type='revolute'><parent link='a'/><child link='b'/><axis xyz='0 0 1'/>"
        "<origin xyz='0 0 0.2'/><limit lower='-2' upper='2' effort='1' velocity='1'/></joint>"
        "<joint name='j2' type='revolute'><parent link='b'/><child link='c'/><axis xyz='0 1 0'/>"
        "<origin xyz='0.3 0 0'/><limit lower='-2' upper='2' effort='1' velocity='1'/></joint></robot>"
    )
    out_dir = tmp_path / "out"
    code, out, _ = run(
        capsys, "compile", str(urdf), "--tool", "0 0 0.1 0 pi/2 0", "--base", "tz(1)", "-o", str(out_dir)
    )
    assert code == 0 and "tz(1) tz(0.2) Rz(q0) tx(0.3) Ry(q1) tz(0.1) Ry(pi/2)" in out
    import symkin

    kin = symkin.load_compiled(out_dir)
    plain = symkin.Robot.from_urdf(urdf)
    q = np.array([0.4, -0.3])
    Tt = np.array([[0, 0, 1, 0], [0, 1, 0, 0], [-1, 0, 0, 0.1], [0, 0, 0, 1.0]])
    Tb = np.eye(4)
    Tb[2, 3] = 1
    np.testing.assert_allclose(kin.fkine(q), Tb @ plain.fkine(q) @ Tt, atol=1e-15)


@pytest.mark.parametrize(
    "argv",
    [["check", "planar2", "--backend", "numpy", "--samples", "2"], ["derive", "planar2", "--sections", "fk"]],
)
def test_tool_and_base_on_other_commands(capsys, argv):
    code, out, _ = run(capsys, *argv, "--tool", "tz(0.25)", "--base", "0 0 0.5 0 0 0")
    assert code == 0
    if argv[0] == "derive":
        assert "6 elementary transforms" in out and "z &= 0.75" in out  # base 0.5 + tool 0.25


def test_derive_sections(capsys):
    code, out, _ = run(capsys, "derive", "ur5", "--sections", "fk,jacobian")
    assert code == 0 and "## Forward kinematics" in out and "## The manipulator Jacobian" in out
    assert "## The manipulator Hessian" not in out and "## Link frames" not in out


def test_plot_command_writes_a_png(capsys, tmp_path):
    pytest.importorskip("matplotlib")
    png = tmp_path / "ur5.png"
    code, out, _ = run(capsys, "plot", "ur5", "--q", "qr", "--ellipsoid", "-o", str(png))
    assert code == 0 and f"wrote {png}" in out
    assert png.read_bytes().startswith(b"\x89PNG")
    code, out, _ = run(capsys, "plot", "planar2", "--q", "0.3 0.4", "--tool", "tx(0.2)", "-o", str(png))
    assert code == 0
