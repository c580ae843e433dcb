"""A stick-figure plot of a robot at one configuration (matplotlib, the ``plot`` extra).

The links are drawn through the origin of every frame of the ETS in turn (base, after each
elementary transform, end effector), so a DH offset shows as the L-shape it is. Each joint is a
marker (a circle for revolute, a square for prismatic) with a short segment along its axis; the
base, each link frame and the end effector get x/y/z triads in red/green/blue. Optionally the
manipulability ellipsoid of the end effector's linear velocity, ``{v = J_v qd : |qd| <= 1}``
(semi-axes along the eigenvectors of ``J_v J_v^T`` with lengths the square roots of its
eigenvalues, Yoshikawa's ellipsoid as in Haviland and Corke, Manipulator Differential Kinematics,
Part 1, 2023, section on manipulability), drawn at a stated scale (m per m/s).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import MissingExtraError
from symkin.model.kinematics import const_matrix, et_matrix

__all__ = ["plot_robot", "chain_points"]

_COLOURS = ("#d62728", "#2ca02c", "#1f77b4")  # x, y, z


def chain_points(
    robot: Any, q: np.ndarray
) -> tuple[np.ndarray, list[tuple[np.ndarray, bool]], list[np.ndarray]]:
    """(origins (M+1, 3) of the base and every ETS frame; (pose before the joint, revolute) per joint
    in chain order; the link frame poses right after each joint, chain order)."""
    T = np.eye(4)
    origins = [T[:3, 3].copy()]
    joints: list[tuple[np.ndarray, bool]] = []
    links: list[np.ndarray] = []
    for e in robot.ets:
        if e.is_joint:
            joints.append((T.copy(), e.is_revolute))
            M = et_matrix(e.axis, e.sign * float(q[e.joint]))
        else:
            M = const_matrix(e.axis, e.const)
        T = T @ M
        if e.is_joint:
            links.append(T.copy())
        origins.append(T[:3, 3].copy())
    return np.array(origins), joints, links


def _triad(ax: Any, T: np.ndarray, length: float, width: float = 1.5) -> None:
    for i, colour in enumerate(_COLOURS):
        end = T[:3, 3] + length * T[:3, i]
        ax.plot(*zip(T[:3, 3], end), color=colour, linewidth=width)


def _shape(ax: Any, ends: list[np.ndarray], radius: float, colour: str) -> np.ndarray:
    """A sphere (one end) or capsule (two) as a wireframe; returns points bounding it."""
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 13), np.linspace(0, np.pi, 7))
    unit = np.stack((np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)), axis=-1)
    out = []
    for c in ends:
        pts = c + radius * unit
        ax.plot_wireframe(pts[..., 0], pts[..., 1], pts[..., 2], color=colour, linewidth=0.4, alpha=0.5)
        out.append(pts.reshape(-1, 3))
    if len(ends) == 2:
        ax.plot(*np.array(ends).T, color=colour, linewidth=max(1.0, 200 * radius), alpha=0.35)
    return np.concatenate(out)


def _box(ax: Any, box: Any) -> np.ndarray:
    """A box's 12 edges; returns its corners."""
    signs = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float)
    corners = np.array(box.center) + (signs * np.array(box.half_extents)) @ box.R.T
    for i in range(8):
        for j in range(i + 1, 8):
            if np.sum(signs[i] != signs[j]) == 1:
                ax.plot(*corners[[i, j]].T, color="0.45", linewidth=1.0)
    return corners


