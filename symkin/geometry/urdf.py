"""Collision geometry from a URDF's ``<collision>`` elements, on the links of a symkin model.

:func:`geometry_from_urdf` reads each ``<link>``'s ``<collision>`` children (through the one URDF
reader, :mod:`symkin.model.urdf`) and places them, with their ``<origin xyz rpy>``, on the link
of ``model`` they move with:

- ``<sphere radius>``: a :class:`~symkin.geometry.Sphere`;
- ``<cylinder radius length>`` (and ``<capsule radius length>``): a
  :class:`~symkin.geometry.Capsule` along the element's z axis from ``-length/2`` to
  ``+length/2`` with the same radius, so a cylinder gains rounded caps (``radius`` longer at
  each end: conservative);
- ``<box size>``: a grid of spheres, each circumscribing its grid cell (conservative), cells
  as near cubes as ``max_box_spheres`` allows;
- ``<mesh filename scale>``: ``mesh_spheres`` spheres fitted by :func:`symkin.geometry.fit.fit_spheres`
  when ``mesh_spheres > 0``, trimesh is installed and the file resolves
  (:func:`symkin.geometry.meshes.resolve_mesh`: relative to the URDF's folder, ``file://`` paths as
  such, ``package://PKG/...`` from ``packages`` or a folder named PKG above the URDF) and reads;
  otherwise skipped with a warning naming the link (and the file). The covering fit of a URDF's
  meshes is :func:`symkin.geometry.mesh_fit.fit_urdf`.

Sizes (radius, length, box sides) must be finite, >= 0 and at most
:data:`symkin.geometry.meshes.MAX_SHAPE_SIZE` (1e4 m), a mesh scale finite and at most that in
size (negative mirrors), else a GeometryError names the link; a box of any thickness, 0 or 1e-300 m
included, becomes at most ``max_box_spheres`` spheres.

``model`` is a :class:`symkin.Tree` (its links are URDF link names) or a :class:`symkin.Robot`
from :meth:`symkin.Robot.from_urdf` of the same file, whose links are ``base`` (the chain's
base link), ``link<k+1>`` (the child link of the k-th movable joint; the constant transform
between symkin's link frame k and that URDF link frame is measured from the two forward
kinematics, and checked) and ``ee`` (the chain's end link when fixed joints lead to it). A
URDF link that is not one of the model's links is attached to its nearest ancestor that is,
through fixed joints (their transforms composed); one reached only through a movable joint the
model does not have, or above the model's base, is skipped with a warning.
"""

from __future__ import annotations

import math
import re
import warnings
from collections.abc import Mapping
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np

from symkin.errors import GeometryError, MissingExtraError
from symkin.geometry.meshes import MAX_SHAPE_SIZE, link_placements, mesh_triangles, shape_sizes, urdf_folder
from symkin.model.geometry import Capsule, Geometry, Sphere, as_index
from symkin.model.transform import rpy_matrix
from symkin.model.urdf import (
    URDFGraph,
    URDFJoint,
    joint_axis,
    joint_origin,
    load_xml,
    read_graph,
)

__all__ = [
    "geometry_from_urdf",
    "urdf_geometry",
    "urdf_link_names",
    "urdf_link_frames",
    "urdf_carriers",
    "box_spheres",
    "MAX_SHAPE_SPHERES",
]

_INSTALL = 'pip install "symkin[geometry]"'
_Frame = tuple[str, np.ndarray]  # model link name, 4x4 transform model link frame -> URDF link frame


def _joint_origin(j: URDFJoint) -> np.ndarray:
    return rpy_matrix(*joint_origin(j.el, f"joint {j.name!r}"))


def _joint_motion(j: URDFJoint, where: str, q: float) -> np.ndarray:
    """The transform of a movable joint at value ``q`` about / along its unit axis."""
    u = np.array([float(c) for c in joint_axis(j.el, f"joint {j.name!r}", where, 1e-9)])
    u /= np.linalg.norm(u)
    T = np.eye(4)
    if j.kind == "prismatic":
        T[:3, 3] = q * u
        return T
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    T[:3, :3] = np.eye(3) + math.sin(q) * K + (1 - math.cos(q)) * (K @ K)
    return T


def _tree_frames(graph: URDFGraph, tree: Any) -> dict[str, _Frame]:
    return {ln: (ln, np.eye(4)) for ln in tree.link_names if ln in graph.children}


