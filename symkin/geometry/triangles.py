"""Triangle meshes as NumPy arrays: distances from points to a surface, inside or outside a closed
surface, splitting triangles small, sampling their surface (NumPy only).

A surface is a triangle array ``(F, 3, 3)`` (F triangles, 3 corners, xyz). A *piece* is a convex
set given by its corners ``(K, m, 3)``: a triangle (m = 3) or a triangle swept along a straight
stroke (m = 6, the prism of a gripper finger over its travel); a ball holds a piece exactly when it
holds all its corners, because a ball is convex.
"""

from __future__ import annotations

import numpy as np

__all__ = [
    "closest_distance",
    "winding_number",
    "subdivide",
    "pieces",
    "sample_surface",
]

_CHUNK = 1 << 21  # point-triangle entries per NumPy block (a few tens of MB)


def _point_triangle(p: np.ndarray, T: np.ndarray) -> np.ndarray:
    """Distances (K,) from points p (K, 3) to triangles T (K, 3, 3), pair by pair: the closest
    point on each triangle by its Voronoi regions (Ericson, Real-Time Collision Detection, 2005,
    section 5.1.5)."""
    a, b, c = T[:, 0], T[:, 1], T[:, 2]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = (ab * ap).sum(-1), (ac * ap).sum(-1)
    bp = p - b
    d3, d4 = (ab * bp).sum(-1), (ac * bp).sum(-1)
    cp = p - c
    d5, d6 = (ab * cp).sum(-1), (ac * cp).sum(-1)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    tiny = 1e-300
    # the face region, then each edge and corner region overrides where it applies
    denom = va + vb + vc
    denom = np.where(np.abs(denom) > tiny, denom, tiny)
    v, w = vb / denom, vc / denom
    q = a + v[:, None] * ab + w[:, None] * ac
    e_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    den = (d4 - d3) + (d5 - d6)
    t = (d4 - d3) / np.where(den > tiny, den, tiny)
    q = np.where(e_bc[:, None], b + t[:, None] * (c - b), q)
    e_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    t = d2 / np.where(d2 - d6 > tiny, d2 - d6, tiny)
    q = np.where(e_ac[:, None], a + t[:, None] * ac, q)
    e_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    t = d1 / np.where(d1 - d3 > tiny, d1 - d3, tiny)
    q = np.where(e_ab[:, None], a + t[:, None] * ab, q)
    q = np.where(((d6 >= 0) & (d5 <= d6))[:, None], c, q)
    q = np.where(((d3 >= 0) & (d4 <= d3))[:, None], b, q)
    q = np.where(((d1 <= 0) & (d2 <= 0))[:, None], a, q)
    return np.sqrt(((p - q) ** 2).sum(-1))


