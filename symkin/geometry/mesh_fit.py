"""Covering sphere models of robots from their collision meshes: fit, measure, report.

:func:`fit_urdf` covers the ``<collision><mesh>`` elements of any URDF on the links of a model
read from it, :func:`fit_builtin` the real meshes of a built-in arm (:mod:`symkin.geometry.builtin_meshes`)
on symkin's own link frames. Each model link's meshes are covered together by
:func:`symkin.geometry.cover.cover_spheres` (exact coverage, outward excess at most
``max_excess``); the result is a :class:`MeshFit`: the Geometry and one :class:`LinkFit` row per
link with its sphere count and excess figures. :func:`coverage` checks a geometry against mesh
surface points drawn independently of the fit (the tests' and the report's check).

Stored numbers are rounded outward (:func:`rounded`): centres to 1e-6 m and radii up by the
centre's rounding and to the next 1e-6 m, so a rounded cover still covers.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from symkin.core.progress import bar
from symkin.errors import GeometryError
from symkin.geometry.cover import Cover, Surface, cover_spheres, outer_excess
from symkin.geometry.meshes import MeshPart, link_placements, mesh_parts, urdf_folder, warn_skipped
from symkin.geometry.triangles import sample_surface
from symkin.model.geometry import Geometry, Sphere
from symkin.model.urdf import load_xml, read_graph

__all__ = [
    "LinkFit",
    "MeshFit",
    "fit_parts",
    "fit_urdf",
    "fit_builtin",
    "coverage",
    "rounded",
    "builtin_parts",
]

_DIGITS = 6  # stored coordinates: micrometres


@dataclass(frozen=True)
class LinkFit:
    """One link's cover: ``spheres`` count, ``pieces`` of its surface held whole, ``excess_bound``
    (m, the largest ``r - d`` of its spheres, plus ``slack``), ``excess_max`` and ``excess_mean``
    (m, sampled on the outer boundary of its spheres), ``slack`` (m, how far the mesh may sit from
    where it is placed, added to every radius) and the mesh ``files``."""

    link: str
    spheres: int
    pieces: int
    excess_bound: float
    excess_max: float
    excess_mean: float
    slack: float
    files: tuple[str, ...]


@dataclass(frozen=True)
class MeshFit:
    """A covering sphere model: ``geometry``, one :class:`LinkFit` per link, the ``max_excess`` it
    was fitted for, ``parts`` (the placed meshes, for :func:`coverage`) and the ``skipped`` meshes."""

    geometry: Geometry
    rows: tuple[LinkFit, ...]
    max_excess: float
    parts: tuple[MeshPart, ...] = field(repr=False)
    skipped: tuple[str, ...] = ()


def rounded(centre: Any, radius: float) -> tuple[tuple[float, float, float], float]:
    """``centre`` rounded to 1e-6 m and ``radius`` rounded up so the rounded sphere holds the
    original one."""
    c = tuple(round(float(x), _DIGITS) for x in centre)
    moved = math.dist(c, tuple(float(x) for x in centre))
    scale = 10**_DIGITS
    r = math.ceil((float(radius) + moved) * scale * (1 + 1e-12)) / scale
    return c, r  # type: ignore[return-value]


def fit_parts(
    parts: Sequence[MeshPart],
    max_excess: float,
    slack: Mapping[str, float] | None = None,
    progress: bool = True,
) -> tuple[list[Sphere], list[LinkFit]]:
    """Spheres covering ``parts`` link by link (each link's meshes together), radii grown by the
    link's ``slack`` and rounded outward, and a row of figures per link (links in first-use order)."""
    links = list(dict.fromkeys(p.link for p in parts))
    spheres: list[Sphere] = []
    rows: list[LinkFit] = []
    for link in bar(links, progress=progress, desc="covering links", unit="link"):
        mine = [p for p in parts if p.link == link]
        surfaces = [Surface(p.triangles, p.stroke, p.file) for p in mine]
        cover: Cover = cover_spheres(surfaces, max_excess)
        grow = float((slack or {}).get(link, 0.0))
        stored = [rounded(c, r + grow) for c, r in zip(cover.centres, cover.radii)]
        C = np.array([c for c, _ in stored])
        R = np.array([r for _, r in stored])
        out = outer_excess(C, R, surfaces)
        spheres += [Sphere(c, r, link) for c, r in stored]
        rows.append(
            LinkFit(
                link, len(R), cover.pieces, float((cover.excess + R - cover.radii).max() + 1e-6),
                float(out.max()), float(out.mean()), grow,
                tuple(dict.fromkeys(Path(p.file).name for p in mine)),
            )
        )  # fmt: skip
    return spheres, rows


def fit_urdf(
    path_or_xml: str | Path,
    model: Any = None,
    max_excess: float = 0.02,
    packages: Mapping[str, str | Path] | None = None,
    progress: bool = True,
) -> MeshFit:
    """Covering spheres for the ``<collision><mesh>`` elements of a URDF on the links of ``model``
    (a Robot from :meth:`symkin.Robot.from_urdf` or a Tree from :meth:`symkin.Tree.from_urdf` of
    the same file; default the Tree of every link). Meshes that cannot be placed or read are skipped
    with a warning naming the link and the file; other collision shapes are not included."""
    from symkin.geometry.urdf import urdf_link_frames
    from symkin.model.tree import Tree

    if model is None:
        model = Tree.from_urdf(path_or_xml)
    root, where = load_xml(path_or_xml)
    graph = read_graph(path_or_xml)
    frames = urdf_link_frames(path_or_xml, model)
    placements, why = link_placements(graph, frames)
    parts, skipped = mesh_parts(root, where, urdf_folder(path_or_xml), placements, why, packages)
    warn_skipped(skipped)
    if not parts:
        raise GeometryError(
            f"{where}: no collision mesh to cover" + (f" ({len(skipped)} skipped)" if skipped else "")
        )
    spheres, rows = fit_parts(parts, max_excess, progress=progress)
    geometry = Geometry(
        tuple(spheres),
        (),
        f"spheres covering the collision meshes of {where} (outward excess <= {max_excess:g} m)",
    )
    return MeshFit(geometry, tuple(rows), float(max_excess), tuple(parts), tuple(skipped))


def builtin_parts(name: str) -> tuple[list[MeshPart], dict[str, float], str]:
    """The real collision meshes of built-in robot ``name`` on its symkin links, the per-link
    slack (:func:`symkin.geometry.builtin_meshes.source_frames`) and the source's label."""
    from symkin.geometry.builtin_meshes import MESH_SOURCES, locate, on_ee, source_frames
    from symkin.model.robots import load
    from symkin.model.tree import Tree

    source = MESH_SOURCES.get(name)
    if source is None:
        raise GeometryError(
            f"no collision meshes are known for {name!r}; built-ins with meshes: {sorted(MESH_SOURCES)}"
        )
    path, packages = locate(source)
    robot = load(name).with_geometry(None)
    tree = Tree.from_urdf(path, frames=list(source.links))
    frames, slack = source_frames(robot, tree, source)
    root, where = load_xml(path)
    placements, why = link_placements(read_graph(path), frames)
    placements = on_ee(robot, placements, source)
    slack["ee"] = slack[f"link{robot.n}"]
    parts, skipped = mesh_parts(root, where, path.parent, placements, why, packages)
    if skipped:
        raise GeometryError(f"{source.label}: meshes missing: {skipped}")
    return parts, slack, source.label


def fit_builtin(name: str, max_excess: float = 0.02, progress: bool = True) -> MeshFit:
    """Covering spheres of built-in robot ``name`` from its real collision meshes, on symkin's link
    frames (no disabled pairs: see :mod:`symkin.model.builtin_geometry` for the stored models')."""
    parts, slack, label = builtin_parts(name)
    spheres, rows = fit_parts(parts, max_excess, slack, progress=progress)
    source = f"spheres covering the collision meshes of {label} (outward excess <= {max_excess:g} m)"
    return MeshFit(Geometry(tuple(spheres), (), source), tuple(rows), float(max_excess), tuple(parts))


def coverage(
    geometry: Geometry, parts: Sequence[MeshPart], samples: int = 20_000, seed: int = 1
) -> dict[str, tuple[float, float, int]]:
    """Per link, ``(fraction covered, largest distance outside, points)`` of ``samples`` points
    drawn on each part's surface plus its vertices (a swept part at random places along its
    stroke), each tested against the spheres of the link (and of the links of its body: ``ee`` with
    the last link of a chain) in the link's frame: ``(1.0, <= 0, N)`` when every point is inside a
    sphere."""
    rng = np.random.default_rng(seed)
    out: dict[str, tuple[float, float, int]] = {}
    for link in dict.fromkeys(p.link for p in parts):
        spheres = [s for s in geometry.shapes if s.link == link]
        X = []
        for p in (p for p in parts if p.link == link):
            pts = np.concatenate(
                [sample_surface(p.triangles, samples, int(rng.integers(1 << 31))), p.triangles.reshape(-1, 3)]
            )
            if p.stroke is not None:
                pts = pts + rng.random((len(pts), 1)) * p.stroke
            X.append(pts)
        P = np.concatenate(X)
        if not spheres:
            out[link] = (0.0, math.inf, len(P))
            continue
        C = np.array([s.center for s in spheres])
        R = np.array([s.radius for s in spheres])
        worst = np.full(len(P), np.inf)
        for i in range(0, len(R), 64):
            D = np.sqrt(((P[:, None, :] - C[None, i : i + 64]) ** 2).sum(-1)) - R[None, i : i + 64]
            worst = np.minimum(worst, D.min(1))
        out[link] = (float((worst <= 0).mean()), float(worst.max()), len(P))
    return out