def _chain_ends(graph: URDFGraph, robot: Any, joints: list[URDFJoint]) -> tuple[str, str]:
    """The base and end links of the chain ``robot`` was read from: from its source text
    (``..., chain A -> B``), else the root and the single fixed descendant of the last joint."""
    m = re.search(r", chain (.+) -> (.+?)$", robot.source or "")
    if m and m.group(1) in graph.children and m.group(2) in graph.children:
        return m.group(1), m.group(2)
    end = joints[-1].child
    while len(graph.children[end]) == 1 and graph.children[end][0].kind == "fixed":
        end = graph.children[end][0].child
    return graph.root(), end


def _chain_frames(graph: URDFGraph, robot: Any) -> dict[str, _Frame]:
    where = graph.where
    missing = [n for n in robot.joint_names if n not in graph.joints or not graph.joints[n].movable]
    if missing:
        raise GeometryError(
            f"robot {robot.name!r} has joints {missing} that are not movable joints of {where}: read the "
            "robot with Robot.from_urdf from the same URDF (or use Tree.from_urdf)"
        )
    joints = [graph.joints[n] for n in robot.joint_names]
    base, end = _chain_ends(graph, robot, joints)
    path = graph.path(base, end)
    if [j.name for j in path if j.movable] != list(robot.joint_names):
        raise GeometryError(
            f"robot {robot.name!r}'s joints {list(robot.joint_names)} are not the movable joints from "
            f"{base!r} to {end!r} in {where}"
        )

    def urdf_fk(q: np.ndarray) -> dict[str, np.ndarray]:
        out, T, k = {base: np.eye(4)}, np.eye(4), 0
        for j in path:
            T = T @ _joint_origin(j)
            if j.movable:
                T = T @ _joint_motion(j, where, float(q[k]))
                k += 1
            out[j.child] = T
        return out

    rng = np.random.default_rng(0)
    lo, hi = np.clip(robot.qlim[0], -math.pi, math.pi), np.clip(robot.qlim[1], -math.pi, math.pi)
    qs = [lo + (hi - lo) * rng.random(robot.n) for _ in range(2)]
    frames: dict[str, _Frame] = {base: ("base", np.eye(4))}
    ends: list[np.ndarray] = []
    for q in qs:
        fk, L = urdf_fk(q), robot.link_poses(q)
        C = [np.linalg.inv(L[k]) @ fk[j.child] for k, j in enumerate(joints)]
        ends.append(np.linalg.inv(robot.fkine(q)) @ fk[end])
        if len(ends) == 1:
            first = C
            continue
        bad = [k for k in range(robot.n) if not np.allclose(C[k], first[k], atol=1e-7)]
        if (
            bad
            or not np.allclose(ends[0], ends[1], atol=1e-7)
            or not np.allclose(ends[0], np.eye(4), atol=1e-7)
        ):
            raise GeometryError(
                f"robot {robot.name!r} does not move like the chain {base!r} -> {end!r} of {where} "
                f"(link frame {bad[0] if bad else 'ee'} differs): read it with Robot.from_urdf from the same "
                "URDF, without with_base/with_tool"
            )
    for k, j in enumerate(joints):
        frames[j.child] = (f"link{k + 1}", first[k])
    if end not in frames:
        frames[end] = ("ee", np.eye(4))
    return frames


def urdf_link_frames(path_or_xml: str | Path, model: Any) -> dict[str, _Frame]:
    """Per URDF link of ``model``'s kinematics, ``(model link name, T)`` with ``T`` the pose of the
    URDF link frame in that model link's frame (4x4); links the model cannot carry are absent."""
    graph = read_graph(path_or_xml)
    return _link_frames(graph, model)[0]


def _link_frames(graph: URDFGraph, model: Any) -> tuple[dict[str, _Frame], dict[str, str]]:
    from symkin.model.tree import as_tree, robot_of

    try:
        robot, tree = robot_of(model), as_tree(model)  # a chain's links are named by their place
    except TypeError:
        raise GeometryError(f"model must be a symkin Robot or Tree, not {type(model).__name__}") from None
    known = _chain_frames(graph, robot) if robot is not None else _tree_frames(graph, tree)
    placed, why = link_placements(graph, known, slide=False)
    return {ln: (p.link, p.T) for ln, p in placed.items()}, why


def urdf_link_names(path_or_xml: str | Path, model: Any) -> dict[str, str]:
    """URDF link name -> the name of the ``model`` link it is attached to (for
    :func:`symkin.geometry.srdf.read_srdf`'s ``names``)."""
    return {ln: f[0] for ln, f in urdf_link_frames(path_or_xml, model).items()}


