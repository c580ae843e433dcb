"""The live browser view of a serial chain (viser, the ``view`` extra): :func:`view` serves it and
returns a running :class:`Viewer`.

The page shows the robot (links, joints, link frames), the linear-velocity manipulability ellipsoid
at the end effector, the collision shapes (red where they collide) and obstacles; its panel has a
slider per joint (within the joint limits), the named configurations, what to show, the
manipulability, the live base-frame Jacobian, and a target-pose gizmo whose moves are solved by
``kin.ik`` from the current configuration (a failed solve keeps the last pose and says why).
viser serves its own client from this process (no network needed). Callbacks compute with the
compiled kinematics only (:mod:`symkin.view.scene`).
"""

from __future__ import annotations

import contextlib
import io
import socket
import threading
import time
import warnings
from typing import Any

import numpy as np

from symkin.core.pose import as_pose
from symkin.errors import MissingExtraError, ParameterError
from symkin.view.address import serve_address
from symkin.view.scene import Scene, ViewState, capsule_mesh, quaternion, quaternion_z_to, rotation

__all__ = ["Viewer", "view"]

_ORANGE, _GREY, _BLUE, _RED, _PURPLE = (
    (255, 127, 14),
    (70, 70, 70),
    (31, 119, 180),
    (214, 39, 40),
    (148, 103, 189),
)
_ROWS = ("vx", "vy", "vz", "wx", "wy", "wz")
_SHOW = ("robot", "link frames", "velocity ellipsoid", "collision shapes", "target gizmo")


def _viser() -> Any:
    try:
        import viser
    except ImportError:
        raise MissingExtraError("the live view needs viser: pip install 'symkin[view]'") from None
    return viser


def _check_address(host: str, port: int) -> None:
    """ParameterError for a port outside 0..65535, OSError naming host and port when it cannot be bound
    (in use, or a host that is not this machine's)."""
    if isinstance(port, bool) or not isinstance(port, (int, np.integer)) or not 0 <= int(port) <= 65535:
        raise ParameterError(f"port must be an integer in 0..65535 (0: any free port), got {port!r}")
    if int(port) == 0:
        return
    try:
        infos = socket.getaddrinfo(host, int(port), type=socket.SOCK_STREAM)
        family, _, _, _, address = infos[0]
        with socket.socket(family, socket.SOCK_STREAM) as probe:
            probe.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            probe.bind(address)
    except OSError as exc:
        reason = "in use" if getattr(exc, "errno", None) == 98 else (exc.strerror or str(exc))
        raise OSError(f"cannot serve on {host}:{port}: {reason} (--port 0 picks a free port)") from None


