"""The live view's server (viser, in-process on a free port) and ``symkin view``: the pushed state
follows the sliders, the frame selector and the IK gizmo, failures keep the pose, trees are served
with their meshes and closest pair, the page is served from this process, and the command's errors
are one line."""

from __future__ import annotations

import importlib.util
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.request

import numpy as np
import pytest

import symkin
from symkin.cli.main import main
from symkin.geometry.urdf import geometry_from_urdf
from tests.conftest import assert_close

viser = pytest.importorskip("viser", reason="the live view needs viser: pip install 'symkin[view]'")

from symkin.view import view  # noqa: E402


@pytest.fixture(scope="module")
def ur5():
    return symkin.compile(symkin.load("ur5"), backend="c")


def test_the_server_serves_its_page_and_set_q_pushes_fk(ur5):
    with view(ur5, port=0, open_browser=False) as viewer:
        assert viewer.port > 0 and viewer.url == f"http://127.0.0.1:{viewer.port}"
        with urllib.request.urlopen(viewer.url, timeout=30) as r:  # the bundled client, no network
            assert r.status == 200 and b"<html" in r.read(4096).lower()
        assert_close(viewer.q, ur5.robot.configs["qr"], 0, "q")  # the default first pose
        q = np.array([0.4, -1.0, 1.2, -0.5, 0.8, 0.3])
        state = viewer.set_q(q)
        assert_close(viewer.q, q, 0, "q")
        assert_close(state.T_links, ur5.link_poses(q), 1e-12, "link frames")
        assert_close(state.T_frame, ur5.fkine(q), 1e-12, "end effector")
        assert state.m_trans == pytest.approx(float(ur5.manipulability(q, axes="trans")), rel=1e-9)
        # joint values beyond the limits are clipped, as a slider would
        lo, hi = ur5.qlim
        assert_close(viewer.set_q(hi + 1.0).q, hi, 0, "clipped")
    assert viewer.stopped
    with pytest.raises(OSError):
        urllib.request.urlopen(viewer.url, timeout=5)


def test_the_target_gizmo_drives_ik_and_a_failure_keeps_the_pose(ur5):
    with view(ur5, port=0, open_browser=False) as viewer:
        q_goal = np.array([0.2, -1.2, 1.4, -0.6, 0.9, 0.1])
        T = ur5.fkine(q_goal)
        res = viewer.set_target(T)
        assert res.success
        assert_close(ur5.fkine(viewer.q), T, 1e-6, "FK(ik(T))")
        assert "IK solved" in viewer.message
        q_solved = viewer.q
        far = T.copy()
        far[:3, 3] += [5.0, 0.0, 0.0]  # 5 m away: out of reach
        res = viewer.set_target(far)
        assert not res.success
        assert_close(viewer.q, q_solved, 0, "kept pose")
        assert "IK failed" in viewer.message
        viewer.set_q(q_goal)
        assert viewer.message == ""
        bad = T.copy()
        bad[3] = [1.0, 0.0, 0.0, 1.0]  # not SE(3): the one pose rule, before anything moves
        with pytest.raises(symkin.PoseError, match="bottom row"):
            viewer.set_target(bad)
        assert_close(viewer.q, q_goal, 0, "kept pose")


@pytest.fixture(scope="module")
def ytree_kin(ytree):
    tree = symkin.Tree.from_urdf(ytree)
    return symkin.compile(tree.with_geometry(geometry_from_urdf(ytree, tree)), backend="numpy")


