"""The live browser view of a robot, a serial chain or a tree (viser, the ``view`` extra): :func:`view`
serves it and returns a running :class:`Viewer`.

The page (:mod:`symkin.view.page`) shows the robot (links, joints, link frames, its URDF meshes),
the followed frame's axes and linear-velocity manipulability ellipsoid, the collision shapes (red
where they collide), the obstacles and the closest pair with its distance; its panel has a frame
selector (a tree's frames, a chain's end effector and link frames), a slider per joint (within the
joint limits), the named configurations, the manipulability and the live base-frame Jacobian of the
followed frame, the closest and the overlapping pairs, what to show, and a target-pose gizmo on the
followed frame whose moves are solved by ``kin.ik`` from the current configuration (a failed solve
keeps the last pose and says why). viser serves its own client from this process (no network
needed). What is drawn is computed by :mod:`symkin.view.scene` (NumPy only).
"""

from __future__ import annotations

import contextlib
import io
import socket
import threading
import time
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.pose import as_pose
from symkin.errors import MissingExtraError, ParameterError
from symkin.view.address import serve_address
from symkin.view.page import SHOW, Page
from symkin.view.scene import MeshPart, Scene, ViewState, figure_size, rotation

__all__ = ["Viewer", "view"]


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
    """A running live view of compiled kinematics ``kin``, a chain or a tree (see :func:`view`).

    ``url`` (one a browser opens), ``host``, ``port``, ``address`` (an
    :class:`~symkin.view.address.Address`, ``public`` when serving every interface); ``q`` (n,),
    ``frame`` (the followed frame) and ``state`` (:class:`~symkin.view.scene.ViewState`) as drawn;
    ``message``, the status line of the panel;
    ``notes``, what could not be drawn (meshes) and why. :meth:`set_q` moves the joints as the
    sliders do, :meth:`set_frame` follows another frame as the frame selector does,
    :meth:`set_target` moves the target gizmo as a drag does, :meth:`show` toggles parts,
    :meth:`wait` blocks, :meth:`stop` ends the server (also on leaving a ``with`` block).
    ``server`` is the viser server.
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
        frame: str | None = None,
        meshes: Sequence[MeshPart] = (),
        notes: Sequence[str] = (),
    ) -> None:
        viser = _viser()
        self.kin = kin
        self.scene = Scene(kin, env, meshes)
        self.notes = tuple(notes)
        model = kin.model
        lo, hi = model.qlim
        q0 = np.clip(model.configs.get("qr", model.configs["qz"]), lo, hi) if q is None else q
        state = self.scene.state(q0, frame)  # checks q and frame
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
        self.span = figure_size(state)
        r_max = float(state.radii.max())
        self.ellipsoid_scale = (
            ellipsoid_scale
            if ellipsoid_scale is not None
            else 0.25 * self.span / (r_max if r_max > 1e-9 else 1.0)
        )
        try:
            self.page = Page(self.server, self.scene, state, self.span, self.ellipsoid_scale, self.notes)
            self._connect()
            self._draw(state)
        except Exception:
            self.stop()
            raise

    # -- the callbacks of the page ------------------------------------------------------------------
    def _connect(self) -> None:
        page, model = self.page, self.kin.model
        page.target.on_update(self._on_target)
        for j, slider in enumerate(page.sliders):
            slider.on_update(lambda event, j=j: self._on_slider(j, event.target.value))
        if page.frame_menu is not None:
            page.frame_menu.on_update(lambda event: self._on_frame(event.target.value))
        if page.config_menu is not None:
            page.config_button.on_click(lambda _: self.set_q(model.configs[page.config_menu.value]))
        for box in page.show_boxes.values():
            box.on_update(lambda _: page.visibility())

    def _draw(self, state: ViewState) -> None:
        self.page.draw(state, self.message)

    def show(self, **parts: bool) -> None:
        """Show or hide parts of the drawing as the panel's "Show" boxes do: ``robot``,
        ``link_frames``, ``meshes``, ``velocity_ellipsoid``, ``collision_shapes``,
        ``closest_pair``, ``target_gizmo``."""
        keys = {k.replace(" ", "_"): k for k in SHOW}
        unknown = sorted(set(parts) - set(keys))
        if unknown:
            raise ParameterError(f"show() takes {', '.join(keys)}; not {', '.join(unknown)}")
        for key, on in parts.items():
            self.page.show_boxes[keys[key]].value = bool(on)

    # -- what the user does -------------------------------------------------------------------------
    def _on_slider(self, j: int, value: float) -> None:
        with self._lock:
            if self._syncing:
                return
            q = self.state.q.copy()
            q[j] = float(value)
            self.message = ""
            self._show_q(q, follow=True)

    def _on_frame(self, frame: str) -> None:
        with self._lock:
            if self._syncing or frame == self.state.frame:
                return
            self.set_frame(frame)

    def _on_target(self, event: Any) -> None:
        T = np.eye(4)
        T[:3, :3] = rotation(event.target.wxyz)
        T[:3, 3] = event.target.position
        self.set_target(T, move_gizmo=False)

    def _show_q(self, q: np.ndarray, follow: bool, frame: str | None = None) -> ViewState:
        state = self.scene.state(q, self.state.frame if frame is None else frame)
        self._draw(state)
        if follow:
            self.page.place_target(state.T_frame)
        self.state = state  # last: what is drawn, once it is
        return state

    def _set_sliders(self, q: np.ndarray) -> None:
        self._syncing = True
        try:
            for slider, v in zip(self.page.sliders, q):
                slider.value = float(v)
        finally:
            self._syncing = False

    @property
    def q(self) -> np.ndarray:
        """The joint values drawn, (n,)."""
        return self.state.q.copy()

    @property
    def frame(self) -> str:
        """The followed frame: the gizmo, the ellipsoid, the manipulability and J0 are its."""
        return self.state.frame

    def set_q(self, q: Any) -> ViewState:
        """Move to joint values ``q`` (n,) as the sliders would (clipped to the joint limits); the
        target gizmo follows the followed frame. Returns the new state."""
        lo, hi = self.kin.model.qlim
        q = np.clip(np.asarray(q, dtype=float).reshape(-1), lo, hi)
        with self._lock:
            self._set_sliders(q)
            self.message = ""
            return self._show_q(q, follow=True)

    def set_frame(self, frame: str) -> ViewState:
        """Follow ``frame`` (a name of ``scene.frames``, as the frame selector offers): the target
        gizmo moves to it, the ellipsoid, manipulability and J0 become its. Returns the new state."""
        with self._lock:
            frame = self.scene.frame_of(frame)
            menu = self.page.frame_menu
            if menu is not None and menu.value != frame:
                self._syncing = True
                try:
                    menu.value = frame
                finally:
                    self._syncing = False
            self.message = ""
            return self._show_q(self.state.q, follow=True, frame=frame)

    def set_target(self, T: Any, move_gizmo: bool = True) -> Any:
        """Solve ``kin.ik(T, frame=...)`` (4, 4) for the followed frame from the current joint
        values (a tree's joints off its path are free); on success show the solution, otherwise keep
        the last pose and say why in the panel. Returns the IKResult; PoseError for a T that is not
        SE(3) (the one pose rule), before anything moves."""
        T = as_pose(T)  # the one pose rule: PoseError before the gizmo moves
        with self._lock:
            if move_gizmo:
                self.page.place_target(T)
            frame = self.scene.frames[self.state.frame]
            if frame is None:
                res = self.kin.ik(T, q0=self.state.q)
            else:
                res = self.kin.ik(T, frame=frame, q0=self.state.q)
            if res.success:
                self._set_sliders(np.asarray(res.q, dtype=float))
                self.message = f"IK solved: {res.iterations} iterations, residual {res.residual:.1e}"
                self._show_q(np.asarray(res.q, dtype=float), follow=False)
            else:
                self.message = f"**IK failed** ({res.reason}): kept the last pose"
                self.page.status(self.state, self.message)
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
    frame: str | None = None,
    urdf: str | Path | None = None,
    meshes: str = "visual",
    notes: Sequence[str] = (),
) -> Viewer:
    """Serve a live view of ``robot`` (compiled kinematics of a chain or a tree, a
    :class:`~symkin.Robot` or :class:`~symkin.Tree`, or anything :func:`symkin.compile` takes: a
    built-in name, ETS text, a DH or URDF file) at ``http://host:port`` and return the running
    :class:`Viewer` (``port=0``: a free port; see ``viewer.url``). ``q``: the first configuration
    (default ``qr``, else ``qz``, clipped to the joint limits); ``frame``: the frame to follow first
    (default: the first of ``viewer.scene.frames``); ``env``: obstacles (an
    :class:`~symkin.Environment`); ``backend``: for a robot not compiled yet; ``ellipsoid_scale``: m
    drawn per m/s (default: the first ellipsoid's largest semi-axis a quarter of the robot's size);
    ``open_browser``: open the page in the default browser.

    ``urdf``: the URDF file the robot was read from, whose ``meshes`` ("visual", "collision" or
    "none") are drawn on its links (:func:`symkin.view.meshes.urdf_meshes`; needs trimesh for mesh
    files). What cannot be drawn is left out with a note (``viewer.notes``, also in the panel), never
    an error: the collision shapes are drawn in its place. ``notes``: more lines for the panel's Notes.

    ``host``: ``127.0.0.1`` serves this machine only; every interface only when asked for as
    exactly ``0.0.0.0`` or ``::``, with a warning (:mod:`symkin.view.address`).

    Raises MissingExtraError without viser (``pip install 'symkin[view]'``), ParameterError for a
    port outside 0..65535 or a host that is empty or means every interface in another spelling
    (``*``, ``0``, ``[::]``...), FrameError for an unknown ``frame``, OSError when host:port cannot be
    served.
    """
    _viser()
    serve_address(host)  # before compiling: a host that is refused is refused at once
    from symkin.runtime.kinematics import Kinematics

    kin = robot
    if not isinstance(kin, Kinematics):
        from symkin.runtime.load import compile as compile_robot

        kin = compile_robot(robot, backend=backend)
    parts: list[MeshPart] = []
    notes = list(notes)
    if urdf is not None:
        from symkin.view.meshes import urdf_meshes

        parts, more = urdf_meshes(urdf, kin.model, meshes)
        notes += more
    viewer = Viewer(
        kin, host=host, port=port, q=q, env=env, ellipsoid_scale=ellipsoid_scale, frame=frame,
        meshes=parts, notes=notes,
    )  # fmt: skip
    if viewer.address.public:
        warnings.warn(viewer.address.warning(viewer.port), stacklevel=2)
    if open_browser:
        import webbrowser

        with contextlib.suppress(Exception):
            webbrowser.open(viewer.url)
    return viewer