def urdf_carriers(path_or_xml: str | Path, model: Any) -> dict[str, tuple[str, ...]]:
    """Per link of ``model``, the URDF links with ``<collision>`` elements attached to it (whose
    geometry :func:`geometry_from_urdf` puts on it), in file order: what an SRDF names
    (:func:`symkin.geometry.srdf.srdf_disabled`, :func:`~symkin.geometry.srdf.write_srdf`)."""
    root, _ = load_xml(path_or_xml)
    names = urdf_link_names(path_or_xml, model)
    out: dict[str, list[str]] = {}
    for lel in root.findall("link"):
        name = lel.get("name") or ""
        if lel.findall("collision") and name in names:
            out.setdefault(names[name], []).append(name)
    return {k: tuple(v) for k, v in out.items()}


#: The most spheres one ``<box>`` may become (``max_box_spheres``) or one ``<mesh>`` be fitted
#: with (``mesh_spheres``): the kernel's pair tests grow with the square of the sphere count.
MAX_SHAPE_SPHERES = 4096


def _sphere_budget(value: Any, what: str) -> int:
    k = as_index(value, f"{what} must be a whole number, not {value!r}")
    if not 1 <= k <= MAX_SHAPE_SPHERES:
        raise GeometryError(f"{what} must be between 1 and {MAX_SHAPE_SPHERES}, got {k}")
    return k


def box_spheres(half_extents: Any, max_spheres: int = 64) -> list[tuple[np.ndarray, float]]:
    """Spheres ``(centre, radius)`` covering the box ``|x_i| <= half_extents_i`` (box frame): a grid
    of at most ``max_spheres`` cells, each sphere through its cell's corners. The cells start as
    cubes of the box's smallest side (but no smaller than the longest side over ``max_spheres``, so
    a side of 0 or 1e-300 m is one layer of cells) and grow by 10 % until the grid has at most
    ``max_spheres`` cells: a cube is one sphere, a thin plate a layer of them, never none."""
    h = np.asarray(half_extents, dtype=float)
    if h.shape != (3,) or not np.isfinite(h).all() or (h < 0).any():
        raise GeometryError(f"box half extents must be 3 finite numbers >= 0, got {half_extents!r}")
    k = _sphere_budget(max_spheres, "max_box_spheres")
    size = 2 * h
    big = float(size.max())
    if not np.isfinite(big) or big > 2 * MAX_SHAPE_SIZE:
        raise GeometryError(f"box size {size.tolist()} is larger than {MAX_SHAPE_SIZE:g} m")
    if big == 0:
        return [(np.zeros(3), 0.0)]
    cell = max(float(size.min()), big / k)
    while True:  # at most log(k) / log(1.1) rounds: every count starts at <= k
        counts = np.maximum(1, np.ceil(size / cell - 1e-9)).astype(int)
        if counts.prod() <= k:
            break
        cell *= 1.1
    step = size / counts
    radius = 0.5 * float(np.linalg.norm(step))
    axes = [-h[i] + step[i] * (np.arange(counts[i]) + 0.5) for i in range(3)]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    return [(c, radius) for c in grid]


def geometry_from_urdf(
    path_or_xml: str | Path,
    model: Any,
    mesh_spheres: int = 0,
    max_box_spheres: int = 64,
    packages: Mapping[str, str | Path] | None = None,
) -> Geometry:
    """The ``<collision>`` elements of a URDF (file path or XML text) as a
    :class:`~symkin.geometry.Geometry` on the links of ``model`` (a :class:`symkin.Tree` or a
    :class:`symkin.Robot` from :meth:`~symkin.Robot.from_urdf` of the same URDF): shapes in the
    frames of the model's links, metres; no disabled pairs (see
    :func:`symkin.geometry.srdf.read_srdf`). Module docstring: which element becomes what.
    ``packages`` maps ``package://`` names to folders (see :func:`symkin.geometry.meshes.resolve_mesh`).
    Sizes must be finite, >= 0 and at most :data:`symkin.geometry.meshes.MAX_SHAPE_SIZE` m (a
    GeometryError names the link otherwise); ``max_box_spheres`` and ``mesh_spheres`` (when > 0)
    are at most :data:`MAX_SHAPE_SPHERES`."""
    return urdf_geometry(path_or_xml, model, mesh_spheres, max_box_spheres, packages)[0]


