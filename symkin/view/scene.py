"""What the live view draws of a serial chain at one configuration, from its compiled kinematics
(NumPy only: no sympy, no viser; the browser side is :mod:`symkin.view.server`).

:meth:`Scene.state` makes one :class:`ViewState`: the link frames (``kin.link_poses``), the
end-effector pose, the stick figure through the origin of every ETS frame (the compiled link frames
times the constant transforms between joints, so a DH offset shows as the L-shape it is), the
base-frame Jacobian, the manipulability ``sqrt(det(J J^T))`` (eq 52 of Haviland and Corke,
Manipulator Differential Kinematics, Part 1) of all six rows and of the linear-velocity rows, the
linear-velocity ellipsoid ``{J_v qd : |qd| <= 1}`` (semi-axes along the eigenvectors of
``J_v J_v^T``, lengths the square roots of its eigenvalues) and, when the robot has collision
geometry, the base-frame points of its shapes and which shapes collide.
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

from symkin.errors import ParameterError, SymkinError
from symkin.model.differential import manipulability_one
from symkin.model.kinematics import const_matrix

__all__ = ["Scene", "ViewState", "ShapeView", "quaternion", "quaternion_z_to", "capsule_mesh"]


class ShapeView(NamedTuple):
    """One collision shape as drawn: ``kind`` "sphere" or "capsule", ``radius``, ``length`` (capsule
    segment, 0 for a sphere) and ``points`` (indices into ``kin.collision_points(q)``)."""

    kind: str
    radius: float
    length: float
    points: tuple[int, ...]


class ViewState(NamedTuple):
    """The drawn quantities at one configuration (base frame, m and rad)."""

    q: np.ndarray  # (n,)
    T_links: np.ndarray  # (n, 4, 4) link frame k: right after joint k
    T_ee: np.ndarray  # (4, 4)
    chain: np.ndarray  # (M + 1, 3) origins of the base and of every ETS frame, the last at the ee
    joints: np.ndarray  # (n, 3) origins of the joints (the frame before each joint)
    J: np.ndarray  # (6, n) base-frame Jacobian, rows (v, omega)
    m: float  # sqrt(det(J J^T))
    m_trans: float  # sqrt(det(J_v J_v^T))
    radii: np.ndarray  # (3,) ellipsoid semi-axes, m/s per unit |qd|, ascending
    axes: np.ndarray  # (3, 3) their directions as columns, a rotation (det +1)
    shape_points: np.ndarray  # (P, 3) sphere centres and capsule ends, in shape order
    colliding: np.ndarray  # (S,) bool: shape s overlaps another active shape or an obstacle


class Scene:
    """The view of compiled kinematics ``kin`` of a serial chain, with obstacles ``env`` (an
    :class:`~symkin.Environment`, or None) checked against the robot's collision geometry."""

    def __init__(self, kin: Any, env: Any = None) -> None:
        try:
            self.robot = kin.model.chain()
        except SymkinError:  # several frames, or a mimic joint on the path
            raise ParameterError(
                f"the live view draws a serial chain; {kin.name} is a tree: pick one frame "
                "(ROBOT.urdf:FRAME or --end-link)"
            ) from None
        self.kin = kin
        self.n = int(kin.n)
        self.env = env if env is not None and len(env) else None
        self._prefix, self._after = _chain_offsets(self.robot)
        geometry = self.robot.geometry
        self.shapes: tuple[ShapeView, ...] = ()
        self._pairs: list[tuple[str, int, int]] = []
        if geometry is not None and len(geometry):
            shapes, p = [], 0
            for s in geometry.shapes:
                ends = s.points
                length = float(np.linalg.norm(np.subtract(ends[-1], ends[0])))
                kind = "sphere" if len(ends) == 1 else "capsule"
                shapes.append(ShapeView(kind, float(s.radius), length, tuple(range(p, p + len(ends)))))
                p += len(ends)
            self.shapes = tuple(shapes)
            self._pairs = kin.collision_pairs(self.env)

    def state(self, q: Any) -> ViewState:
        """Every drawn quantity at joint values ``q`` (n,)."""
        q = np.array(q, dtype=float).reshape(-1)
        if q.shape != (self.n,) or not np.isfinite(q).all():
            raise ParameterError(f"{self.robot.name} needs {self.n} finite joint values, got {q.tolist()}")
        kin = self.kin
        T_links = np.asarray(kin.link_poses(q))  # (n, 4, 4)
        T_ee = np.asarray(kin.fkine(q))
        J = np.asarray(kin.jacob0(q))  # (6, n)
        points = list(self._prefix)
        joints = [self._prefix[-1]]
        for k in range(self.n):
            points.append(T_links[k, :3, 3])
            for c in self._after[k]:
                points.append(T_links[k, :3, :3] @ c + T_links[k, :3, 3])
            if k + 1 < self.n:
                joints.append(points[-1])
        Jv = J[:3]
        w, V = np.linalg.eigh(Jv @ Jv.T)
        if np.linalg.det(V) < 0:
            V[:, 0] = -V[:, 0]
        S = len(self.shapes)
        shape_points, colliding = np.zeros((0, 3)), np.zeros(S, dtype=bool)
        if S:
            shape_points = np.asarray(kin.collision_points(q))
            d = np.asarray(kin.distances(q, self.env))
            for (kind, i, j), dk in zip(self._pairs, d):
                if dk < 0:
                    colliding[i] = True
                    if kind == "self":
                        colliding[j] = True
        return ViewState(
            q, T_links, T_ee, np.array(points), np.array(joints), J, manipulability_one(J),
            manipulability_one(Jv), np.sqrt(np.maximum(w, 0.0)), V, shape_points, colliding,
        )  # fmt: skip

    def span(self, q: Any) -> float:
        """The size of the drawing at ``q`` (m): the largest extent of the stick figure, at least 0.1."""
        chain = self.state(q).chain
        return max(float(np.ptp(chain, axis=0).max()), 0.1)

    def shape_pose(self, state: ViewState, s: int) -> tuple[np.ndarray, np.ndarray]:
        """Centre (3,) and orientation (w, x, y, z) of shape ``s`` at ``state``; a capsule's axis is
        its local z."""
        shape = self.shapes[s]
        ends = state.shape_points[list(shape.points)]
        if shape.kind == "sphere":
            return ends[0], np.array([1.0, 0.0, 0.0, 0.0])
        return ends.mean(axis=0), quaternion_z_to(ends[1] - ends[0])