def test_a_tree_follows_the_selected_frame(ytree_kin, ytree):
    tree = ytree_kin.model
    env = symkin.Environment(spheres=(symkin.Sphere((0.4, 0.0, 0.5), 0.05),))
    with view(ytree_kin, port=0, open_browser=False, env=env, urdf=ytree, frame="l_hand") as viewer:
        page = viewer.page
        assert viewer.frame == "l_hand" and page.frame_menu.value == "l_hand"
        assert len(page.sliders) == tree.n and len(page.meshes) == len(tree.link_names)
        q = tree.random_q(seed=5)
        viewer.set_q(q)
        for frame in ("r_hand", "head", "l_hand"):
            state = viewer.set_frame(frame)
            assert viewer.frame == frame and page.frame_menu.value == frame
            assert_close(state.T_frame, tree.fkine(q, frame), 1e-12, frame)
            assert_close(state.J, tree.jacob0(q, frame), 1e-12, f"J0 of {frame}")
            assert_close(page.target.position, state.T_frame[:3, 3], 1e-6, "the gizmo on the frame")
            assert f"of {frame.replace('_', chr(92) + '_')}" in page._jacobian.content
        # the gizmo drives IK of the followed frame; the joints off its path stay free
        goal = tree.random_q(seed=6)
        res = viewer.set_target(tree.fkine(goal, "l_hand"))
        assert res.success and viewer.frame == "l_hand"
        assert_close(tree.fkine(viewer.q, "l_hand"), tree.fkine(goal, "l_hand"), 1e-6, "FK(ik(T))")
        with pytest.raises(symkin.FrameError, match="r_hand"):
            viewer.set_frame("no_hand")
        # the closest pair: its line joins the witness points, its distance is in the panel
        c = viewer.state.closest
        line, a, b, label = page.closest
        assert_close(np.asarray(line.points)[0], np.array([c.a, c.b]), 1e-6, "closest-pair line")
        assert_close(a.position, c.a, 1e-6, "witness a")
        assert_close(b.position, c.b, 1e-6, "witness b")
        assert f"{1000 * c.distance:.2f} mm" in page._collision.content
        assert label.text == f"{1000 * c.distance:.1f} mm"


def test_overlapping_pairs_are_red_and_listed(ytree_kin):
    tree = ytree_kin.model
    env = symkin.Environment(spheres=(symkin.Sphere((0.0, 0.0, 0.3), 0.1),))  # inside the torso
    with view(ytree_kin, port=0, open_browser=False, env=env, q=tree.qz) as viewer:
        state, page = viewer.state, viewer.page
        assert state.closest.distance < 0 and state.obstacles_hit.all()
        assert "pairs in collision" in page._status.content
        assert "pairs overlap" in page._collision.content
        red = [tuple(h.color) for h in page.shapes if tuple(h.color) == (214, 39, 40)]
        assert len(red) == int(state.colliding.sum()) > 0
        assert tuple(page.obstacles[0].color) == (214, 39, 40)
        assert tuple(np.asarray(page.closest[0].colors)[0, 0]) == (214, 39, 40)


def test_bad_ports_and_busy_ports_are_errors(ur5):
    with pytest.raises(symkin.ParameterError, match="0..65535"):
        view(ur5, port=70000, open_browser=False)
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        s.listen()
        busy = s.getsockname()[1]
        with pytest.raises(OSError, match=f"127.0.0.1:{busy}: in use"):
            view(ur5, port=busy, open_browser=False)


def _ipv6() -> bool:
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
    except OSError:
        return False
    return True


@pytest.mark.parametrize(
    "host, public",
    [
        ("0.0.0.0", True),
        pytest.param("::", True, marks=pytest.mark.skipif(not _ipv6(), reason="no IPv6")),
        pytest.param("::1", False, marks=pytest.mark.skipif(not _ipv6(), reason="no IPv6")),
        ("localhost", False),
    ],
)
def test_the_printed_url_opens_the_page(ur5, host, public, recwarn):
    """Issue 36, item 2: ``http://::1:PORT`` and ``http://:PORT`` were printed; every interface
    (only as 0.0.0.0 or ::) comes with a warning."""
    with view(ur5, host=host, port=0, open_browser=False) as viewer, urllib.request.urlopen(viewer.url) as r:
        assert r.status == 200
    said = [str(w.message) for w in recwarn if "every interface" in str(w.message)]
    assert len(said) == (1 if public else 0), said


@pytest.mark.parametrize("host", ["", "*", "0", "[::]"])
def test_an_empty_or_wildcard_host_is_refused_before_compiling(host, monkeypatch):
    import symkin.runtime.load

    monkeypatch.setattr(symkin.runtime.load, "compile", lambda *a, **k: pytest.fail("compiled"))
    with pytest.raises(symkin.ParameterError, match="0.0.0.0"):
        view("planar3", host=host, port=0, open_browser=False)


def test_show_names_the_parts_it_knows(ur5):
    with view(ur5, port=0, open_browser=False) as viewer:
        viewer.show(robot=False, velocity_ellipsoid=False)
        with pytest.raises(symkin.ParameterError, match="velocity_ellipsoid"):
            viewer.show(ellipsoid=False)


def test_cli_serves_for_seconds_then_stops(capsys):
    assert main(["view", "planar3", "--no-browser", "--port", "0", "--seconds", "0.5"]) == 0
    out = capsys.readouterr().out
    assert "viewing planar3 at http://127.0.0.1:" in out and "0.5 s" in out


