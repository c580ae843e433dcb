"""What the live view draws of a robot, a serial chain or a tree, at one configuration (NumPy only:
no sympy, no viser; the browser side is :mod:`symkin.view.server`).

The model is read as a tree (a chain through :meth:`symkin.Tree.from_robot`, links ``base``,
``link1``.., ``ee``), so chains and trees are drawn by one walk. :meth:`Scene.state` makes one
:class:`ViewState` for joint values ``q`` and a followed *frame* (a tree's declared frames; a
chain's end effector ``ee`` and its link frames ``link1``..): the frame of every link a joint moves
(a chain's link frames), the stick figure through the origin of every ETS frame (from the model's walk,
:meth:`symkin.Tree.segment_poses`, so a DH offset shows as the L-shape it is), the poses of the
meshes' links; from the compiled kinematics, the frame's pose and base-frame Jacobian, the
manipulability ``sqrt(det(J J^T))`` (eq 52 of Haviland and Corke, Manipulator Differential
Kinematics, Part 1, 2023) of all six rows and of the linear-velocity rows, the linear-velocity
ellipsoid ``{J_v qd : |qd| <= 1}`` (semi-axes along the eigenvectors of ``J_v J_v^T``, lengths the
square roots of its eigenvalues) and, when the robot has collision geometry, the base-frame points
of its shapes, which shapes and obstacles collide, and the closest active pair with its signed
distance and witness points (:func:`symkin.geometry.reference.witnesses`).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np

from symkin.errors import FrameError, ParameterError
from symkin.geometry.pairs import as_environment, as_tree, layout_of
from symkin.geometry.reference import witnesses
from symkin.model.differential import manipulability_one
from symkin.model.kinematics import const_matrix
from symkin.model.orientation import quaternion, quaternion_matrix

__all__ = [
    "Scene",
    "ViewState",
    "ShapeView",
    "Closest",
    "MeshPart",
    "frame_choices",
    "figure_size",
    "quaternion",
    "quaternion_z_to",
    "rotation",
    "capsule_mesh",
]


class ShapeView(NamedTuple):
    """One collision shape as drawn: ``kind`` "sphere" or "capsule", ``radius``, ``length`` (capsule
    segment, 0 for a sphere), ``points`` (indices into ``kin.collision_points(q)``), ``link``."""

    kind: str
    radius: float
    length: float
    points: tuple[int, ...]
    link: str


class MeshPart(NamedTuple):
    """A mesh fixed to model link ``link``: ``vertices`` (V, 3) float32 in that link's frame (m),
    ``faces`` (F, 3) uint32, ``color`` (r, g, b) 0-255, ``name`` (where it came from)."""

    link: str
    vertices: np.ndarray
    faces: np.ndarray
    color: tuple[int, int, int]
    name: str


class Closest(NamedTuple):
    """The active pair at the smallest signed distance: ``label`` ("self", i, j) or (obstacle kind,
    shape i, obstacle k), as ``kin.collision_pairs``; ``distance`` (m, negative: overlap);
    ``a``, ``b`` (3,) its witness points (``a - b = distance * n``, see
    :func:`symkin.geometry.reference.witnesses`); ``text``, the pair in words."""

    label: tuple[str, int, int]
    distance: float
    a: np.ndarray
    b: np.ndarray
    text: str


class ViewState(NamedTuple):
    """The drawn quantities at one configuration and frame (base frame, m and rad)."""

    q: np.ndarray  # (n,)
    frame: str  # the followed frame (a key of Scene.frames)
    T_frame: np.ndarray  # (4, 4) its pose
    T_links: np.ndarray  # (K, 4, 4) the frame of the link each joint slot moves (a chain: link frame k)
    joints: np.ndarray  # (K, 3) the origins of the joints (the frame just before each)
    stick: np.ndarray  # (M, 2, 3) one line per ETS element: its frame's origin before and after
    J: np.ndarray  # (6, n) the frame's base-frame Jacobian, rows (v, omega)
    m: float  # sqrt(det(J J^T))
    m_trans: float  # sqrt(det(J_v J_v^T))
    radii: np.ndarray  # (3,) ellipsoid semi-axes, m/s per unit |qd|, ascending
    axes: np.ndarray  # (3, 3) their directions as columns, a rotation (det +1)
    shape_points: np.ndarray  # (P, 3) sphere centres and capsule ends, in shape order
    colliding: np.ndarray  # (S,) bool: shape s overlaps another active shape or an obstacle
    obstacles_hit: np.ndarray  # (O,) bool: obstacle o (spheres, capsules, boxes) overlaps a shape
    pairs_hit: tuple[tuple[float, str], ...]  # (distance, pair in words) of overlapping pairs, deepest first
    closest: Closest | None  # None: no active pair
    mesh_poses: np.ndarray  # (G, 4, 4) the pose of each mesh's link


def frame_choices(kin: Any) -> dict[str, Any]:
    """The frames the view can follow, name -> the ``frame=`` argument of ``kin``: its frames
    (``kin.frames``; the only one as None: a chain's end effector ``ee``) and a chain's link frame k
    as ``link<k+1>`` (k), the link names of the chain read as a tree."""
    frames = tuple(kin.frames)
    choices = {name: None if len(frames) == 1 else name for name in frames}
    if getattr(kin, "link_poses", None) is not None:  # a chain's link frames
        choices.update({f"link{k + 1}": k for k in range(int(kin.n))})
    return choices


class _Segment(NamedTuple):
    """The constant part of one segment's stick figure: origins (a, 3) of the frames before its
    joint in its parent link's frame, and (b, 3) of the frames from its joint on in its own link's
    frame (the last one its origin)."""

    before: np.ndarray
    after: np.ndarray


def _segment_figure(ets: Sequence[Any]) -> _Segment:
    T = np.eye(4)
    before: list[np.ndarray] = []
    after_consts: list[np.ndarray] = []
    joint = False
    for e in ets:
        if e.is_joint:
            joint = True
            continue
        M = const_matrix(e.axis, e.const)
        if joint:
            after_consts.append(M)
        else:
            T = T @ M
            before.append(T[:3, 3].copy())
    if not joint:
        return _Segment(np.array(before).reshape(-1, 3), np.zeros((0, 3)))
    # the frames from the joint on, seen from the link frame at the end: inv(D_i), D_i the
    # product of the constants after frame i
    D, after = np.eye(4), [np.zeros(3)]
    for M in reversed(after_consts):
        D = M @ D
        after.append(np.linalg.inv(D)[:3, 3])
    return _Segment(np.array(before).reshape(-1, 3), np.array(after[::-1]))


class Scene:
    """The view of compiled kinematics ``kin`` (a chain or a tree), with obstacles ``env`` (an
    :class:`~symkin.Environment`, shapes, or None) checked against the robot's collision geometry,
    and ``meshes`` (:class:`MeshPart` s, see :mod:`symkin.view.meshes`) moved with their links.

    ``frames``: name -> ``frame=`` argument (:func:`frame_choices`), the first the default;
    ``shapes``: the collision shapes as drawn; ``obstacles``: the environment's shapes in the order
    of :attr:`ViewState.obstacles_hit`."""

    def __init__(self, kin: Any, env: Any = None, meshes: Sequence[MeshPart] = ()) -> None:
        self.kin = kin
        self.model = kin.model
        self.tree = as_tree(self.model)
        self.n = int(kin.n)
        self.frames = frame_choices(kin)
        env = as_environment(env)
        self.env = env if len(env) else None
        self.obstacles: tuple[Any, ...] = (*env.spheres, *env.capsules, *env.boxes)
        self._figure = [_segment_figure(seg.ets) for seg in self.tree.segments]
        self._slotted = [k for k, seg in enumerate(self.tree.segments) if seg.slot is not None]
        segment_of = {self.tree.base_link: -1, **{s.link: k for k, s in enumerate(self.tree.segments)}}
        self.meshes = tuple(meshes)
        unknown = sorted({m.link for m in self.meshes} - set(segment_of))
        if unknown:
            raise ParameterError(f"meshes on links {unknown} that {self.model.name} does not have")
        self._mesh_segment = np.array([segment_of[m.link] for m in self.meshes], dtype=int)
        self.shapes: tuple[ShapeView, ...] = ()
        self._pairs: list[tuple[str, int, int]] = []
        geometry = self.model.geometry
        if geometry is not None and len(geometry):
            self.layout = layout_of(self.model)
            shapes = []
            for s, first in zip(self.layout.shapes, self.layout.point_index):
                ends = s.points
                length = float(np.linalg.norm(np.subtract(ends[-1], ends[0])))
                kind = "sphere" if len(ends) == 1 else "capsule"
                points = tuple(range(first, first + len(ends)))
                shapes.append(ShapeView(kind, float(s.radius), length, points, s.link))
            self.shapes = tuple(shapes)
            self._pairs = kin.collision_pairs(self.env)
            kinds = ("sphere", "capsule", "box")
            counts = np.cumsum([0, len(env.spheres), len(env.capsules)])
            self._obstacle_of = {kind: int(c) for kind, c in zip(kinds, counts)}

    def summary(self) -> str:
        """What is drawn, in words: joints, frames, collision shapes and pairs, obstacles, meshes."""
        self_pairs = sum(1 for label in self._pairs if label[0] == "self")
        k = len(self.obstacles)
        obstacles = f", {k} obstacle{'s' if k > 1 else ''}" if k else ""
        return (
            f"{self.n} joints, {len(self.frames)} frames, {len(self.shapes)} collision shapes "
            f"({self_pairs} self pairs checked{obstacles}), {len(self.meshes)} meshes"
        )

    def frame_of(self, frame: str | None) -> str:
        """``frame`` (a name of :attr:`frames`; None: the first) checked: FrameError naming them."""
        if frame is None:
            return next(iter(self.frames))
        if frame not in self.frames:
            raise FrameError(
                f"{self.model.name} has no frame {frame!r} to follow; its frames: {list(self.frames)}"
            )
        return frame

    def state(self, q: Any, frame: str | None = None) -> ViewState:
        """Every drawn quantity at joint values ``q`` (n,), following ``frame`` (a name of
        :attr:`frames`; default the first)."""
        q = np.array(q, dtype=float).reshape(-1)
        if q.shape != (self.n,) or not np.isfinite(q).all():
            raise ParameterError(f"{self.model.name} needs {self.n} finite joint values, got {q.tolist()}")
        frame = self.frame_of(frame)
        kin = self.kin
        T, J = kin.fkine_jacob0(q, self.frames[frame])
        T, J = np.asarray(T), np.asarray(J)
        L, P = self.tree.segment_poses(q)
        Jv = J[:3]
        w, V = np.linalg.eigh(Jv @ Jv.T)
        if np.linalg.det(V) < 0:
            V[:, 0] = -V[:, 0]
        mesh_poses = np.concatenate((np.eye(4)[None], L))[self._mesh_segment + 1]
        return ViewState(
            q, frame, T, L[self._slotted], P[self._slotted, :3, 3], self._stick(L),
            J, manipulability_one(J), manipulability_one(Jv), np.sqrt(np.maximum(w, 0.0)), V,
            *self._collisions(q), mesh_poses,
        )  # fmt: skip

    def _stick(self, L: np.ndarray) -> np.ndarray:
        """(M, 2, 3): per segment, its parent's origin, then the origins of its ETS frames."""
        lines = []
        for k, seg in enumerate(self.tree.segments):
            parent = np.eye(4) if seg.parent < 0 else L[seg.parent]
            fig = self._figure[k]
            pts = [
                parent[:3, 3],
                *(fig.before @ parent[:3, :3].T + parent[:3, 3]),
                *(fig.after @ L[k, :3, :3].T + L[k, :3, 3]),
            ]
            lines += [(a, b) for a, b in zip(pts[:-1], pts[1:])]
        return np.array(lines, dtype=float).reshape(-1, 2, 3)

    def _collisions(self, q: np.ndarray) -> tuple:
        """shape points, colliding shapes, obstacles hit, overlapping pairs, closest pair."""
        S, O = len(self.shapes), len(self.obstacles)
        colliding, hit = np.zeros(S, dtype=bool), np.zeros(O, dtype=bool)
        if not S:
            return np.zeros((0, 3)), colliding, hit, (), None
        kin = self.kin
        X = np.asarray(kin.collision_points(q))
        d = np.asarray(kin.distances(q, self.env))
        pairs_hit = []
        for k in np.flatnonzero(d < 0)[np.argsort(d[d < 0], kind="stable")]:
            kind, i, j = self._pairs[k]
            colliding[i] = True
            if kind == "self":
                colliding[j] = True
            else:
                hit[self._obstacle_of[kind] + j] = True
            pairs_hit.append((float(d[k]), self.layout.describe(self._pairs[k])))
        closest = None
        if len(d):
            k = int(np.argmin(d))
            label = self._pairs[k]
            _, a, b = witnesses(self.model, X, [label], self.env)
            closest = Closest(label, float(d[k]), a[0], b[0], self.layout.describe(label))
        return X, colliding, hit, tuple(pairs_hit), closest

    def shape_pose(self, state: ViewState, s: int) -> tuple[np.ndarray, np.ndarray]:
        """Centre (3,) and orientation (w, x, y, z) of shape ``s`` at ``state``; a capsule's axis is
        its local z."""
        shape = self.shapes[s]
        ends = state.shape_points[list(shape.points)]
        if shape.kind == "sphere":
            return ends[0], np.array([1.0, 0.0, 0.0, 0.0])
        return ends.mean(axis=0), quaternion_z_to(ends[1] - ends[0])


def figure_size(state: ViewState) -> float:
    """The size of the drawing at ``state`` (m): the largest extent of the stick figure, at least 0.1."""
    points = state.stick.reshape(-1, 3)
    return max(float(np.ptp(points, axis=0).max()), 0.1) if len(points) else 0.1


def rotation(wxyz: Any) -> np.ndarray:
    """Rotation matrix (3, 3) of a quaternion (w, x, y, z) (normalised first)."""
    return quaternion_matrix(np.asarray(wxyz, dtype=float) / np.linalg.norm(wxyz))


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
    Two hemispheres of ``rings`` latitude bands each, at z = +-length/2, joined by a cylinder
    (``length`` 0: a sphere)."""
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