def _chain_offsets(robot: Any) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """The constant part of the stick figure: the origins (3,) of the frames before the first joint
    (base frame, the base's origin first), and per joint k the origins (m_k, 3) of the frames after
    it up to the next joint, in link frame k."""
    T = np.eye(4)
    prefix = [T[:3, 3].copy()]
    after: list[list[np.ndarray]] = []
    for e in robot.ets:
        if e.is_joint:
            after.append([])
            T = np.eye(4)
            continue
        T = T @ const_matrix(e.axis, e.const)
        (after[-1] if after else prefix).append(T[:3, 3].copy())
    return prefix, [np.array(a).reshape(-1, 3) for a in after]


def quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z), w >= 0, of a rotation matrix (3, 3) (Shepperd's method)."""
    R = np.asarray(R, dtype=float)
    tr = float(np.trace(R))
    i = int(np.argmax([tr, R[0, 0], R[1, 1], R[2, 2]]))
    if i == 0:
        r = 2.0 * math.sqrt(1.0 + tr)
        q = [r / 4, (R[2, 1] - R[1, 2]) / r, (R[0, 2] - R[2, 0]) / r, (R[1, 0] - R[0, 1]) / r]
    elif i == 1:
        r = 2.0 * math.sqrt(max(1.0 + R[0, 0] - R[1, 1] - R[2, 2], 1e-300))
        q = [(R[2, 1] - R[1, 2]) / r, r / 4, (R[0, 1] + R[1, 0]) / r, (R[0, 2] + R[2, 0]) / r]
    elif i == 2:
        r = 2.0 * math.sqrt(max(1.0 + R[1, 1] - R[0, 0] - R[2, 2], 1e-300))
        q = [(R[0, 2] - R[2, 0]) / r, (R[0, 1] + R[1, 0]) / r, r / 4, (R[1, 2] + R[2, 1]) / r]
    else:
        r = 2.0 * math.sqrt(max(1.0 + R[2, 2] - R[0, 0] - R[1, 1], 1e-300))
        q = [(R[1, 0] - R[0, 1]) / r, (R[0, 2] + R[2, 0]) / r, (R[1, 2] + R[2, 1]) / r, r / 4]
    out = np.array(q) / np.linalg.norm(q)
    return -out if out[0] < 0 else out


def rotation(wxyz: Any) -> np.ndarray:
    """Rotation matrix (3, 3) of a quaternion (w, x, y, z) (normalised first)."""
    w, x, y, z = np.asarray(wxyz, dtype=float) / np.linalg.norm(wxyz)
    return np.array(
        [
            [1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
            [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
            [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)],
        ]
    )


def quaternion_z_to(d: np.ndarray) -> np.ndarray:
    """The shortest rotation (w, x, y, z) taking the z axis to direction ``d`` (3,) (identity for d = 0)."""
    norm = float(np.linalg.norm(d))
    if norm < 1e-12:
        return np.array([1.0, 0.0, 0.0, 0.0])
    u = np.asarray(d, dtype=float) / norm
    if u[2] < -1.0 + 1e-12:  # z to -z: half a turn about x
        return np.array([0.0, 1.0, 0.0, 0.0])
    q = np.array([1.0 + u[2], -u[1], u[0], 0.0])  # (1 + z.u, z x u)
    return q / np.linalg.norm(q)


def capsule_mesh(
    radius: float, length: float, segments: int = 16, rings: int = 6
) -> tuple[np.ndarray, np.ndarray]:
    """A capsule along z, centred at the origin: vertices (V, 3) float32 and triangles (F, 3) uint32.
    Two hemispheres of ``rings`` latitude bands each, at z = +-length/2, joined by a cylinder."""
    h = length / 2.0
    lat = np.concatenate(
        (np.linspace(0.0, np.pi / 2, rings + 1), np.linspace(np.pi / 2, np.pi, rings + 1))
    )  # the equator twice: top hemisphere's edge at +h, bottom's at -h
    shift = np.where(np.arange(lat.size) <= rings, h, -h)
    lon = np.linspace(0.0, 2 * np.pi, segments, endpoint=False)
    ring_r, ring_z = radius * np.sin(lat), radius * np.cos(lat) + shift
    V = np.stack(
        (
            np.outer(ring_r, np.cos(lon)),
            np.outer(ring_r, np.sin(lon)),
            np.repeat(ring_z[:, None], segments, 1),
        ),
        axis=-1,
    ).reshape(-1, 3)
    faces = []
    for i in range(lat.size - 1):
        for j in range(segments):
            a, b = i * segments + j, i * segments + (j + 1) % segments
            c, d = a + segments, b + segments
            faces += [(a, c, b), (b, c, d)]
    return V.astype(np.float32), np.array(faces, dtype=np.uint32)