def test_cli_views_a_tree_with_obstacles_an_srdf_and_meshes(ytree, tmp_path, capsys):
    args = ["view", str(ytree), "--no-browser", "--port", "0", "--seconds", "0.3", "--backend", "numpy"]
    assert main([*args, "--follow", "r_hand"]) == 0
    out, err = capsys.readouterr()
    assert "viewing ytree at http://127.0.0.1:" in out and "6 joints, 3 frames" in out
    pairs = int(out.split("(")[2].split()[0])  # "... collision shapes (N self pairs checked), ..."
    tree = symkin.Tree.from_urdf(ytree)
    assert f"{len(geometry_from_urdf(ytree, tree).shapes)} collision shapes ({pairs} self pairs" in out
    if importlib.util.find_spec("trimesh") is not None:
        assert f"{len(tree.link_names)} meshes" in out and err == ""
    else:  # the hand's mesh file is left out, with a note
        assert f"{len(tree.link_names) - 1} meshes" in out and "needs trimesh" in err
    env = tmp_path / "env.json"
    env.write_text('{"spheres": [[0.4, 0, 0.5, 0.05]], "boxes": [[0, 0.5, 0.3, 0.1, 0.1, 0.1]]}')
    srdf = tmp_path / "ytree.srdf"  # the two arms' links never checked against each other
    srdf.write_text(
        '<robot name="ytree">'
        + "".join(
            f'<disable_collisions link1="{a}" link2="{b}" reason="Never"/>'
            for a in ("l_upper", "l_lower")
            for b in ("r_upper", "r_lower")
        )
        + "</robot>"
    )
    assert main([*args, "--env", str(env), "--srdf", str(srdf), "--meshes", "none"]) == 0
    out = capsys.readouterr().out
    after = int(out.split("(")[2].split()[0])
    shapes = {s.link for s in geometry_from_urdf(ytree, tree).shapes}
    per_link = {x: sum(s.link == x for s in geometry_from_urdf(ytree, tree).shapes) for x in shapes}
    disabled = sum(per_link[a] * per_link[b] for a in ("l_upper", "l_lower") for b in ("r_upper", "r_lower"))
    assert after == pairs - disabled > 0
    assert "2 obstacles" in out and "0 meshes" in out


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--port", "70000"], "0..65535"),
        (["--port", "http"], "0..65535"),
        (["--q", "1 2"], "3"),
        (["--seconds", "-1"], "positive"),
        (["--follow", "hand"], "no frame 'hand'"),
        (["--srdf", "x.srdf"], "planar3 has no collision geometry"),
    ],
)
def test_cli_errors_are_one_line(argv, message, capsys):
    assert main(["view", "planar3", "--no-browser", *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("symkin: error:") and message in err[0]


@pytest.mark.parametrize("host", ["", " ", "*", "0", "::0", "[::]"])
def test_cli_refuses_an_empty_or_wildcard_host(host, capsys):
    """``--host "$VAR"`` with VAR unset served every interface and printed ``http://:PORT``."""
    assert main(["view", "planar3", "--no-browser", "--port", "0", "--seconds", "0.1", "--host", host]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("symkin: error:") and "0.0.0.0" in err[0], err


def test_cli_serves_every_interface_when_asked_with_one_warning_line(capsys):
    argv = ["view", "planar3", "--no-browser", "--port", "0", "--seconds", "0.2", "--host", "0.0.0.0"]
    assert main(argv) == 0
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("symkin: warning: serving on every interface"), err
    assert "viewing planar3 at http://127.0.0.1:" in captured.out


def test_cli_without_the_extra_says_how_to_install_it(monkeypatch, capsys):
    monkeypatch.setitem(sys.modules, "viser", None)  # import viser fails, as when it is not installed
    assert main(["view", "planar3", "--no-browser", "--port", "0", "--seconds", "0.1"]) == 2
    assert capsys.readouterr().err.strip() == "symkin: error: view needs viser: pip install 'symkin[view]'"


def test_ctrl_c_stops_the_command_cleanly(tmp_path):
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    proc = subprocess.Popen(
        [sys.executable, "-m", "symkin", "view", "planar3", "--no-browser", "--port", "0"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
    )  # fmt: skip
    try:
        line = proc.stdout.readline()  # the URL: serving
        assert "viewing planar3 at http://127.0.0.1:" in line, line + proc.stderr.read()
        url = line.split(" at ")[1].split()[0]
        with urllib.request.urlopen(url, timeout=30) as r:
            assert r.status == 200
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert out.strip() == "stopped"
    assert "Traceback" not in err