class Viewer:
    """A running live view of compiled kinematics ``kin`` (see :func:`view`).

    ``url`` (one a browser opens), ``host``, ``port``, ``address`` (an
    :class:`~symkin.view.address.Address`, ``public`` when serving every interface); ``q`` (n,) and
    ``state`` (:class:`~symkin.view.scene.ViewState`) as drawn; ``message``, the status line of the
    panel. :meth:`set_q` moves the joints as the sliders
    do, :meth:`set_target` moves the target gizmo as a drag does, :meth:`wait` blocks, :meth:`stop`
    ends the server (also on leaving a ``with`` block). ``server`` is the viser server.
    """

    def __init__(
        self,
        kin: Any,
        *,
        host: str = "127.0.0.1",
        port: int = 8080,
        q: Any = None,
        env: Any = None,
        ellipsoid_scale: float | None = None,
    ) -> None:
        viser = _viser()
        self.kin = kin
        self.scene = Scene(kin, env)
        robot = kin.robot
        q0 = robot.configs.get("qr", robot.configs["qz"]) if q is None else q
        state = self.scene.state(q0)  # checks q
        address = serve_address(host)  # refuses an empty host and wildcards not asked for explicitly
        host = address.host
        _check_address(host, port)
        with contextlib.redirect_stdout(io.StringIO()):  # viser prints a banner; we print the URL
            self.server = viser.ViserServer(host=host, port=int(port), verbose=False)
        self.host, self.port = host, int(self.server.get_port())
        if int(port) and self.port != int(port):
            self.stop()
            raise OSError(f"cannot serve on {host}:{port}: in use (--port 0 picks a free port)")
        self.url, self.address = address.url(self.port), address
        self._lock = threading.RLock()
        self._syncing = False
        self._stopped = threading.Event()
        self.message = ""
        self.state: ViewState = state
        chain = state.chain
        self.span = max(float(np.ptp(chain, axis=0).max()), 0.1)
        r_max = float(state.radii.max())
        self.ellipsoid_scale = (
            ellipsoid_scale
            if ellipsoid_scale is not None
            else 0.25 * self.span / (r_max if r_max > 1e-9 else 1.0)
        )
        try:
            self._build(robot, state)
        except Exception:
            self.stop()
            raise

    # -- the scene and the panel -------------------------------------------------------------------
    def _build(self, robot: Any, state: ViewState) -> None:
        s, gui, span = self.server.scene, self.server.gui, self.span
        gui.configure_theme(control_width="large", show_share_button=False)
        centre = 0.5 * (state.chain.min(axis=0) + state.chain.max(axis=0))
        self.server.initial_camera.look_at = centre
        self.server.initial_camera.position = centre + 0.9 * span * np.array([1.0, -1.2, 0.6])
        s.add_grid("/grid", width=2 * span, height=2 * span, cell_size=span / 10, section_size=span / 2)
        self._base = s.add_frame("/base", axes_length=0.15 * span, axes_radius=0.008 * span)
        self._links = [
            s.add_frame(f"/links/{k}", axes_length=0.08 * span, axes_radius=0.005 * span)
            for k in range(self.scene.n)
        ]
        self._ee = s.add_frame("/ee", axes_length=0.15 * span, axes_radius=0.008 * span)
        self._chain = s.add_line_segments(
            "/chain", self._segments(state), colors=_GREY, thickness=0.012 * span
        )
        self._joints = [
            s.add_icosphere(f"/joints/{k}", radius=0.025 * span, color=_ORANGE, subdivisions=2)
            for k in range(self.scene.n)
        ]
        self._ellipsoid = s.add_icosphere(
            "/ellipsoid", radius=1.0, color=_PURPLE, opacity=0.4, subdivisions=3, cast_shadow=False
        )
        self._shapes = []
        for k, shape in enumerate(self.scene.shapes):
            if shape.kind == "sphere":
                h = s.add_icosphere(
                    f"/shapes/{k}", radius=shape.radius, color=_BLUE, opacity=0.3, subdivisions=2
                )
            else:
                V, F = capsule_mesh(shape.radius, shape.length)
                h = s.add_mesh_simple(f"/shapes/{k}", V, F, color=_BLUE, opacity=0.3)
            self._shapes.append(h)
        self._obstacles(self.scene.env)
        self._target = s.add_transform_controls("/target", scale=0.3 * span, line_width=2.5)
        self._place_target(state.T_ee)
        self._target.on_update(self._on_target)

        self._status = gui.add_markdown("")
        with gui.add_folder("Joints"):
            self._sliders = []
            lo, hi = robot.qlim
            for j, name in enumerate(robot.joint_names):
                revolute = robot.ets.joints[j].is_revolute
                slider = gui.add_slider(
                    f"{name} ({'rad' if revolute else 'm'})", min=float(lo[j]), max=float(hi[j]),
                    step=1e-3 if revolute else 5e-4, initial_value=float(np.clip(state.q[j], lo[j], hi[j])),
                )  # fmt: skip
                slider.on_update(lambda event, j=j: self._on_slider(j, event.target.value))
                self._sliders.append(slider)
            names = sorted(robot.configs)
            if names:
                self._config = gui.add_dropdown("configuration", names, initial_value=names[0])
                gui.add_button("go to configuration").on_click(
                    lambda _: self.set_q(robot.configs[self._config.value])
                )
        with gui.add_folder("Manipulability and J0"):
            self._numbers = gui.add_markdown("")
            self._jacobian = gui.add_markdown("")
        with gui.add_folder("Show", expand_by_default=False):
            self._show = {key: gui.add_checkbox(key, initial_value=True) for key in _SHOW}
            for box in self._show.values():
                box.on_update(lambda _: self._visibility())
            if not self.scene.shapes:
                self._show["collision shapes"].visible = False
        self._draw(state)

    def _obstacles(self, env: Any) -> None:
        if env is None:
            return
        s = self.server.scene
        for k, o in enumerate(env.spheres):
            s.add_icosphere(
                f"/obstacles/sphere{k}", radius=o.radius, color=(150, 150, 150), position=o.center
            )
        for k, o in enumerate(env.capsules):
            a, b = np.array(o.a), np.array(o.b)
            V, F = capsule_mesh(o.radius, float(np.linalg.norm(b - a)))
            s.add_mesh_simple(
                f"/obstacles/capsule{k}",
                V,
                F,
                color=(150, 150, 150),
                position=(a + b) / 2,
                wxyz=quaternion_z_to(b - a),
            )
        for k, o in enumerate(env.boxes):
            s.add_box(
                f"/obstacles/box{k}", color=(150, 150, 150), dimensions=2 * np.array(o.half_extents),
                position=o.center, wxyz=quaternion(o.R),
            )  # fmt: skip

    @staticmethod
    def _segments(state: ViewState) -> np.ndarray:
        c = state.chain
        return np.stack((c[:-1], c[1:]), axis=1).astype(np.float32)  # (M, 2, 3)

    def _place_target(self, T: np.ndarray) -> None:
        self._target.position = T[:3, 3]
        self._target.wxyz = quaternion(T[:3, :3])

    def _draw(self, state: ViewState) -> None:
        """Push ``state`` to the browsers (one batch of messages)."""
        with self.server.atomic():
            for k, h in enumerate(self._links):
                h.position, h.wxyz = state.T_links[k, :3, 3], quaternion(state.T_links[k, :3, :3])
            self._ee.position, self._ee.wxyz = state.T_ee[:3, 3], quaternion(state.T_ee[:3, :3])
            self._chain.points = self._segments(state)
            for k, h in enumerate(self._joints):
                h.position = state.joints[k]
            radii = np.maximum(state.radii * self.ellipsoid_scale, 1e-4 * self.span)
            self._ellipsoid.position = state.T_ee[:3, 3]
            self._ellipsoid.wxyz = quaternion(state.axes)
            self._ellipsoid.scale = tuple(float(r) for r in radii)
            for k, h in enumerate(self._shapes):
                h.position, h.wxyz = self.scene.shape_pose(state, k)
                h.color = _RED if state.colliding[k] else _BLUE
            self._numbers.content = self._numbers_text(state)
            self._jacobian.content = self._jacobian_text(state)
            self._status.content = self._status_text(state)

    def _numbers_text(self, state: ViewState) -> str:
        p = state.T_ee[:3, 3]
        return (
            f"**manipulability** m = {state.m:.4g}, translational m_v = {state.m_trans:.4g}  \n"
            f"ellipsoid semi-axes {', '.join(f'{r:.3g}' for r in state.radii[::-1])} m/s "
            f"(drawn at {self.ellipsoid_scale:.3g} m per m/s)  \n"
            f"end effector at ({p[0]:.4f}, {p[1]:.4f}, {p[2]:.4f}) m"
        )

    @staticmethod
    def _jacobian_text(state: ViewState) -> str:
        rows = [f"{r}  " + " ".join(f"{x:5.2f}" for x in row) for r, row in zip(_ROWS, state.J)]
        return "**J0** (base frame)\n```\n" + "\n".join(rows) + "\n```"

    def _status_text(self, state: ViewState) -> str:
        lines = [self.message] if self.message else []
        if self.scene.shapes:
            hits = int(state.colliding.sum())
            lines.append(f"**{hits} shapes in collision (red)**" if hits else "collision-free")
        return "  \n".join(lines)

    def _visibility(self) -> None:
        show = {k: bool(v.value) for k, v in self._show.items()}
        self._chain.visible = self._ee.visible = self._base.visible = show["robot"]
        for h in self._joints:
            h.visible = show["robot"]
        for h in self._links:
            h.visible = show["link frames"]
        self._ellipsoid.visible = show["velocity ellipsoid"]
        for h in self._shapes:
            h.visible = show["collision shapes"]
        self._target.visible = show["target gizmo"]

    def show(self, **parts: bool) -> None:
        """Show or hide parts of the drawing as the panel's "Show" boxes do: ``robot``,
        ``link_frames``, ``velocity_ellipsoid``, ``collision_shapes``, ``target_gizmo``."""
        keys = {k.replace(" ", "_"): k for k in _SHOW}
        unknown = sorted(set(parts) - set(keys))
        if unknown:
            raise ParameterError(f"show() takes {', '.join(keys)}; not {', '.join(unknown)}")
        for key, on in parts.items():
            self._show[keys[key]].value = bool(on)

    # -- what the user does -------------------------------------------------------------------------
    def _on_slider(self, j: int, value: float) -> None:
        with self._lock:
            if self._syncing:
                return
            q = self.state.q.copy()
            q[j] = float(value)
            self.message = ""
            self._show_q(q, follow=True)

    def _on_target(self, event: Any) -> None:
        T = np.eye(4)
        T[:3, :3] = rotation(event.target.wxyz)
        T[:3, 3] = event.target.position
        self.set_target(T, move_gizmo=False)

    def _show_q(self, q: np.ndarray, follow: bool) -> ViewState:
        state = self.scene.state(q)
        self.state = state
        self._draw(state)
        if follow:
            self._place_target(state.T_ee)
        return state

    @property
    def q(self) -> np.ndarray:
        """The joint values drawn, (n,)."""
        return self.state.q.copy()

    def set_q(self, q: Any) -> ViewState:
        """Move to joint values ``q`` (n,) as the sliders would (clipped to the joint limits); the
        target gizmo follows the end effector. Returns the new state."""
        lo, hi = self.kin.robot.qlim
        q = np.clip(np.asarray(q, dtype=float).reshape(-1), lo, hi)
        with self._lock:
            self._syncing = True
            try:
                for slider, v in zip(self._sliders, q):
                    slider.value = float(v)
            finally:
                self._syncing = False
            self.message = ""
            return self._show_q(q, follow=True)

    def set_target(self, T: Any, move_gizmo: bool = True) -> Any:
        """Solve ``kin.ik(T)`` (4, 4) from the current joint values; on success show the solution,
        otherwise keep the last pose and say why in the panel. Returns the IKResult; PoseError for a
        T that is not SE(3) (the one pose rule), before anything moves."""
        T = as_pose(T)  # the one pose rule: PoseError before the gizmo moves
        with self._lock:
            if move_gizmo:
                self._place_target(T)
            res = self.kin.ik(T, q0=self.state.q)
            if res.success:
                self._syncing = True
                try:
                    for slider, v in zip(self._sliders, res.q):
                        slider.value = float(v)
                finally:
                    self._syncing = False
                self.message = f"IK solved: {res.iterations} iterations, residual {res.residual:.1e}"
                self._show_q(np.asarray(res.q, dtype=float), follow=False)
            else:
                self.message = f"**IK failed** ({res.reason}): kept the last pose"
                self._status.content = self._status_text(self.state)
        return res

    # -- running ------------------------------------------------------------------------------------
    def clients(self) -> int:
        """How many browsers are connected."""
        return len(self.server.get_clients())

    def wait(self, seconds: float | None = None) -> None:
        """Block until :meth:`stop` (from another thread) or ``seconds`` have passed (None: until
        stopped, or Ctrl-C, which raises KeyboardInterrupt here)."""
        end = None if seconds is None else time.monotonic() + seconds
        while not self._stopped.is_set():
            left = 0.2 if end is None else min(0.2, end - time.monotonic())
            if left <= 0:
                return
            self._stopped.wait(left)

    def stop(self) -> None:
        """Stop the server (idempotent)."""
        if self._stopped.is_set():
            return
        self._stopped.set()
        with contextlib.redirect_stdout(io.StringIO()):
            self.server.stop()

    @property
    def stopped(self) -> bool:
        return self._stopped.is_set()

    def __enter__(self) -> Viewer:
        return self

    def __exit__(self, *exc: Any) -> None:
        self.stop()

    def __repr__(self) -> str:
        return f"<Viewer {self.kin.name} at {self.url}{' (stopped)' if self.stopped else ''}>"


