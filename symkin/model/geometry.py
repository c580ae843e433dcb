"""Collision geometry as data: spheres and capsules fixed to a robot's links, and an environment of
spheres, capsules and boxes in the base frame (leaf module: NumPy only).

A shape names the link it moves with. On a serial chain (:class:`symkin.Robot`) the links are
``"base"``, ``"link1"`` ... ``"link<n>"`` (``link<k+1>`` moves with the k-th joint along the chain,
so its frame is link frame k, ``link_poses(q)[k]``) and ``"ee"`` (the end-effector frame, fixed to
the last link); an integer k is accepted for link frame k. On a :class:`symkin.Tree` the links are
the tree's link names (URDF ``<link>`` names). Coordinates are in that link's frame, in metres.

Which pairs are checked is decided from the model's structure when the geometry is attached (see
:func:`symkin.geometry.active_pairs`): never two shapes on one rigid body (links joined by fixed
joints), never adjacent bodies (joined by one joint), never the pairs listed in ``disabled``
(e.g. SRDF ``disable_collisions``).
"""

from __future__ import annotations

import dataclasses
import hashlib
import operator
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from symkin.core.arrays import finite_number
from symkin.errors import GeometryError

__all__ = [
    "Sphere",
    "Capsule",
    "Box",
    "Geometry",
    "Environment",
    "Shape",
    "link_name",
    "as_index",
    "check_geometry",
    "rename_links",
]

Vec3 = tuple[float, float, float]


def _vec3(value: Any, what: str) -> Vec3:
    try:
        a = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise GeometryError(f"{what} must be 3 numbers, got {value!r}") from None
    if a.shape != (3,):
        raise GeometryError(f"{what} must be 3 numbers, got shape {a.shape}")
    if not np.isfinite(a).all():
        raise GeometryError(f"{what} must be finite, got {a.tolist()}")
    return (float(a[0]), float(a[1]), float(a[2]))


def _radius(value: Any, what: str = "radius") -> float:
    return finite_number(value, what, 0.0, False, GeometryError)


def as_index(value: Any, message: str) -> int:
    """``value`` as an int (an integer or anything with ``__index__``, never a bool), else a
    GeometryError with ``message``."""
    if not isinstance(value, (bool, np.bool_)):
        try:
            return operator.index(value)
        except TypeError:
            pass
    raise GeometryError(message) from None


def link_name(link: Any) -> str:
    """A shape's link as a name: text is kept, an integer k (a chain's link frame k) becomes
    ``"link<k+1>"``."""
    if isinstance(link, str):
        if not link or "\0" in link:
            raise GeometryError(f"a link name must be non-empty text without NUL, got {link!r}")
        return link
    k = as_index(link, f"a link must be a name or a link frame index, not {link!r}")
    if k < 0:
        raise GeometryError(f"a link frame index must be >= 0, got {k}")
    return f"link{k + 1}"


class _Round:
    """What a sphere and a capsule share: the points of their core (``_ENDS``: each field and its
    name in errors, after ``_KIND``), a radius and a link, checked when they are made."""

    _KIND = ""
    _ENDS: tuple[tuple[str, str], ...] = ()
    radius: float
    link: str

    def __post_init__(self) -> None:
        for end, what in self._ENDS:
            object.__setattr__(self, end, _vec3(getattr(self, end), f"{self._KIND} {what}"))
        object.__setattr__(self, "radius", _radius(self.radius, f"{self._KIND} radius"))
        object.__setattr__(self, "link", link_name(self.link))

    @property
    def points(self) -> tuple[Vec3, ...]:
        return tuple(getattr(self, end) for end, _ in self._ENDS)


@dataclass(frozen=True)
class Sphere(_Round):
    """A sphere of ``radius`` centred at ``center`` in the frame of ``link``."""

    _KIND, _ENDS = "sphere", (("center", "center"),)
    center: Vec3
    radius: float
    link: str = "base"


@dataclass(frozen=True)
class Capsule(_Round):
    """The points within ``radius`` of the segment ``a``-``b`` (frame of ``link``)."""

    _KIND, _ENDS = "capsule", (("a", "end a"), ("b", "end b"))
    a: Vec3
    b: Vec3
    radius: float
    link: str = "base"


