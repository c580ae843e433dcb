"""The live view in a real headless browser (Chromium over the DevTools protocol, software WebGL):
the screenshot shows the robot where its forward kinematics put it, and a click on a joint slider
moves the joint, the drawn pose and the pixels consistently with FK; a tree loads with its meshes,
its collision spheres and its closest pair are drawn where they are, the frame selector changes the
followed frame, and no request leaves this machine."""

from __future__ import annotations

import time
from urllib.parse import urlparse

import numpy as np
import pytest

from tests.conftest import assert_close
from tests.view.browser import Browser, chromium

pytest.importorskip("viser", reason="the live view needs viser: pip install 'symkin[view]'")
pytest.importorskip("PIL", reason="reading screenshots needs Pillow (comes with matplotlib)")
if chromium() is None:
    pytest.skip("no Chromium: apt-get install chromium", allow_module_level=True)

import symkin  # noqa: E402
from symkin.geometry.urdf import geometry_from_urdf  # noqa: E402
from symkin.view import view  # noqa: E402
from symkin.view.scene import rotation  # noqa: E402

EVERYTHING = (
    "robot",
    "link_frames",
    "meshes",
    "velocity_ellipsoid",
    "collision_shapes",
    "closest_pair",
    "target_gizmo",
)


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
        points = np.vstack((state.joints, state.T_frame[:3, 3]))
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
        assert_close(moved_state.T_frame, kin.fkine(viewer.q), 1e-12, "end effector")
        assert_close(moved_state.J, kin.jacob0(viewer.q), 1e-12, "Jacobian")
        moved = browser.settled(str(tmp_path / "moved.png"))
        drawn_now = _drawn(moved, empty)
        ee_before, ee_now = _pixels(camera, np.array([state.T_frame[:3, 3], moved_state.T_frame[:3, 3]]))
        assert np.linalg.norm(ee_now - ee_before) > 40, "the end effector barely moved on screen"
        assert _near(drawn_now, _pixels(camera, moved_state.joints)).all(), (
            "joints not drawn where FK puts them"
        )
        assert _near(drawn_now, ee_now[None]).all(), "end effector not drawn where FK puts it"
        changed = _drawn(moved, first)
        assert changed[:, : int(0.7 * w)].mean() > 0.005, "the picture did not change"


def _only(viewer, browser, part: str, empty: np.ndarray, path) -> np.ndarray:
    """Where the page differs from the empty scene with only ``part`` shown (H, W) bool, and the
    screenshot (H, W, 3)."""
    viewer.show(**{k: k == part for k in EVERYTHING})
    image = browser.settled(str(path))
    return _drawn(image, empty), image


def _click_option(browser, label: str, option: str) -> None:
    """Open the panel's dropdown ``label`` and click its ``option``, as a user does."""
    box = browser.js(
        "(() => { const l = [...document.querySelectorAll('label')].find(e => e.textContent === "
        f"{label!r}); const r = document.getElementById(l.htmlFor).getBoundingClientRect(); "
        "return [r.x, r.y, r.width, r.height]; })()"
    )
    browser.click(box[0] + box[2] / 2, box[1] + box[3] / 2)
    find = (
        "(() => { const o = [...document.querySelectorAll('[role=\"option\"]')].find(e => "
        f"e.textContent.trim() === {option!r}); if (!o) return null; const r = o.getBoundingClientRect(); "
        "return [r.x, r.y, r.width, r.height]; })()"
    )
    _until(lambda: browser.js(find) is not None, what=f"the option {option!r} to show")
    x, y, w, h = browser.js(find)
    browser.click(x + w / 2, y + h / 2)


