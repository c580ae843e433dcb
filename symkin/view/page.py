"""The live view's page (viser): the 3-D scene's nodes and the panel's controls, made once, and
:meth:`Page.draw`, which pushes one :class:`~symkin.view.scene.ViewState` to the browsers.

The scene: the base frame, the frame of every link a joint moves, the stick figure through every ETS
frame, the joints, the meshes (:mod:`symkin.view.meshes`), the followed frame's axes and
linear-velocity ellipsoid, the collision shapes (blue, red where they overlap), the obstacles (grey,
red where they overlap), the closest pair's witness points joined by a line (green, red when they
overlap) with its distance, and the target gizmo. The panel: the status line, the frame selector,
a slider per joint, the named configurations, the manipulability and J0 of the followed frame,
the closest pair and the overlapping pairs, what to show, and notes on what could not be drawn.
The callbacks are :class:`symkin.view.server.Viewer`'s.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.view.scene import Scene, ViewState, capsule_mesh, quaternion, quaternion_z_to

__all__ = ["Page", "SHOW"]

_ORANGE, _GREY, _BLUE, _RED, _PURPLE, _GREEN, _STONE = (
    (255, 127, 14),
    (70, 70, 70),
    (31, 119, 180),
    (214, 39, 40),
    (148, 103, 189),
    (20, 170, 60),
    (150, 150, 150),
)
_ROWS = ("vx", "vy", "vz", "wx", "wy", "wz")
SHOW = (
    "robot",
    "link frames",
    "meshes",
    "velocity ellipsoid",
    "collision shapes",
    "closest pair",
    "target gizmo",
)
_PAIRS_LISTED = 8  # overlapping pairs named in the panel


class Page:
    """The nodes and controls of one viewer's page on ``server`` (a viser server) for ``scene``,
    first drawn at ``state``; ``span`` (m) sizes the markers, ``ellipsoid_scale`` is m drawn per
    m/s, ``notes`` are shown in the panel."""

    def __init__(
        self, server: Any, scene: Scene, state: ViewState, span: float, ellipsoid_scale: float,
        notes: Sequence[str] = (),
    ) -> None:  # fmt: skip
        self.server, self.scene, self.span, self.ellipsoid_scale = server, scene, span, ellipsoid_scale
        self._scene_nodes(state)
        self._panel(state, notes)

    # -- the 3-D scene ------------------------------------------------------------------------------
    def _scene_nodes(self, state: ViewState) -> None:
        s, span, scene = self.server.scene, self.span, self.scene
        self.server.gui.configure_theme(control_width="large", show_share_button=False)
        points = state.stick.reshape(-1, 3)
        centre = 0.5 * (points.min(axis=0) + points.max(axis=0))
        self.server.initial_camera.look_at = centre
        self.server.initial_camera.position = centre + 0.9 * span * np.array([1.0, -1.2, 0.6])
        s.add_grid(
            "/grid", width=2 * span, height=2 * span, cell_size=span / 10, section_size=span / 2,
            position=(0.0, 0.0, min(0.0, float(points[:, 2].min()))),  # under a humanoid's feet
        )  # fmt: skip
        self.base = s.add_frame("/base", axes_length=0.15 * span, axes_radius=0.008 * span)
        self.links = [
            s.add_frame(f"/links/{k}", axes_length=0.08 * span, axes_radius=0.005 * span)
            for k in range(len(state.T_links))
        ]
        self.frame = s.add_frame("/frame", axes_length=0.15 * span, axes_radius=0.008 * span)
        self.stick = s.add_line_segments(
            "/stick", state.stick.astype(np.float32), colors=_GREY, thickness=0.012 * span
        )
        self.joints = [
            s.add_icosphere(f"/joints/{k}", radius=0.025 * span, color=_ORANGE, subdivisions=2)
            for k in range(len(state.joints))
        ]
        self.meshes = [
            s.add_mesh_simple(f"/meshes/{k}", m.vertices, m.faces, color=m.color)
            for k, m in enumerate(scene.meshes)
        ]
        self.ellipsoid = s.add_icosphere(
            "/ellipsoid", radius=1.0, color=_PURPLE, opacity=0.4, subdivisions=3, cast_shadow=False
        )
        self.shapes = []
        for k, shape in enumerate(scene.shapes):
            if shape.kind == "sphere":
                h = s.add_icosphere(
                    f"/shapes/{k}", radius=shape.radius, color=_BLUE, opacity=0.3, subdivisions=2
                )
            else:
                V, F = capsule_mesh(shape.radius, shape.length)
                h = s.add_mesh_simple(f"/shapes/{k}", V, F, color=_BLUE, opacity=0.3)
            self.shapes.append(h)
        self.obstacles = [self._obstacle(k, o) for k, o in enumerate(scene.obstacles)]
        self.closest = None
        if state.closest is not None:
            c = state.closest
            self.closest = (
                s.add_line_segments(
                    "/closest/line", np.array([[c.a, c.b]], dtype=np.float32), colors=_GREEN,
                    thickness=0.006 * span,
                ),
                s.add_icosphere("/closest/a", radius=0.012 * span, color=_GREEN, subdivisions=2),
                s.add_icosphere("/closest/b", radius=0.012 * span, color=_GREEN, subdivisions=2),
                s.add_label("/closest/label", "", font_screen_scale=0.8),
            )  # fmt: skip
        self.target = s.add_transform_controls("/target", scale=0.3 * span, line_width=2.5)
        self.place_target(state.T_frame)

    def _obstacle(self, k: int, o: Any) -> Any:
        s = self.server.scene
        if hasattr(o, "half_extents"):
            return s.add_box(
                f"/obstacles/{k}", color=_STONE, dimensions=2 * np.array(o.half_extents),
                position=o.center, wxyz=quaternion(o.R),
            )  # fmt: skip
        if hasattr(o, "center"):
            return s.add_icosphere(f"/obstacles/{k}", radius=o.radius, color=_STONE, position=o.center)
        a, b = np.array(o.a), np.array(o.b)
        V, F = capsule_mesh(o.radius, float(np.linalg.norm(b - a)))
        return s.add_mesh_simple(
            f"/obstacles/{k}", V, F, color=_STONE, position=(a + b) / 2, wxyz=quaternion_z_to(b - a)
        )

    def place_target(self, T: np.ndarray) -> None:
        self.target.position = T[:3, 3]
        self.target.wxyz = quaternion(T[:3, :3])

    # -- the panel ----------------------------------------------------------------------------------
    def _panel(self, state: ViewState, notes: Sequence[str]) -> None:
        gui, scene, model = self.server.gui, self.scene, self.scene.model
        self._status = gui.add_markdown("")
        names = list(scene.frames)
        self.frame_menu = None
        if len(names) > 1:
            self.frame_menu = gui.add_dropdown("frame", names, initial_value=state.frame)
        with gui.add_folder("Joints"):
            self.sliders = []
            lo, hi = model.qlim
            revolute = np.asarray(model.revolute, dtype=bool)
            for j, name in enumerate(model.joint_names):
                self.sliders.append(
                    gui.add_slider(
                        f"{name} ({'rad' if revolute[j] else 'm'})", min=float(lo[j]), max=float(hi[j]),
                        step=1e-3 if revolute[j] else 5e-4,
                        initial_value=float(np.clip(state.q[j], lo[j], hi[j])),
                    )
                )  # fmt: skip
            configs = sorted(model.configs)
            self.config_menu = self.config_button = None
            if configs:
                self.config_menu = gui.add_dropdown("configuration", configs, initial_value=configs[0])
                self.config_button = gui.add_button("go to configuration")
        with gui.add_folder("Manipulability and J0"):
            self._numbers = gui.add_markdown("")
            self._jacobian = gui.add_markdown("")
        self._collision = None
        if scene.shapes:
            with gui.add_folder("Collision"):
                self._collision = gui.add_markdown("")
        with gui.add_folder("Show", expand_by_default=False):
            self.show_boxes = {key: gui.add_checkbox(key, initial_value=True) for key in SHOW}
            absent = {
                "meshes": not scene.meshes,
                "collision shapes": not scene.shapes,
                "closest pair": self.closest is None,
            }
            for key, gone in absent.items():
                self.show_boxes[key].visible = not gone
        if notes:
            with gui.add_folder("Notes", expand_by_default=False):
                shown = list(notes[:6]) + ([f"... and {len(notes) - 6} more"] if len(notes) > 6 else [])
                gui.add_markdown("  \n".join(_md(x) for x in shown))

    def visibility(self) -> None:
        """Show the parts whose "Show" box is ticked."""
        show = {k: bool(v.value) for k, v in self.show_boxes.items()}
        self.stick.visible = self.base.visible = self.frame.visible = show["robot"]
        for h in self.joints:
            h.visible = show["robot"]
        for h in self.links:
            h.visible = show["link frames"]
        for h in self.meshes:
            h.visible = show["meshes"]
        self.ellipsoid.visible = show["velocity ellipsoid"]
        for h in self.shapes:
            h.visible = show["collision shapes"]
        for h in self.closest or ():
            h.visible = show["closest pair"]
        self.target.visible = show["target gizmo"]

    # -- one state ----------------------------------------------------------------------------------
    def draw(self, state: ViewState, message: str) -> None:
        """Push ``state`` to the browsers (one batch of messages); ``message`` heads the status."""
        with self.server.atomic():
            for k, h in enumerate(self.links):
                h.position, h.wxyz = state.T_links[k, :3, 3], quaternion(state.T_links[k, :3, :3])
            self.frame.position, self.frame.wxyz = state.T_frame[:3, 3], quaternion(state.T_frame[:3, :3])
            self.stick.points = state.stick.astype(np.float32)
            for k, h in enumerate(self.joints):
                h.position = state.joints[k]
            for k, h in enumerate(self.meshes):
                h.position, h.wxyz = state.mesh_poses[k, :3, 3], quaternion(state.mesh_poses[k, :3, :3])
            radii = np.maximum(state.radii * self.ellipsoid_scale, 1e-4 * self.span)
            self.ellipsoid.position = state.T_frame[:3, 3]
            self.ellipsoid.wxyz = quaternion(state.axes)
            self.ellipsoid.scale = tuple(float(r) for r in radii)
            for k, h in enumerate(self.shapes):
                h.position, h.wxyz = self.scene.shape_pose(state, k)
                h.color = _RED if state.colliding[k] else _BLUE
            for k, h in enumerate(self.obstacles):
                h.color = _RED if state.obstacles_hit[k] else _STONE
            if self.closest is not None and state.closest is not None:
                c, (line, a, b, label) = state.closest, self.closest
                colour = _RED if c.distance < 0 else _GREEN
                line.points = np.array([[c.a, c.b]], dtype=np.float32)
                line.colors = np.tile(np.array(colour, dtype=np.uint8), (1, 2, 1))
                a.position, b.position = c.a, c.b
                a.color = b.color = colour
                label.position = 0.5 * (c.a + c.b)
                label.text = f"{1000 * c.distance:.1f} mm"
            self._numbers.content = self.numbers_text(state)
            self._jacobian.content = jacobian_text(state)
            if self._collision is not None:
                self._collision.content = collision_text(state)
            self.status(state, message)

    def status(self, state: ViewState, message: str) -> None:
        lines = [message] if message else []
        if self.scene.shapes:
            hits = len(state.pairs_hit)
            lines.append(f"**{hits} pairs in collision (red)**" if hits else "collision-free")
        self._status.content = "  \n".join(lines)

    def numbers_text(self, state: ViewState) -> str:
        p = state.T_frame[:3, 3]
        return (
            f"frame **{_md(state.frame)}** at ({p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}) m  \n"
            f"**manipulability** m = {state.m:.4g}, translational m_v = {state.m_trans:.4g}  \n"
            f"ellipsoid semi-axes {', '.join(f'{r:.3g}' for r in state.radii[::-1])} m/s "
            f"(drawn at {self.ellipsoid_scale:.3g} m per m/s)"
        )


def jacobian_text(state: ViewState) -> str:
    """J0 of the followed frame as a Markdown code block, one row per line."""
    rows = [f"{r}  " + " ".join(f"{x:5.2f}" for x in row) for r, row in zip(_ROWS, state.J)]
    return f"**J0** of {_md(state.frame)} (base frame)\n```\n" + "\n".join(rows) + "\n```"


def collision_text(state: ViewState) -> str:
    """The closest pair, its signed distance and the overlapping pairs, as Markdown."""
    c = state.closest
    if c is None:
        return "no active pair (every pair is adjacent or disabled)"
    lines = [f"**closest pair** {_md(c.text)}: **{1000 * c.distance:.2f} mm**"]
    if state.pairs_hit:
        lines.append(f"**{len(state.pairs_hit)} pairs overlap** (deepest first):")
        lines += [f"{1000 * d:.2f} mm  {_md(t)}" for d, t in state.pairs_hit[:_PAIRS_LISTED]]
        if len(state.pairs_hit) > _PAIRS_LISTED:
            lines.append(f"... and {len(state.pairs_hit) - _PAIRS_LISTED} more")
    return "  \n".join(lines)


def _md(text: str) -> str:
    """Text shown as itself in Markdown (names from a URDF may hold *, _ or <)."""
    out = str(text)
    for ch in "\\`*_{}[]<>()#+-.!|":
        out = out.replace(ch, "\\" + ch)
    return out
