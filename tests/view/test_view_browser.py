"""The live view in a real headless browser (Chromium over the DevTools protocol, software WebGL):
the screenshot shows the robot where its forward kinematics put it, and a click on a joint slider
moves the joint, the drawn pose and the pixels consistently with FK."""

from __future__ import annotations

import time

import numpy as np
import pytest

from tests.conftest import assert_close
from tests.view.browser import Browser, chromium

pytest.importorskip("viser", reason="the live view needs viser: pip install 'symkin[view]'")
pytest.importorskip("PIL", reason="reading screenshots needs Pillow (comes with matplotlib)")
if chromium() is None:
    pytest.skip("no Chromium: apt-get install chromium", allow_module_level=True)

import symkin  # noqa: E402
from symkin.view import view  # noqa: E402
from symkin.view.scene import rotation  # noqa: E402

EVERYTHING = ("robot", "link_frames", "velocity_ellipsoid", "collision_shapes", "target_gizmo")


@pytest.fixture(scope="module")
def browser():
    b = Browser(chromium(), size=(1400, 900))
    yield b
    b.close()


def _until(condition, timeout: float = 60.0, what: str = "") -> None:
    deadline = time.monotonic() + timeout
    while not condition():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.1)


def _camera(viewer):
    """The camera of the one connected browser, once it has reported it."""
    _until(lambda: viewer.clients() == 1, what="the browser to connect")
    client = next(iter(viewer.server.get_clients().values()))
    _until(lambda: client.camera.update_timestamp != 0.0, what="the browser's camera")
    return client.camera


def _pixels(camera, points: np.ndarray) -> np.ndarray:
    """Pixel (u, v) (N, 2) of base-frame points (N, 3) through viser's camera (OpenCV axes:
    x right, y down, z forward; vertical field of view ``fov``)."""
    R, t = rotation(camera.wxyz), np.asarray(camera.position)
    p = (points - t) @ R  # camera coordinates
    assert (p[:, 2] > 0).all(), "a point behind the camera"
    f = 0.5 * camera.image_height / np.tan(0.5 * camera.fov)
    return np.c_[
        0.5 * camera.image_width + f * p[:, 0] / p[:, 2], 0.5 * camera.image_height + f * p[:, 1] / p[:, 2]
    ]


def _drawn(image: np.ndarray, empty: np.ndarray) -> np.ndarray:
    """Where ``image`` differs from the empty scene's screenshot (H, W) bool."""
    return np.abs(image.astype(int) - empty.astype(int)).max(axis=-1) > 40


def _near(mask: np.ndarray, uv: np.ndarray, r: int = 5) -> np.ndarray:
    """Per pixel (u, v): whether ``mask`` is set within r pixels of it."""
    out = []
    for u, v in np.round(uv).astype(int):
        out.append(bool(mask[max(v - r, 0) : v + r + 1, max(u - r, 0) : u + r + 1].any()))
    return np.array(out)


def test_the_page_draws_the_robot_where_fk_puts_it_and_a_slider_click_moves_it(browser, tmp_path):
    kin = symkin.compile(symkin.load("panda"), backend="c")
    with view(kin, port=0, open_browser=False) as viewer:
        browser.open(viewer.url)
        camera = _camera(viewer)
        viewer.show(**dict.fromkeys(EVERYTHING, False))
        empty = browser.settled(str(tmp_path / "empty.png"))
        viewer.show(**dict.fromkeys(EVERYTHING, True))
        first = browser.settled(str(tmp_path / "robot.png"))
        drawn = _drawn(first, empty)
        # the robot is drawn: at every joint and at the end effector, as projected from FK
        state = viewer.state
        points = np.vstack((state.joints, state.T_ee[:3, 3]))
        uv = _pixels(camera, points)
        h, w = drawn.shape
        assert ((uv >= 0) & (uv < [w, h])).all(), f"the robot is out of the picture: {uv}"
        assert _near(drawn, uv).all(), f"nothing drawn at the projected joints {uv[~_near(drawn, uv)]}"
        assert drawn[:, : int(0.7 * w)].mean() > 0.02, "too little of the scene differs from the empty one"

        # click at 90% of the first joint's slider track, in the page
        tracks = browser.js(
            "[...document.querySelectorAll('[role=\"slider\"]')].map(e => {"
            " const r = e.closest('.mantine-Slider-root').getBoundingClientRect();"
            " return [r.x, r.y, r.width, r.height]; })"
        )
        assert len(tracks) == kin.n, f"{len(tracks)} sliders for {kin.n} joints"
        x, y, width, height = tracks[0]
        q_before = viewer.q
        browser.click(x + 0.9 * width, y + height / 2)
        _until(lambda: abs(viewer.q[0] - q_before[0]) > 0.1, what="the slider click to reach the server")
        lo, hi = kin.qlim[:, 0]
        assert abs(viewer.q[0] - (lo + 0.9 * (hi - lo))) < 0.08 * (hi - lo), (viewer.q[0], lo, hi)
        assert_close(viewer.q[1:], q_before[1:], 1e-12, "the other joints")
        # what is drawn is the forward kinematics of the new joint values
        moved_state = viewer.state
        assert_close(moved_state.T_links, kin.link_poses(viewer.q), 1e-12, "link frames")
        assert_close(moved_state.T_ee, kin.fkine(viewer.q), 1e-12, "end effector")
        assert_close(moved_state.J, kin.jacob0(viewer.q), 1e-12, "Jacobian")
        moved = browser.settled(str(tmp_path / "moved.png"))
        drawn_now = _drawn(moved, empty)
        ee_before, ee_now = _pixels(camera, np.array([state.T_ee[:3, 3], moved_state.T_ee[:3, 3]]))
        assert np.linalg.norm(ee_now - ee_before) > 40, "the end effector barely moved on screen"
        assert _near(drawn_now, _pixels(camera, moved_state.joints)).all(), (
            "joints not drawn where FK puts them"
        )
        assert _near(drawn_now, ee_now[None]).all(), "end effector not drawn where FK puts it"
        changed = _drawn(moved, first)
        assert changed[:, : int(0.7 * w)].mean() > 0.005, "the picture did not change"
