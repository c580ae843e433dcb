"""Spheres that cover a point set or a mesh: k-means, then each sphere grown to its farthest point.

:func:`fit_spheres` is how a ``<mesh>`` collision element becomes spheres
(:func:`symkin.geometry.urdf.geometry_from_urdf`). The spheres are in the coordinates of the
points (for a mesh file, its own units and frame) and cover every given point; for a mesh they
cover its vertices and points sampled on its surface, so a face between samples can bulge out by
at most the sample spacing's share.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from symkin.errors import GeometryError
from symkin.geometry.meshes import load_mesh
from symkin.model.geometry import as_index

__all__ = ["fit_spheres", "mesh_points"]


def _load(mesh_or_points: Any) -> Any:
    """A mesh file path loaded with trimesh (:func:`symkin.geometry.meshes.load_mesh`); anything
    else as given."""
    if not isinstance(mesh_or_points, (str, Path)):
        return mesh_or_points
    mesh = load_mesh(mesh_or_points)
    if len(np.asarray(mesh.vertices).reshape(-1, 3)) == 0:
        raise GeometryError(
            f"mesh file {str(mesh_or_points)!r} has no vertices (empty, or not a mesh trimesh reads)"
        )
    return mesh


def _triangles(obj: Any) -> np.ndarray | None:
    """The mesh's triangles (F, 3, 3) when it has faces, else None."""
    faces = getattr(obj, "faces", None)
    if not hasattr(obj, "vertices") or faces is None or len(faces) == 0:
        return None
    V = np.asarray(obj.vertices, dtype=float).reshape(-1, 3)
    F = np.asarray(faces, dtype=int).reshape(-1, 3)
    return V[F]


def _subdivide(tri: np.ndarray, max_edge: float, limit: int = 200_000) -> np.ndarray:
    """Triangles (F, 3, 3) split in four at their edge midpoints until no edge is longer than
    ``max_edge`` (or about ``limit`` triangles): the same surface in pieces small spheres can hold."""
    for _ in range(12):
        edges = np.linalg.norm(tri - np.roll(tri, 1, axis=1), axis=-1).max(1)
        big = edges > max_edge
        if not big.any() or len(tri) + 3 * int(big.sum()) > limit:
            break
        t = tri[big]
        m01, m12, m20 = (t[:, 0] + t[:, 1]) / 2, (t[:, 1] + t[:, 2]) / 2, (t[:, 2] + t[:, 0]) / 2
        parts = [
            np.stack((t[:, 0], m01, m20), 1), np.stack((m01, t[:, 1], m12), 1),
            np.stack((m20, m12, t[:, 2]), 1), np.stack((m01, m12, m20), 1),
        ]  # fmt: skip
        tri = np.concatenate([tri[~big], *parts])
    return tri


def mesh_points(mesh_or_points: Any, samples: int = 2000, seed: int = 0) -> np.ndarray:
    """The (N, 3) points :func:`fit_spheres` covers: an array as given; an object with
    ``.vertices`` (a trimesh mesh) its vertices plus ``samples`` points sampled on its surface when
    trimesh is installed and it has faces; a file path loaded with trimesh (MissingExtraError
    without it)."""
    from symkin.core.sizes import count, room

    samples = count(samples, "samples", minimum=0, error=GeometryError)
    room(24.0 * samples, f"{samples} surface samples", GeometryError)
    obj = _load(mesh_or_points)
    if hasattr(obj, "vertices"):
        pts = [np.asarray(obj.vertices, dtype=float).reshape(-1, 3)]
        faces = getattr(obj, "faces", None)
        if samples > 0 and faces is not None and len(faces) > 0:
            try:
                import trimesh
            except ImportError:
                trimesh = None
            if trimesh is not None:
                try:
                    drawn = trimesh.sample.sample_surface(obj, samples, seed=seed)[0]
                except TypeError:  # trimesh before the seed argument
                    drawn = trimesh.sample.sample_surface(obj, samples)[0]
                pts.append(np.asarray(drawn, dtype=float).reshape(-1, 3))
        P = np.concatenate(pts)
    else:
        try:
            P = np.asarray(obj, dtype=float)
        except (TypeError, ValueError):
            raise GeometryError(
                f"expected (N, 3) points, a mesh with .vertices or a mesh file path, not {type(obj).__name__}"
            ) from None
        if P.ndim != 2 or P.shape[1] != 3:
            raise GeometryError(f"points must have shape (N, 3), got {P.shape}")
    if P.shape[0] == 0:
        raise GeometryError("no points to cover: give at least one point")
    if not np.isfinite(P).all():
        raise GeometryError("points contain NaN or inf")
    return P