def plot_robot(
    robot: Any,
    q: Any = None,
    *,
    ax: Any = None,
    frames: bool = True,
    ellipsoid: bool = False,
    ellipsoid_scale: float | None = None,
    path: str | Path | None = None,
    title: str | None = None,
    elev: float = 25.0,
    azim: float = -60.0,
    geometry: bool = True,
    env: Any = None,
    highlight: Any = (),
) -> Any:
    """Draw ``robot`` at ``q`` ((n,), default ``qz``) and return the matplotlib Figure.

    ``ax``: a 3-D axes to draw into (default: a new figure); ``frames``: draw each link frame (the
    base and end-effector frames are always drawn); ``ellipsoid``: add the linear-velocity
    manipulability ellipsoid at the end effector, scaled by ``ellipsoid_scale`` m per m/s (default:
    its largest semi-axis a quarter of the drawing's size; the title states the scale); ``path``:
    save a PNG there (150 dpi); ``geometry``: draw the robot's collision shapes (blue, wireframe;
    the shapes whose indices are in ``highlight`` red); ``env``: obstacles to draw (an
    :class:`~symkin.model.geometry.Environment`, grey). Raises MissingExtraError without matplotlib.
    """
    try:
        from matplotlib.figure import Figure
    except ImportError:
        raise MissingExtraError("robot plots need matplotlib: pip install 'symkin[plot]'") from None
    from symkin.core.arrays import as_config

    q = robot.configs["qz"] if q is None else as_config(q, robot.n, robot.name)  # one configuration
    origins, joints, links = chain_points(robot, q)
    Tee = robot.fkine(q)
    span = float(np.ptp(origins, axis=0).max()) if len(origins) > 1 else 1.0
    span = span if span > 1e-9 else 1.0
    if ax is None:
        fig = Figure(figsize=(6.4, 5.6))
        ax = fig.add_subplot(projection="3d")
    else:
        fig = ax.figure
    ax.plot(*origins.T, color="0.25", linewidth=3, solid_capstyle="round", zorder=1)
    for (T, revolute), e in zip(joints, (e for e in robot.ets if e.is_joint)):
        ax.scatter(
            *T[:3, 3], s=60, marker="o" if revolute else "s", color="#ff7f0e", depthshade=False, zorder=3
        )
        axis = T[:3, e.axis.index] * e.sign
        seg = np.array([T[:3, 3] - 0.06 * span * axis, T[:3, 3] + 0.06 * span * axis])
        ax.plot(*seg.T, color="#ff7f0e", linewidth=2.5)
    _triad(ax, np.eye(4), 0.15 * span, 2.5)
    if frames:
        for T in links:
            _triad(ax, T, 0.08 * span)
    _triad(ax, Tee, 0.15 * span, 2.5)
    heading = title or f"{robot.name} at q = {np.array2string(q, precision=3, suppress_small=True)}"
    points = [origins]
    if ellipsoid:
        Jv = robot.jacob0(q)[:3]
        w, V = np.linalg.eigh(Jv @ Jv.T)
        radii = np.sqrt(np.maximum(w, 0.0))
        scale = ellipsoid_scale if ellipsoid_scale is not None else 0.25 * span / max(radii.max(), 1e-12)
        u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 36), np.linspace(0, np.pi, 18))
        sphere = np.stack((np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v)), axis=-1)
        pts = Tee[:3, 3] + scale * (sphere * radii) @ V.T
        ax.plot_surface(pts[..., 0], pts[..., 1], pts[..., 2], color="#9467bd", alpha=0.25, linewidth=0)
        points.append(pts.reshape(-1, 3))
        heading += (
            f"\nvelocity ellipsoid at {scale:.3g} m per m/s, m = {robot.manipulability(q, 'trans'):.3g}"
        )
    if geometry and robot.geometry is not None:
        frames_of = {"base": np.eye(4), "ee": Tee, **{f"link{k + 1}": T for k, T in enumerate(links)}}
        marked = set(int(i) for i in highlight)
        for i, shape in enumerate(robot.geometry.shapes):
            T = frames_of[shape.link]
            ends = [T[:3, :3] @ np.array(p) + T[:3, 3] for p in shape.points]
            points.append(_shape(ax, ends, shape.radius, "#d62728" if i in marked else "#1f77b4"))
    if env is not None:
        for s in (*env.spheres, *env.capsules):
            points.append(_shape(ax, [np.array(p) for p in s.points], s.radius, "0.45"))
        for b in env.boxes:
            points.append(_box(ax, b))
    allp = np.concatenate(points)
    centre = (allp.max(axis=0) + allp.min(axis=0)) / 2
    half = max(float(np.ptp(allp, axis=0).max()) / 2, 0.1 * span) * 1.1
    for axis, c in zip("xyz", centre):
        getattr(ax, f"set_{axis}lim")(c - half, c + half)
        getattr(ax, f"set_{axis}label")(f"{axis} (m)")
    ax.set_box_aspect((1, 1, 1))
    ax.view_init(elev=elev, azim=azim)
    ax.set_title(heading, fontsize=9)
    if path is not None:
        fig.savefig(path, dpi=150)
    return fig
