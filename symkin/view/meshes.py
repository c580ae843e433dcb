"""The meshes the live view draws for a URDF robot: each ``<visual>`` (or ``<collision>``) element of
the URDF as triangles in the frame of the model link it moves with (:class:`~symkin.view.scene.MeshPart`).

A ``<mesh>`` file is read with trimesh (the ``geometry`` extra) and scaled by its ``scale``; its
``filename`` is found relative to the URDF's folder, as an absolute or ``file://`` path, or, for
``package://PKG/rest``, as ``rest`` below the nearest folder named ``PKG`` above the URDF (how
example-robot-data and most description packages are laid out; no ROS needed). ``<box>``,
``<cylinder>`` and ``<sphere>`` elements are made here (NumPy). Each element's ``<origin>`` and the
fixed joints between its URDF link and the model link (:func:`symkin.geometry.urdf.urdf_link_frames`)
place it; the colour is its ``<material>``'s (inline or named at the top of the file), else grey.

Nothing here is an error: without trimesh, for a file that does not resolve, does not exist or
cannot be read, or a link the model does not carry, the element is left out and a note says why;
the view then draws the collision shapes in its place (:func:`symkin.view.server.view`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import Any
from xml.etree import ElementTree

import numpy as np

from symkin.errors import SymkinError
from symkin.geometry.meshes import load_mesh, resolve_mesh
from symkin.model.transform import rpy_matrix
from symkin.view.scene import MeshPart, capsule_mesh

__all__ = ["urdf_meshes", "resolve_mesh_file", "box_mesh", "cylinder_mesh", "MESH_KINDS"]

MESH_KINDS = ("visual", "collision", "none")
_GREY = (185, 185, 190)
_INSTALL = 'pip install "symkin[geometry]"'


def resolve_mesh_file(filename: str, folder: Path) -> Path | None:
    """The file a URDF ``<mesh filename>`` names (module docstring), or None for a ``package://``
    path no folder above ``folder`` resolves (:func:`symkin.geometry.meshes.resolve_mesh`)."""
    return resolve_mesh(filename, folder)


def box_mesh(size: Sequence[float]) -> tuple[np.ndarray, np.ndarray]:
    """The box of side lengths ``size`` centred at the origin: vertices (8, 3), faces (12, 3),
    wound outward."""
    h = np.asarray(size, dtype=float) / 2
    V = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], dtype=float) * h
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    F = [(a, b, c) for a, b, c, _ in quads] + [(a, c, d) for a, _, c, d in quads]
    return V.astype(np.float32), np.array(F, dtype=np.uint32)


def cylinder_mesh(radius: float, length: float, segments: int = 24) -> tuple[np.ndarray, np.ndarray]:
    """The closed cylinder along z from ``-length/2`` to ``+length/2``: vertices (2 s + 2, 3),
    faces (4 s, 3)."""
    t = np.linspace(0.0, 2 * math.pi, segments, endpoint=False)
    ring = np.c_[radius * np.cos(t), radius * np.sin(t)]
    h = length / 2
    V = np.vstack(
        (np.c_[ring, np.full(segments, -h)], np.c_[ring, np.full(segments, h)], [[0, 0, -h], [0, 0, h]])
    )
    F = []
    for i in range(segments):
        j = (i + 1) % segments
        F += [(i, j, segments + i), (j, segments + j, segments + i)]  # the side
        F += [(2 * segments, j, i), (2 * segments + 1, segments + i, segments + j)]  # the caps
    return V.astype(np.float32), np.array(F, dtype=np.uint32)


def _numbers(el: ElementTree.Element | None, attr: str, count: int, default: str) -> list[float]:
    text = default if el is None else (el.get(attr) or default)
    values = [float(x) for x in text.split()]
    if len(values) != count or not all(math.isfinite(v) for v in values):
        raise ValueError(f"{attr}={text!r}: {count} finite numbers expected")
    return values


def _rgba(colour: ElementTree.Element | None) -> tuple[int, int, int] | None:
    """A ``<color rgba>`` as 0-255 (r, g, b), or None."""
    if colour is None:
        return None
    try:
        rgba = _numbers(colour, "rgba", 4, "")
    except ValueError:
        return None
    r, g, b = (int(round(255 * min(max(c, 0.0), 1.0))) for c in rgba[:3])
    return r, g, b


def _colour(el: ElementTree.Element, named: dict[str, tuple[int, int, int]]) -> tuple[int, int, int]:
    """The colour of a ``<visual>``: its material's colour, inline or by name, else grey."""
    material = el.find("material")
    if material is None:
        return _GREY
    return _rgba(material.find("color")) or named.get(material.get("name") or "", _GREY)