def _kmeans(P: np.ndarray, k: int, rng: np.random.Generator, iters: int = 60) -> np.ndarray:
    """Labels (N,) of Lloyd's k-means from a k-means++ start (every cluster non-empty)."""
    N = P.shape[0]
    C = np.empty((k, 3))
    C[0] = P[rng.integers(N)]
    d2 = ((P - C[0]) ** 2).sum(1)
    for j in range(1, k):
        total = d2.sum()
        i = int(rng.choice(N, p=d2 / total)) if total > 0 else int(rng.integers(N))
        C[j] = P[i]
        d2 = np.minimum(d2, ((P - C[j]) ** 2).sum(1))
    labels = np.full(N, -1)
    for _ in range(iters):
        D = ((P[:, None, :] - C[None]) ** 2).sum(2)
        new = D.argmin(1)
        counts = np.bincount(new, minlength=k)
        for j in np.flatnonzero(counts == 0):  # an empty cluster takes the worst-served point
            far = int(D[np.arange(N), new].argmax())
            new[far] = j
            D[far] = 0.0
        if np.array_equal(new, labels):
            break
        labels = new
        for j in range(k):
            C[j] = P[labels == j].mean(0)
    return labels


def fit_spheres(
    mesh_or_points: Any, n: int, seed: int = 0, samples: int = 2000, shrink: bool = True
) -> list[tuple[np.ndarray, float]]:
    """At most ``n`` spheres ``(centre (3,), radius)`` that together contain every point of
    ``mesh_or_points`` (see :func:`mesh_points`: an (N, 3) array, a mesh with ``.vertices``, or a
    mesh file path), in the points' coordinates and units.

    k-means (NumPy, deterministic for a ``seed``) splits the points into ``n`` clusters (fewer
    when there are fewer distinct points); each sphere is centred at its cluster's centroid with
    the distance of its farthest point as radius. ``shrink`` then hands each point to the
    smallest sphere that already contains it and shrinks the radii to what they still hold, until
    nothing changes (no radius ever grows, no sphere is left empty). For a mesh with faces, each
    triangle then goes whole into the sphere it makes grow least, so the spheres contain the whole
    surface, not only the sampled points. Spheres are sorted by radius, largest first.
    """
    k = as_index(n, f"n must be a whole number >= 1, not {n!r}")
    if k < 1:
        raise GeometryError(f"n must be >= 1, got {k}")
    obj = _load(mesh_or_points)
    P = mesh_points(obj, samples=samples, seed=seed)
    k = min(k, len(np.unique(P, axis=0)))
    from symkin.core.sizes import room

    room(16.0 * len(P) * k, f"fitting {k} spheres to {len(P)} points (their distances)", GeometryError)
    labels = _kmeans(P, k, np.random.default_rng(seed)) if k > 1 else np.zeros(len(P), dtype=int)
    C = np.array([P[labels == j].mean(0) for j in range(k)])
    D = np.sqrt(((P[:, None, :] - C[None]) ** 2).sum(2))  # (N, k)
    rows = np.arange(len(P))
    r = np.array([D[labels == j, j].max() for j in range(k)])
    if shrink:
        for _ in range(50):
            inside = r[None, :] >= D
            # each point to the smallest sphere holding it (its own always does)
            new = np.where(inside, r[None, :], np.inf).argmin(1)
            empty = np.bincount(new, minlength=k) == 0
            while empty.any():  # a sphere left with nothing keeps its own points: n spheres stay
                back = empty[labels]
                new[back] = labels[back]
                empty = np.bincount(new, minlength=k) == 0
            r_new = np.zeros(k)
            np.maximum.at(r_new, new, D[rows, new])
            done = np.array_equal(new, labels)
            labels, r = new, r_new
            if done:
                break
    tri = _triangles(obj)
    if tri is not None:
        # a mesh: each triangle (split to a quarter of the median radius) goes whole into the sphere
        # it grows least (a ball holding a triangle's corners holds the triangle), so the whole
        # surface is covered, not only the samples
        tri = _subdivide(tri, 0.25 * float(np.median(r)) if r.max() > 0 else np.inf)
        need = np.sqrt(((tri[:, :, None, :] - C[None, None]) ** 2).sum(-1)).max(1)  # (F, k)
        pick = np.maximum(need - r[None, :], 0.0).argmin(1)
        np.maximum.at(r, pick, need[np.arange(len(tri)), pick])
    # a hair of margin so the cover survives rounding when distances are recomputed elsewhere
    r = r * (1 + 1e-9) + 1e-12
    order = np.argsort(-r, kind="stable")
    return [(C[j].copy(), float(r[j])) for j in order]
