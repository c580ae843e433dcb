"""``symkin collide`` and ``symkin bench collide``."""

from __future__ import annotations

import importlib.util
import json

import numpy as np
import pytest

import symkin
from symkin.cli import main


def test_collide_free_and_in_collision(capsys):
    assert main(["collide", "panda", "qr"]) == 0
    out = capsys.readouterr().out
    assert "collision-free" in out and f"{len(symkin.load('panda').geometry.shapes)} shapes" in out
    hand = symkin.load("panda").fkine(symkin.load("panda").qr)[:3, 3]
    sphere = " ".join(map(str, [*hand, 0.05]))
    assert main(["collide", "panda", "qr", "--sphere", sphere]) == 1
    out = capsys.readouterr().out
    assert "IN COLLISION" in out and "obstacle sphere 0" in out


def test_collide_json_and_env_file(tmp_path, capsys):
    scene = tmp_path / "scene.json"
    scene.write_text(
        json.dumps({"boxes": [[0.5, 0, -0.1, 0.5, 0.8, 0.05]], "spheres": [[0.3, 0.3, 0.3, 0.05]]})
    )
    q = "0 -0.3 0 -2.2 0 2.0 0.78"
    assert main(["collide", "panda", *q.split(), "--env", str(scene), "--json", "--top", "3"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["in_collision"] is False and len(data["closest"]) == 3
    assert data["pairs"] == len(
        symkin.compile("panda").collision_pairs(
            symkin.Environment(
                spheres=(symkin.Sphere((0.3, 0.3, 0.3), 0.05),),
                boxes=(symkin.Box((0.5, 0, -0.1), (0.5, 0.8, 0.05)),),
            )
        )
    )
    d = [row["distance"] for row in data["closest"]]
    assert d == sorted(d)


@pytest.mark.parametrize(
    "argv, message",
    [
        (["collide", "puma560"], "no collision geometry"),
        (["collide", "panda", "1", "2"], "7 numbers"),
        (["collide", "panda", "--sphere", "0 0 nan 0.1"], "finite"),
        (["collide", "panda", "--sphere", "0 0 0 -0.1"], "radius"),
        (["collide", "panda", "--env", "/nonexistent/scene.json"], "--env"),
    ],
)
def test_collide_bad_input(argv, message, capsys):
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_bench_collide_runs_and_agrees():
    from symkin.bench.collide import format_collide, run_collide

    r = run_collide("panda", batch=500, progress=False, ik_targets=10)
    assert [row["obstacles"] for row in r["rows"]] == [0, 10, 100]
    assert all(row["batch_ns"] > 0 and row["speedup_batch_vs_numpy"] > 1 for row in r["rows"])
    assert [ik["scene"] for ik in r["ik"]] == ["table top", "10 random spheres", "cage"]
    assert all(ik["aware_in_collision"] == ik["aware_one_in_collision"] == 0 for ik in r["ik"])
    assert all(np.isfinite(ik["ratio"]) and np.isfinite(ik["ratio_one"]) for ik in r["ik"])
    assert r["ik"][2]["obstacles"] == 14 and r["ik"][2]["plain_in_collision"] > 0  # the cage catches some
    assert all(0.1 < row["outside"] < 0.3 and row["ratio"] > 0 for row in r["limits"])
    text = format_collide(r)
    assert "avoiding" in text and "C batch" in text and "beyond" in text
    m = r["mmc"]
    assert m["c_backend"] == "c" and m["steps_with_obstacle_rows"] > 0 and m["c_us"] > 0
    assert "MMC past an obstacle" in text


def test_srdf_command_and_the_srdf_option(tmp_path, capsys):
    out = tmp_path / "panda.srdf"
    assert main(["srdf", "panda", "-o", str(out)]) == 0
    assert "adjacent" in capsys.readouterr().out and "<disable_collisions" in out.read_text()
    assert main(["collide", "panda", "qr", "--json"]) == 0
    full = json.loads(capsys.readouterr().out)
    assert main(["collide", "panda", "qr", "--json", "--srdf", str(out)]) == 0
    lean = json.loads(capsys.readouterr().out)
    assert lean["pairs"] < full["pairs"] and lean["in_collision"] == full["in_collision"] is False
    q = "0 -0.3 0 -2.2 0 2.0 0.78"
    assert main(["ik", "panda", "--target-q", q, "--collision", "--srdf", str(out), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["success"] is True
    other = tmp_path / "other.srdf"
    other.write_text('<robot name="x"><disable_collisions link1="a" link2="b" reason="Never"/></robot>')
    for argv, message in (
        (["collide", "panda", "--srdf", str(other)], "another robot"),
        (["collide", "puma560", "--srdf", str(out)], "no collision geometry"),
        (["ik", "panda", "--target-q", q, "--srdf", str(out)], "--collision"),
        (["servo", "panda", "--target-q", q, "--srdf", str(out)], "--collision"),
        (["bench", "ik", "--srdf", str(out)], "bench collide"),
        (["collide", "panda", "--srdf", str(tmp_path / "none.srdf")], "SRDF"),
        (["ik", "panda", "--target-q", q, "--collision", "--all"], "numerical"),
    ):
        assert main(argv) == 2, argv
        assert message in capsys.readouterr().err, argv


def test_srdf_of_a_urdf_names_its_links(tmp_path, capsys):
    from tests.geometry.test_srdf import ARM

    urdf = tmp_path / "arm2.urdf"
    urdf.write_text(ARM)
    assert main(["srdf", str(urdf)]) == 0
    captured = capsys.readouterr()
    assert '<robot name="arm2">' in captured.out and 'link1="flange" link2="hand"' in captured.out
    srdf = tmp_path / "arm2.srdf"
    srdf.write_text(captured.out)
    assert main(["collide", str(urdf), "0 0 0", "--srdf", str(srdf), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["pairs"] == 0  # every pair adjacent or proved apart


def test_plot_draws_geometry_and_obstacles(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    out = tmp_path / "panda.png"
    assert main(["plot", "panda", "--q", "qr", "--sphere", "0.45 0 0.5 0.1", "-o", str(out)]) == 0
    text = capsys.readouterr().out
    assert out.stat().st_size > 10_000 and "in collision (red)" in text
    assert main(["plot", "panda", "--q", "qr", "-o", str(out)]) == 0
    assert "collision-free" in capsys.readouterr().out
    fig = symkin.load("panda").plot(
        symkin.load("panda").qr, env=symkin.Environment(boxes=(symkin.Box((0, 0, -1), (1, 1, 0.1)),))
    )
    assert len(fig.axes[0].lines) > 12 + 20  # the box's 12 edges and the shapes' wireframes


ARM_URDF = """<robot name="arm2">
  <link name="base"><collision><geometry><sphere radius="0.08"/></geometry></collision></link>
  <link name="upper"><collision><origin xyz="0.2 0 0" rpy="0 1.5707963267948966 0"/>
    <geometry><cylinder radius="0.04" length="0.3"/></geometry></collision></link>
  <link name="fore"><collision><origin xyz="0.2 0 0"/><geometry><box size="0.4 0.06 0.06"/></geometry>
    </collision></link>
  <joint name="shoulder" type="revolute"><parent link="base"/><child link="upper"/><origin xyz="0 0 0.1"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="elbow" type="revolute"><parent link="upper"/><child link="fore"/><origin xyz="0.4 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
</robot>"""


def test_collide_and_plot_read_a_urdfs_collision_elements(tmp_path, capsys):
    urdf = tmp_path / "arm2.urdf"
    urdf.write_text(ARM_URDF)
    assert main(["collide", str(urdf), "0", "0", "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["in_collision"] is False and data["pairs"] >= 1  # base - forearm spheres
    # the forearm folded back over the base: its box spheres reach the base sphere
    assert main(["collide", str(urdf), "0", "3.0"]) == 1
    assert "IN COLLISION" in capsys.readouterr().out
    assert main(["collide", str(urdf), "0", "0", "--sphere", "0.6 0 0.1 0.05"]) == 1  # on the forearm
    capsys.readouterr()
    with_tool = ["collide", str(urdf), "0", "0", "--tool", "tx(0.1)", "--json"]
    assert main(with_tool) == 0  # a tool keeps the shapes on their links
    assert json.loads(capsys.readouterr().out)["in_collision"] is False
    pytest.importorskip("matplotlib")
    png = tmp_path / "arm2.png"
    assert main(["plot", str(urdf), "--q", "0 3.0", "-o", str(png)]) == 0
    assert "in collision (red)" in capsys.readouterr().out and png.stat().st_size > 10_000


def test_servo_with_collision_goes_around_an_obstacle(capsys, tmp_path):
    """`symkin servo --collision --sphere ...` servos with MMC and the obstacle's dampers (the C
    step); the straight servo through the same sphere's place enters it."""
    panda = symkin.load("panda")
    kin = symkin.compile(panda, backend="c")
    T0 = kin.fkine(panda.qr)
    goal = T0[:3, 3] + (0.0, 0.4, 0.0)
    centre = T0[:3, 3] + (0.0, 0.2, 0.0)
    sphere = symkin.Environment(spheres=(symkin.Sphere(centre, 0.05),))
    pose = " ".join(map(str, [*goal, np.pi, 0.0, -np.pi / 4]))
    plain = symkin.servo(kin, panda.qr, np.r_[np.c_[T0[:3, :3], goal], [[0, 0, 0, 1]]], max_steps=500)
    shapes = len(panda.geometry.shapes)
    assert kin.distances(plain.q, sphere)[:, -shapes:].min() < 0  # straight through the sphere
    argv = ["servo", "panda", "--pose", pose, "--collision", "--sphere", " ".join(map(str, [*centre, 0.05]))]
    assert main([*argv, "--json"]) == 0
    data = json.loads(capsys.readouterr().out)
    assert data["arrived"] and data["closest_obstacle"] > 0 and data["controller_backend"] == "c"
    assert main(argv) == 0 and "closest approach to an obstacle" in capsys.readouterr().out
    if importlib.util.find_spec("matplotlib") is not None:  # the clearance panel
        png = tmp_path / "servo.png"
        assert main([*argv, "--plot", str(png)]) == 0 and png.stat().st_size > 10_000
        capsys.readouterr()
    assert main(["servo", "panda", "--pose", pose, "--sphere", "0 0 0 0.1"]) == 2
    assert "add --collision" in capsys.readouterr().err
    assert main(["servo", "panda", "--pose", pose, "--collision", "--controller", "rrmc"]) == 2
    assert "MMC" in capsys.readouterr().err
    assert main(["servo", "panda", "--pose", pose, "--collision", "--d-i", "0.01", "--d-s", "0.05"]) == 2
    assert "--d-i" in capsys.readouterr().err