def view(
    robot: Any,
    port: int = 8080,
    host: str = "127.0.0.1",
    *,
    open_browser: bool = True,
    q: Any = None,
    env: Any = None,
    backend: str = "c",
    ellipsoid_scale: float | None = None,
) -> Viewer:
    """Serve a live view of ``robot`` (compiled kinematics of a chain, a :class:`~symkin.Robot`, or
    anything :func:`symkin.compile` takes: a built-in name, ETS text, a DH or URDF file) at
    ``http://host:port`` and return the running :class:`Viewer` (``port=0``: a free port; see
    ``viewer.url``). ``q``: the first configuration (default ``qr``, else ``qz``); ``env``: obstacles
    (an :class:`~symkin.Environment`); ``backend``: for a robot not compiled yet;
    ``ellipsoid_scale``: m drawn per m/s (default: the first ellipsoid's largest semi-axis a quarter
    of the robot's size); ``open_browser``: open the page in the default browser.

    ``host``: ``127.0.0.1`` serves this machine only; every interface only when asked for as
    exactly ``0.0.0.0`` or ``::``, with a warning (:mod:`symkin.view.address`).

    Raises MissingExtraError without viser (``pip install 'symkin[view]'``), ParameterError for a
    port outside 0..65535, a tree, or a host that is empty or means every interface in another
    spelling (``*``, ``0``, ``[::]``...), OSError when host:port cannot be served.
    """
    _viser()
    serve_address(host)  # before compiling: a host that is refused is refused at once
    from symkin.runtime.kinematics import Kinematics

    kin = robot
    if not isinstance(kin, Kinematics):
        from symkin.runtime.load import compile as compile_robot

        kin = compile_robot(robot, backend=backend)
    viewer = Viewer(kin, host=host, port=port, q=q, env=env, ellipsoid_scale=ellipsoid_scale)
    if viewer.address.public:
        warnings.warn(viewer.address.warning(viewer.port), stacklevel=2)
    if open_browser:
        import webbrowser

        with contextlib.suppress(Exception):
            webbrowser.open(viewer.url)
    return viewer