def urdf_geometry(
    path_or_xml: str | Path,
    model: Any,
    mesh_spheres: int = 0,
    max_box_spheres: int = 64,
    packages: Mapping[str, str | Path] | None = None,
) -> tuple[Geometry, tuple[str, ...]]:
    """:func:`geometry_from_urdf` and the URDF links some of whose ``<collision>`` elements it
    skipped (with a warning each), sorted."""
    if mesh_spheres:
        mesh_spheres = _sphere_budget(mesh_spheres, "mesh_spheres")
    max_box_spheres = _sphere_budget(max_box_spheres, "max_box_spheres")
    root, where = load_xml(path_or_xml)
    graph = read_graph(path_or_xml)
    frames, why = _link_frames(graph, model)
    folder = urdf_folder(path_or_xml)
    shapes: list[Sphere | Capsule] = []
    counts = {"sphere": 0, "cylinder": 0, "capsule": 0, "box": 0, "mesh": 0}
    skipped: list[str] = []
    for lel in root.findall("link"):
        lname = lel.get("name") or ""
        collisions = lel.findall("collision")
        if not collisions:
            continue
        if lname not in frames:
            warnings.warn(
                f"{where}: link {lname!r} has collision geometry but the model has no link for it "
                f"({why.get(lname, 'not on the model')}): skipped",
                stacklevel=2,
            )
            skipped.append(lname)
            continue
        target, A = frames[lname]
        for i, cel in enumerate(collisions):
            what = f"link {lname!r} collision {cel.get('name') or i}"
            T = A @ rpy_matrix(*joint_origin(cel, what))
            g = cel.find("geometry")
            kids = list(g) if g is not None else []
            if not kids:
                warnings.warn(f"{where}: {what} has no <geometry> shape: skipped", stacklevel=2)
                continue
            shape = kids[0]
            tag = shape.tag

            def at(p: Any, T: np.ndarray = T) -> np.ndarray:
                return T[:3, :3] @ np.asarray(p, dtype=float) + T[:3, 3]

            try:
                if tag == "sphere":
                    (r,) = shape_sizes(shape, "radius", 1, f"{where}: {what} sphere radius")
                    shapes.append(Sphere(at((0, 0, 0)), r, target))
                elif tag in ("cylinder", "capsule"):
                    (r,) = shape_sizes(shape, "radius", 1, f"{where}: {what} {tag} radius")
                    (length,) = shape_sizes(shape, "length", 1, f"{where}: {what} {tag} length")
                    shapes.append(Capsule(at((0, 0, -length / 2)), at((0, 0, length / 2)), r, target))
                elif tag == "box":
                    size = shape_sizes(shape, "size", 3, f"{where}: {what} box size")
                    for c, r in box_spheres(np.array(size) / 2, max_box_spheres):
                        shapes.append(Sphere(at(c), r, target))
                elif tag == "mesh":
                    fitted = _mesh(shape, folder, mesh_spheres, where, what, packages)
                    if fitted is None:
                        skipped.append(lname)
                        continue
                    shapes.extend(Sphere(at(c), r, target) for c, r in fitted)
                else:
                    warnings.warn(f"{where}: {what} has an unknown shape <{tag}>: skipped", stacklevel=2)
                    skipped.append(lname)
                    continue
            except GeometryError as exc:
                text = str(exc)
                raise GeometryError(text if lname in text else f"{where}: {what}: {text}") from None
            counts[tag] += 1
    made = ", ".join(f"{v} {k}" for k, v in counts.items() if v) or "no shapes"
    note = f"; skipped on {sorted(set(skipped))}" if skipped else ""
    geometry = Geometry(tuple(shapes), (), f"<collision> elements of {where} ({made}){note}")
    return geometry, tuple(sorted(set(skipped)))


def _mesh(
    shape: ElementTree.Element,
    folder: Path,
    mesh_spheres: int,
    where: str,
    what: str,
    packages: Mapping[str, str | Path] | None,
) -> list[tuple[np.ndarray, float]] | None:
    """Spheres fitted to a ``<mesh>`` (in the collision element's frame), or None with a warning
    naming the link and the file (not fitted, not resolved, missing, unreadable, empty)."""
    if mesh_spheres <= 0:
        warnings.warn(
            f"{where}: {what} is a mesh ({shape.get('filename') or ''!r}): skipped; pass mesh_spheres > 0 "
            f"(with trimesh installed: {_INSTALL}) to fit spheres to it",
            stacklevel=3,
        )
        return None
    try:
        tri, _, note = mesh_triangles(shape, folder, packages, where, what)
    except MissingExtraError:
        tri, note = None, f"{where}: {what} is a mesh; fitting spheres needs trimesh ({_INSTALL}): skipped"
    if tri is None:
        warnings.warn(note, stacklevel=3)
        return None
    import trimesh

    from symkin.geometry.fit import fit_spheres

    mesh = trimesh.Trimesh(
        vertices=tri.reshape(-1, 3), faces=np.arange(3 * len(tri)).reshape(-1, 3), process=False
    )
    return fit_spheres(mesh, mesh_spheres)