def closest_distance(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Distances (N,) from points (N, 3) to the surface of triangles (F, 3, 3) (unsigned, exact up
    to rounding); +inf when there are no triangles. Each point is tested only against the triangles
    whose bounding ball may hold a point nearer than the nearest ball's far side."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    T = np.asarray(triangles, dtype=float).reshape(-1, 3, 3)
    out = np.full(len(P), np.inf)
    if len(T) == 0 or len(P) == 0:
        return out
    mid = T.mean(1)
    rho = np.sqrt(((T - mid[:, None]) ** 2).sum(-1)).max(1)
    step = max(1, _CHUNK // (4 * len(T)))
    for i in range(0, len(P), step):
        p = P[i : i + step]
        D = np.sqrt(((p[:, None, :] - mid[None]) ** 2).sum(-1))  # (n, F)
        bound = (D + rho).min(1)
        ip, it = np.nonzero(D - rho <= bound[:, None])
        d = _point_triangle(p[ip], T[it])
        part = np.full(len(p), np.inf)
        np.minimum.at(part, ip, d)
        out[i : i + step] = part
    return out


def winding_number(points: np.ndarray, triangles: np.ndarray) -> np.ndarray:
    """Generalised winding numbers (N,) of points (N, 3) about a surface (F, 3, 3): the sum of the
    triangles' signed solid angles over 4 pi (Van Oosterom and Strackee, The solid angle of a plane
    triangle, IEEE Trans. Biomedical Engineering, 1983; Jacobson, Kavan and Sorkine-Hornung, Robust
    inside-outside segmentation using generalized winding numbers, 2013): about 1 inside a closed
    surface wound outward (counter-clockwise seen from outside), 0 outside, fractional where the
    surface has holes."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    T = np.asarray(triangles, dtype=float).reshape(-1, 3, 3)
    out = np.zeros(len(P))
    if len(T) == 0:
        return out
    step = max(1, _CHUNK // len(T))
    for i in range(0, len(P), step):
        p = P[i : i + step, None, :]
        a, b, c = T[None, :, 0] - p, T[None, :, 1] - p, T[None, :, 2] - p
        la, lb, lc = (np.sqrt((x * x).sum(-1)) for x in (a, b, c))
        det = (a * np.cross(b, c)).sum(-1)
        den = la * lb * lc + (a * b).sum(-1) * lc + (b * c).sum(-1) * la + (c * a).sum(-1) * lb
        out[i : i + step] = 2.0 * np.arctan2(det, den).sum(axis=1) / (4.0 * np.pi)
    return out


def subdivide(triangles: np.ndarray, max_edge: float, limit: int = 2_000_000) -> np.ndarray:
    """Triangles (F, 3, 3) cut in two at the midpoint of their longest edge until no edge is
    longer than ``max_edge`` (the same surface in smaller pieces; long thin triangles become a row
    of pieces, not a grid of slivers); stops early, leaving longer edges, only when the next round
    would pass ``limit`` triangles."""
    tri = np.asarray(triangles, dtype=float).reshape(-1, 3, 3)
    while len(tri):
        L = np.linalg.norm(tri - np.roll(tri, -1, axis=1), axis=-1)  # edge k runs corner k -> k+1
        k = L.argmax(1)
        big = L[np.arange(len(tri)), k] > max_edge
        if not big.any() or len(tri) + int(big.sum()) > limit:
            break
        t, kb = tri[big], k[big]
        rows = np.arange(len(t))
        p0, p1, p2 = t[rows, kb], t[rows, (kb + 1) % 3], t[rows, (kb + 2) % 3]
        m = (p0 + p1) / 2
        tri = np.concatenate([tri[~big], np.stack((p0, m, p2), 1), np.stack((m, p1, p2), 1)])
    return tri


def pieces(triangles: np.ndarray, max_edge: float, stroke: np.ndarray | None = None) -> np.ndarray:
    """Convex pieces (K, m, 3) whose union is the surface of ``triangles`` (F, 3, 3), each edge at
    most ``max_edge``: the triangles split small (m = 3); with ``stroke`` (a 3-vector), the surface
    swept along the segment from 0 to ``stroke``, as prisms (m = 6) of the split triangles over
    stroke steps of at most ``max_edge``."""
    tri = subdivide(triangles, max_edge)
    if stroke is None:
        return tri
    s = np.asarray(stroke, dtype=float)
    steps = max(1, int(np.ceil(np.linalg.norm(s) / max_edge)))
    cuts = np.linspace(0.0, 1.0, steps + 1)
    out = [np.concatenate([tri + t0 * s, tri + t1 * s], axis=1) for t0, t1 in zip(cuts[:-1], cuts[1:])]
    return np.concatenate(out)


def sample_surface(triangles: np.ndarray, count: int, seed: int = 0) -> np.ndarray:
    """``count`` points (count, 3) drawn uniformly by area on the surface of triangles (F, 3, 3)
    (NumPy's generator with ``seed``)."""
    T = np.asarray(triangles, dtype=float).reshape(-1, 3, 3)
    rng = np.random.default_rng(seed)
    area = 0.5 * np.linalg.norm(np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0]), axis=1)
    total = area.sum()
    p = area / total if total > 0 else np.full(len(T), 1.0 / len(T))
    k = rng.choice(len(T), size=count, p=p)
    u, v = rng.random(count), rng.random(count)
    flip = u + v > 1
    u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
    t = T[k]
    return t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