def _shape(geometry: ElementTree.Element, folder: Path) -> tuple[np.ndarray, np.ndarray, str]:
    """Vertices, faces and a name of one ``<geometry>``'s shape; ValueError saying why not."""
    shape = next(iter(geometry), None)
    if shape is None:
        raise ValueError("no shape in <geometry>")
    if shape.tag == "box":
        return (*box_mesh(_numbers(shape, "size", 3, "")), "box")
    if shape.tag == "cylinder":
        r, length = _numbers(shape, "radius", 1, "")[0], _numbers(shape, "length", 1, "")[0]
        return (*cylinder_mesh(r, length), "cylinder")
    if shape.tag == "sphere":
        return (*capsule_mesh(_numbers(shape, "radius", 1, "")[0], 0.0), "sphere")
    if shape.tag != "mesh":
        raise ValueError(f"unknown shape <{shape.tag}>")
    filename = shape.get("filename") or ""
    path = resolve_mesh_file(filename, folder)
    if path is None:
        raise ValueError(f"{filename!r}: no folder named after its package above the URDF")
    if not path.is_file():
        raise ValueError(f"mesh file {str(path)!r} does not exist")
    try:
        mesh = load_mesh(path)
    except SymkinError as exc:
        raise ValueError(str(exc)) from None
    V, F = np.asarray(mesh.vertices, dtype=float), np.asarray(mesh.faces, dtype=np.int64)
    if not len(F) or not np.isfinite(V).all():
        raise ValueError(f"mesh file {str(path)!r} has no triangles or NaN/inf vertices")
    V = V * _numbers(shape, "scale", 3, "1 1 1")
    return V, F.astype(np.uint32), path.name


def urdf_meshes(path: str | Path, model: Any, kind: str = "visual") -> tuple[list[MeshPart], list[str]]:
    """The ``<visual>`` (``kind="visual"``) or ``<collision>`` (``"collision"``) elements of the URDF
    file ``path`` as :class:`MeshPart` s on the links of ``model`` (a Tree read from it, or a Robot
    from :meth:`symkin.Robot.from_urdf` of it), and notes (one line each) on what was left out and
    why. ``kind="none"``: nothing."""
    if kind not in MESH_KINDS:
        raise ValueError(f"kind is one of {MESH_KINDS}, not {kind!r}")
    if kind == "none":
        return [], []
    from symkin.geometry.urdf import urdf_link_frames
    from symkin.model.urdf import load_xml

    path = Path(path)
    try:
        root, _ = load_xml(path)
        frames = urdf_link_frames(path, model)
    except SymkinError as exc:
        return [], [f"no meshes drawn: {exc}"]
    try:
        import trimesh  # noqa: F401

        has_trimesh = True
    except ImportError:
        has_trimesh = False
    named = {m.get("name") or "": c for m in root.findall("material") if (c := _rgba(m.find("color")))}
    parts: list[MeshPart] = []
    notes: list[str] = []
    no_trimesh = 0
    for link in root.findall("link"):
        name = link.get("name") or ""
        for i, el in enumerate(link.findall(kind)):
            what = f"link {name!r} {kind} {el.get('name') or i}"
            geometry = el.find("geometry")
            if geometry is None:
                continue
            if name not in frames:
                notes.append(f"{what}: not drawn: the model has no link it moves with")
                continue
            if not has_trimesh and next(iter(geometry), ElementTree.Element("")).tag == "mesh":
                no_trimesh += 1
                continue
            try:
                V, F, shape = _shape(geometry, path.parent)
                origin = el.find("origin")
                T = frames[name][1] @ rpy_matrix(
                    _numbers(origin, "xyz", 3, "0 0 0"), _numbers(origin, "rpy", 3, "0 0 0")
                )
            except ValueError as exc:
                notes.append(f"{what}: not drawn: {exc}")
                continue
            V = V @ T[:3, :3].T + T[:3, 3]
            parts.append(
                MeshPart(frames[name][0], V.astype(np.float32), F, _colour(el, named), f"{name} {shape}")
            )
    if no_trimesh:
        notes.insert(
            0, f"{no_trimesh} {kind} meshes not drawn: reading mesh files needs trimesh ({_INSTALL})"
        )
    return parts, notes