def _rotation(value: Any) -> tuple[float, ...]:
    try:
        R = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise GeometryError(f"box rotation must be a 3x3 rotation matrix, got {value!r}") from None
    if R.size == 9:
        R = R.reshape(3, 3)
    if R.shape != (3, 3) or not np.isfinite(R).all():
        raise GeometryError(f"box rotation must be a finite 3x3 rotation matrix, got shape {R.shape}")
    if not np.allclose(R.T @ R, np.eye(3), atol=1e-9) or np.linalg.det(R) < 0:
        raise GeometryError("box rotation must be a rotation matrix (orthonormal, det +1)")
    return tuple(float(x) for x in R.ravel())


@dataclass(frozen=True)
class Box:
    """A box of half side lengths ``half_extents`` centred at ``center``, axes the columns of
    ``rotation`` (row-major 3x3, identity by default), in the base frame (environment only)."""

    center: Vec3
    half_extents: Vec3
    rotation: tuple[float, ...] = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", _vec3(self.center, "box center"))
        h = _vec3(self.half_extents, "box half_extents")
        if min(h) < 0:
            raise GeometryError(f"box half_extents must be >= 0, got {list(h)}")
        object.__setattr__(self, "half_extents", h)
        object.__setattr__(self, "rotation", _rotation(self.rotation))

    @property
    def R(self) -> np.ndarray:
        return np.array(self.rotation).reshape(3, 3)


Shape = Sphere | Capsule


def _pair(p: Any) -> tuple[str, str]:
    try:
        a, b = p
    except (TypeError, ValueError):
        raise GeometryError(f"a disabled pair must be two link names, got {p!r}") from None
    a, b = link_name(a), link_name(b)
    return (a, b) if a <= b else (b, a)


@dataclass(frozen=True)
class Geometry:
    """A robot's collision model: ``shapes`` (spheres and capsules, each on a link) and
    ``disabled``, pairs of links never checked against each other (sorted, deduplicated)."""

    shapes: tuple[Shape, ...] = ()
    disabled: tuple[tuple[str, str], ...] = ()
    source: str = field(default="", compare=False)

    def __post_init__(self) -> None:
        shapes = tuple(self.shapes)
        for s in shapes:
            if not isinstance(s, (Sphere, Capsule)):
                raise GeometryError(f"robot geometry holds Sphere and Capsule shapes, not {type(s).__name__}")
        object.__setattr__(self, "shapes", shapes)
        object.__setattr__(self, "disabled", tuple(sorted({_pair(p) for p in self.disabled})))

    @property
    def links(self) -> tuple[str, ...]:
        """The links that carry shapes, in first-use order."""
        return tuple(dict.fromkeys(s.link for s in self.shapes))

    def __len__(self) -> int:
        return len(self.shapes)

    def with_disabled(self, pairs: Iterable[Sequence[Any]]) -> Geometry:
        """This geometry with more link pairs never checked."""
        return Geometry(self.shapes, (*self.disabled, *pairs), self.source)

    def fingerprint(self) -> str:
        """sha256 of the shapes and disabled pairs (exact numbers): part of the collision cache key."""
        h = hashlib.sha256()
        for s in self.shapes:
            h.update(repr((type(s).__name__, s.link, *[float.hex(x) for p in s.points for x in p],
                           float.hex(s.radius))).encode())  # fmt: skip
        h.update(repr(self.disabled).encode())
        return h.hexdigest()