def test_a_tree_its_spheres_and_closest_pair_are_drawn_the_frame_selector_follows(browser, ytree, tmp_path):
    tree = symkin.Tree.from_urdf(ytree)
    kin = symkin.compile(tree.with_geometry(geometry_from_urdf(ytree, tree)), backend="numpy")
    env = symkin.Environment(spheres=(symkin.Sphere((0.45, 0.25, 0.55), 0.06),))
    q = np.array([0.3, 0.05, -0.4, 0.6, 0.5, -0.8])
    browser.record_network()
    with view(kin, port=0, open_browser=False, env=env, urdf=ytree, q=q, frame="head") as viewer:
        browser.open(viewer.url)
        camera = _camera(viewer)
        viewer.show(**dict.fromkeys(EVERYTHING, False))
        empty = browser.settled(str(tmp_path / "empty.png"))
        state = viewer.state
        h, w = empty.shape[:2]
        # the collision spheres, alone: drawn at their centres, bluish
        spheres = [k for k, s in enumerate(viewer.scene.shapes) if s.kind == "sphere"]
        centres = state.shape_points[[viewer.scene.shapes[k].points[0] for k in spheres]]
        drawn, image = _only(viewer, browser, "collision_shapes", empty, tmp_path / "spheres.png")
        uv = _pixels(camera, centres)
        inside = ((uv >= 0) & (uv < [w, h])).all(axis=1)
        assert inside.sum() >= len(spheres) - 2, f"spheres out of the picture: {uv[~inside]}"
        assert _near(drawn, uv[inside], r=3).all(), "a sphere is not drawn at its centre"
        px = image[np.round(uv[inside, 1]).astype(int), np.round(uv[inside, 0]).astype(int)].astype(int)
        assert (px[:, 2] > px[:, 0] + 20).all(), f"the free spheres are not blue at their centres: {px}"
        # the closest pair, alone: a green line between the witness points
        c = state.closest
        assert c is not None and c.distance > 0
        drawn, image = _only(viewer, browser, "closest_pair", empty, tmp_path / "closest_label.png")
        viewer.page.closest[3].visible = False  # its label (the distance) may cover the line
        image = browser.settled(str(tmp_path / "closest.png"))
        drawn = _drawn(image, empty)
        ends = _pixels(camera, np.array([c.a, c.b, 0.75 * c.a + 0.25 * c.b, 0.25 * c.a + 0.75 * c.b]))
        assert _near(drawn, ends, r=4).all(), f"the closest-pair line is not drawn: {ends}"
        rgb = image.astype(int)
        green = (rgb[..., 1] > rgb[..., 0] + 30) & (rgb[..., 1] > rgb[..., 2] + 30)
        assert _near(green, ends, r=4).all(), f"the closest pair is not green along its line: {ends}"
        # everything, for the eye
        viewer.show(**dict.fromkeys(EVERYTHING, True))
        before = browser.settled(str(tmp_path / "tree.png"))
        # the frame selector: pick r_hand in the page; the gizmo and J0 follow it
        assert viewer.frame == "head"
        _click_option(browser, "frame", "r_hand")
        _until(lambda: viewer.frame == "r_hand", what="the frame selector to reach the server")
        assert_close(viewer.state.T_frame, tree.fkine(viewer.q, "r_hand"), 1e-12, "r_hand pose")
        assert_close(viewer.page.target.position, viewer.state.T_frame[:3, 3], 1e-6, "gizmo at r_hand")
        assert_close(viewer.q, q, 0, "the joints did not move")
        followed = browser.settled(str(tmp_path / "r_hand.png"))
        hand = _pixels(camera, viewer.state.T_frame[None, :3, 3])
        assert _near(_drawn(followed, before), hand, r=6).all(), "nothing changed at r_hand: the gizmo"
        urls = browser.requested()
    assert any(u.startswith("ws://127.0.0.1") for u in urls), f"the page's web socket is not recorded: {urls}"
    hosts = {urlparse(u).hostname for u in urls if urlparse(u).scheme not in ("data", "blob", "about")}
    assert hosts <= {"127.0.0.1", "localhost"}, f"requests left this machine: {sorted(hosts)}"
