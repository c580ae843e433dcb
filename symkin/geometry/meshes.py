"""A URDF's ``<collision><mesh>`` elements as triangles in the frames of a symkin model's links.

:func:`read_mesh` reads one mesh file (trimesh, the ``geometry`` extra) into a triangle array,
scaled, with a :class:`~symkin.errors.GeometryError` naming the file when it cannot be read, has no
triangles or holds NaN/inf. :func:`resolve_mesh` finds the file of a ``filename`` attribute:
relative to the URDF's folder, ``file://`` paths as such, and ``package://PKG/rest`` as ``DIR/rest``
with ``DIR`` given for ``PKG`` in ``packages`` or, failing that, the nearest folder named ``PKG``
above the URDF. :func:`mesh_parts` places every mesh of a URDF on the links of a model, given the
pose of each URDF link in a model link's frame (:func:`link_placements`): links joined by fixed
joints to a model link ride on it; a link that a prismatic joint the model does not have moves
(a gripper finger) rides on it too, **swept over that joint's whole travel** (its stroke), so a
cover of it holds the finger wherever it is.
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np

from symkin.errors import GeometryError, MissingExtraError, URDFError
from symkin.model.transform import rpy_matrix
from symkin.model.urdf import URDFGraph, joint_axis, joint_limits, joint_origin, xml_numbers

__all__ = [
    "MeshPart",
    "Placement",
    "load_mesh",
    "read_mesh",
    "resolve_mesh",
    "link_placements",
    "mesh_parts",
    "mesh_triangles",
    "shape_sizes",
    "urdf_folder",
    "MAX_SHAPE_SIZE",
    "box_triangles",
]

#: The largest collision shape dimension (m) accepted from a URDF: radius, length, box side, a
#: mesh's extent after its scale. Larger ones are refused with the link named (a sphere of 1e300
#: m squares to inf in every distance).
MAX_SHAPE_SIZE = 1e4

_INSTALL = 'pip install "symkin[geometry]"'


@dataclass(frozen=True)
class Placement:
    """Where a URDF link rides: the model link ``link``, the URDF link frame's pose ``T`` (4, 4)
    in that link's frame, and ``stroke`` (3,) in that frame when a prismatic joint the model lacks
    slides it (the link at ``T`` is at the joint's lower limit), else None."""

    link: str
    T: np.ndarray
    stroke: np.ndarray | None = None


@dataclass(frozen=True)
class MeshPart:
    """One ``<collision><mesh>``: ``triangles`` (F, 3, 3) in the frame of model link ``link``
    (metres), swept along ``stroke`` when not None; ``urdf_link`` and ``file`` say where it came from."""

    link: str
    urdf_link: str
    file: str
    triangles: np.ndarray
    stroke: np.ndarray | None = None


def resolve_mesh(
    filename: str, folder: Path, packages: Mapping[str, str | Path] | None = None
) -> Path | None:
    """The path of a mesh ``filename`` of a URDF in ``folder`` (module docstring), or None for a
    ``package://`` path that neither ``packages`` nor a folder above the URDF resolves."""
    if filename.startswith("package://"):
        pkg, _, rest = filename[len("package://") :].partition("/")
        if packages and pkg in packages:
            return Path(packages[pkg]) / rest
        for up in [folder.resolve(), *folder.resolve().parents]:
            if up.name == pkg:
                return up / rest
        return None
    if filename.startswith("file://"):
        filename = filename[len("file://") :]
    p = Path(filename)
    return p if p.is_absolute() else folder / p


def load_mesh(path: str | Path, what: str = "") -> Any:
    """The mesh file ``path`` (any format trimesh reads) as a trimesh mesh; GeometryError naming
    the file (and ``what``, e.g. the link) when it cannot be read, MissingExtraError without trimesh."""
    where = f"{what}: " if what else ""
    try:
        import trimesh
    except ImportError:
        raise MissingExtraError(
            f"{where}reading the mesh file {str(path)!r} needs trimesh: {_INSTALL}"
        ) from None
    try:
        return trimesh.load(str(path), force="mesh")
    except Exception as exc:  # trimesh raises many kinds for unreadable files
        raise GeometryError(
            f"{where}cannot read mesh file {str(path)!r}: {type(exc).__name__}: {exc}"
        ) from None


def read_mesh(path: str | Path, scale: Any = (1.0, 1.0, 1.0), what: str = "") -> np.ndarray:
    """The triangles (F, 3, 3) of the mesh file ``path`` (:func:`load_mesh`), each vertex
    multiplied by ``scale`` per axis. GeometryError naming the file (and ``what``, e.g. the link)
    when it cannot be read, has no triangles or holds NaN/inf; MissingExtraError without trimesh.
    (:func:`check_extent` bounds the size.)"""
    where = f"{what}: " if what else ""
    s = np.asarray(scale, dtype=float).reshape(-1)
    if s.shape != (3,) or not np.isfinite(s).all():
        raise GeometryError(f"{where}mesh scale must be 3 finite numbers, got {scale!r}")
    T = np.asarray(load_mesh(path, what).triangles, dtype=float).reshape(-1, 3, 3)
    if len(T) == 0:
        raise GeometryError(f"{where}mesh file {str(path)!r} has no triangles (empty or not a mesh)")
    if not np.isfinite(T).all():
        raise GeometryError(f"{where}mesh file {str(path)!r} has NaN or inf vertices")
    with np.errstate(over="ignore", invalid="ignore"):
        return T * s


def check_extent(T: np.ndarray, what: str) -> None:
    """GeometryError naming ``what`` unless every vertex of ``T`` is finite and within
    :data:`MAX_SHAPE_SIZE` of its frame's origin."""
    extent = float(np.abs(T).max()) if T.size else 0.0
    if not math.isfinite(extent) or extent > MAX_SHAPE_SIZE:
        raise GeometryError(
            f"{what} reaches {extent:g} m from its origin; collision shapes must stay within "
            f"{MAX_SHAPE_SIZE:g} m"
        )


def _slide(
    graph: URDFGraph, link: str, known: Mapping[str, Placement], slide: bool = True
) -> tuple[Placement | None, str]:
    """Walk up from ``link`` to a link in ``known`` through fixed joints and (with ``slide``) at
    most one prismatic joint (not in ``known``'s model): its placement, or (None, why not)."""
    T = np.eye(4)  # the pose of ``link``'s frame in the frame of ``cur``
    stroke: np.ndarray | None = None  # the travel of the sliding joint, in the frame of ``cur``
    cur = link
    while cur not in known:
        j = graph.parent_joint.get(cur)
        if j is None:
            return None, f"it is not below the model's base (the root {cur!r} is reached)"
        O = rpy_matrix(*joint_origin(j.el, f"joint {j.name!r}"))
        if j.kind == "prismatic" and stroke is None and slide:
            lo, hi, _ = joint_limits(j, graph.where)
            u = np.array([float(c) for c in joint_axis(j.el, f"joint {j.name!r}", graph.where, 1e-9)])
            u /= np.linalg.norm(u)
            M = np.eye(4)
            M[:3, 3] = lo * u  # the link at the lower limit, sliding by (hi - lo) u from there
            T = O @ M @ T
            stroke = O[:3, :3] @ ((hi - lo) * u)
        elif j.kind == "fixed":
            T = O @ T
            stroke = None if stroke is None else O[:3, :3] @ stroke
        else:
            return None, f"the {j.kind} joint {j.name!r} above it is not a joint of the model"
        cur = j.parent
    base = known[cur]
    if stroke is not None:
        stroke = base.T[:3, :3] @ stroke
    return Placement(base.link, base.T @ T, stroke), ""


def link_placements(
    graph: URDFGraph, frames: Mapping[str, tuple[str, np.ndarray]], slide: bool = True
) -> tuple[dict[str, Placement], dict[str, str]]:
    """Every URDF link's :class:`Placement`, from ``frames`` (URDF link -> (model link, pose of the
    URDF link frame in the model link's frame)) for the links the model has, walking up fixed joints
    and (with ``slide``) one sliding joint for the others; and, for links with no placement, why not."""
    known = {ln: Placement(name, np.asarray(T, dtype=float)) for ln, (name, T) in frames.items()}
    out, why = dict(known), {}
    for ln in graph.links:
        if ln in out:
            continue
        found, reason = _slide(graph, ln, known, slide)
        if found is None:
            why[ln] = reason
        else:
            out[ln] = found
    return out, why


def mesh_parts(
    root: ElementTree.Element,
    where: str,
    folder: Path,
    placements: Mapping[str, Placement],
    why: Mapping[str, str] | None = None,
    packages: Mapping[str, str | Path] | None = None,
) -> tuple[list[MeshPart], list[str]]:
    """The ``<collision><mesh>`` elements of a URDF (its root element, ``where`` for messages,
    ``folder`` for relative paths) placed on model links by ``placements``; and a warning line for
    each mesh that could not be used (not placed, not resolved, not found, unreadable), naming the
    link and the file. Other collision shapes are not read here."""
    parts: list[MeshPart] = []
    skipped: list[str] = []
    for lel in root.findall("link"):
        lname = lel.get("name") or ""
        for i, cel in enumerate(lel.findall("collision")):
            g = cel.find("geometry")
            shape = None if g is None else next((k for k in g if k.tag in ("mesh", "box")), None)
            if shape is None:
                continue
            what = f"link {lname!r} collision {cel.get('name') or i}"
            label = f"mesh {shape.get('filename') or ''!r}" if shape.tag == "mesh" else "box"
            if lname not in placements:
                reason = (why or {}).get(lname, "the model has no link for it")
                skipped.append(f"{where}: {what} ({label}) skipped: {reason}")
                continue
            if shape.tag == "box":
                size = shape_sizes(shape, "size", 3, f"{where}: {what} box size")
                T, file = box_triangles(np.array(size) / 2), f"{lname} box {i}"
            else:
                T, file, note = mesh_triangles(shape, folder, packages, where, what)
                if T is None:
                    skipped.append(note)
                    continue
            place = placements[lname]
            M = place.T @ rpy_matrix(*joint_origin(cel, what))
            tri = T @ M[:3, :3].T + M[:3, 3]
            parts.append(MeshPart(place.link, lname, file, tri, place.stroke))
    return parts, skipped


def mesh_triangles(
    shape: ElementTree.Element, folder: Path, packages: Mapping[str, str | Path] | None, where: str, what: str
) -> tuple[np.ndarray | None, str, str]:
    """A ``<mesh>``'s triangles (scaled, in the collision element's frame) and file, or None and
    the warning line saying why not (not resolved, missing, unreadable); MissingExtraError without
    trimesh, GeometryError for a bad scale or a mesh larger than :data:`MAX_SHAPE_SIZE`."""
    filename = shape.get("filename") or ""
    path = resolve_mesh(filename, folder, packages)
    if path is None:
        why = "package:// paths are not resolved (no ROS package path; give packages={name: folder})"
        return None, "", f"{where}: {what} is a mesh at {filename!r}; {why}: skipped"
    if not path.is_file():
        return None, "", f"{where}: {what}: mesh file {str(path)!r} does not exist: skipped"
    scale = [1.0] * 3
    if shape.get("scale"):
        scale = shape_sizes(shape, "scale", 3, f"{where}: {what} mesh scale", signed=True)
    try:
        T = read_mesh(path, scale, f"{where}: {what}")
    except GeometryError as exc:
        return None, "", f"{exc}: skipped"
    check_extent(T, f"{where}: {what}: mesh file {str(path)!r} scaled by {scale}")
    return T, str(path), ""


def shape_sizes(
    shape: ElementTree.Element, attr: str, count: int, what: str, signed: bool = False
) -> list[float]:
    """``count`` sizes of a shape attribute: finite, at most :data:`MAX_SHAPE_SIZE` in size and
    >= 0 (unless ``signed``: a mesh scale may mirror), else a GeometryError naming ``what`` (the
    link and collision element)."""
    try:
        values = [float(v) for v in xml_numbers(shape.get(attr), count, what)]
    except URDFError as exc:
        raise GeometryError(str(exc)) from None
    if max(abs(v) for v in values) > MAX_SHAPE_SIZE or (not signed and min(values) < 0):
        sign = "" if signed else ">= 0 and "
        raise GeometryError(f"{what} is {values}; collision sizes must be {sign}at most {MAX_SHAPE_SIZE:g} m")
    return values


def urdf_folder(path_or_xml: str | Path) -> Path:
    """The folder relative mesh paths of a URDF start from: the file's, or the working folder for
    XML text."""
    text = str(path_or_xml)
    is_file = isinstance(path_or_xml, Path) or not text.lstrip().lstrip("\ufeff").startswith("<")
    return Path(text).parent if is_file else Path.cwd()


def box_triangles(half_extents: Any) -> np.ndarray:
    """The 12 triangles (12, 3, 3) of the box ``|x_i| <= half_extents_i``, wound outward."""
    h = np.asarray(half_extents, dtype=float)
    V = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float) * h
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    return np.array([V[[a, b, c]] for a, b, c, d in quads] + [V[[a, c, d]] for a, b, c, d in quads])


def warn_skipped(lines: list[str]) -> None:
    """Each line of :func:`mesh_parts`'s skipped list as a warning."""
    for line in lines:
        warnings.warn(line, stacklevel=3)