@dataclass(frozen=True)
class Environment:
    """Obstacles in the robot's base frame: spheres, capsules and boxes (their ``link`` is ignored)."""

    spheres: tuple[Sphere, ...] = ()
    capsules: tuple[Capsule, ...] = ()
    boxes: tuple[Box, ...] = ()

    def __post_init__(self) -> None:
        for what, kind in (("spheres", Sphere), ("capsules", Capsule), ("boxes", Box)):
            items = tuple(getattr(self, what))
            for x in items:
                if not isinstance(x, kind):
                    raise GeometryError(f"Environment {what} must be {kind.__name__}, not {type(x).__name__}")
            object.__setattr__(self, what, items)

    @classmethod
    def from_points(cls, points: Any, radius: float) -> Environment:
        """A point cloud (N, 3) as spheres of ``radius`` (e.g. half the voxel size)."""
        r = _radius(radius)
        P = np.asarray(points, dtype=float)
        if P.ndim != 2 or P.shape[1] != 3:
            raise GeometryError(f"points must have shape (N, 3), got {P.shape}")
        if not np.isfinite(P).all():
            raise GeometryError("points contain NaN or inf")
        return cls(spheres=tuple(Sphere(p, r) for p in P))

    def __hash__(self) -> int:
        """The hash of the obstacles, computed once (an environment is a key of the C IK solvers
        that avoid it, looked up on every ``kin.ik(T, collision=env)``)."""
        h = self.__dict__.get("_hash")
        if h is None:
            h = hash((self.spheres, self.capsules, self.boxes))
            object.__setattr__(self, "_hash", h)
        return h

    def __getstate__(self) -> dict[str, Any]:
        """Pickle the obstacles only: the packed arrays a kernel cached (with their memory
        addresses) stay behind."""
        return {k: v for k, v in self.__dict__.items() if not k.startswith("_")}

    def __add__(self, other: Environment) -> Environment:
        return Environment(
            self.spheres + other.spheres, self.capsules + other.capsules, self.boxes + other.boxes
        )

    def __len__(self) -> int:
        return len(self.spheres) + len(self.capsules) + len(self.boxes)

    def arrays(self) -> dict[str, np.ndarray]:
        """Packed arrays: spheres (S, 4) [x y z r], capsules (C, 7) [a b r], boxes (B, 15)
        [center, half extents, rotation row-major]."""
        return {
            "spheres": np.array([[*s.center, s.radius] for s in self.spheres], dtype=float).reshape(-1, 4),
            "capsules": np.array([[*c.a, *c.b, c.radius] for c in self.capsules], dtype=float).reshape(-1, 7),
            "boxes": np.array(
                [[*b.center, *b.half_extents, *b.rotation] for b in self.boxes], dtype=float
            ).reshape(-1, 15),  # fmt: skip
        }


def check_geometry(geometry: Any, links: Sequence[str], name: str = "robot") -> None:
    """Raise GeometryError unless ``geometry`` is None or a Geometry whose shapes and disabled
    pairs name only ``links``."""
    if geometry is None:
        return
    if not isinstance(geometry, Geometry):
        raise GeometryError(
            f"geometry must be a symkin.geometry.Geometry or None, not {type(geometry).__name__}"
        )
    known = set(links)
    for s in geometry.shapes:
        if s.link not in known:
            raise GeometryError(
                f"{name} has no link {s.link!r} for a {type(s).__name__.lower()}; links: {list(links)}"
            )
    for a, b in geometry.disabled:
        for x in (a, b):
            if x not in known:
                raise GeometryError(
                    f"disabled pair ({a!r}, {b!r}): {name} has no link {x!r}; links: {list(links)}"
                )


def move_links(geometry: Geometry | None, moves: dict[str, np.ndarray]) -> Geometry | None:
    """``geometry`` with the shapes on each link of ``moves`` mapped by its 4x4 transform (point
    p becomes ``T @ p``): the same body seen from a frame that moved."""
    if geometry is None or not moves:
        return geometry

    def moved(s: Shape) -> Shape:
        T = moves.get(s.link)
        if T is None:
            return s
        ends = {end: tuple(T[:3, :3] @ np.array(p) + T[:3, 3]) for (end, _), p in zip(s._ENDS, s.points)}
        return dataclasses.replace(s, **ends)

    return Geometry(tuple(moved(s) for s in geometry.shapes), geometry.disabled, geometry.source)


def rename_links(geometry: Geometry | None, names: dict[str, str]) -> Geometry | None:
    """``geometry`` with the links in ``names`` renamed (others kept)."""
    if geometry is None:
        return None
    shapes = tuple(dataclasses.replace(s, link=names.get(s.link, s.link)) for s in geometry.shapes)
    disabled = tuple((names.get(a, a), names.get(b, b)) for a, b in geometry.disabled)
    return Geometry(shapes, disabled, geometry.source)
