"""Spheres that cover a body's surface exactly, as few as a stated outward excess allows.

:func:`cover_spheres` takes the closed triangle meshes of one rigid body (in one frame; a mesh may
be swept along a straight stroke, like a gripper finger over its travel) and a maximum outward
excess ``e`` (metres), and returns spheres such that

- **coverage is exact**: the surface is cut into convex pieces (triangles split until every edge
  is at most ``e / 2``; a swept mesh into prisms of those triangles over stroke steps of at most
  ``e / 2``) and every piece lies whole inside one sphere, all its corners within the radius (a
  ball is convex, so it then holds the whole piece): every point of the surface is inside a
  sphere, not only sampled ones;
- **the outward excess is bounded**: a sphere of radius ``r`` centred at depth ``d`` inside the
  solid (``d`` the distance from the centre to the surface, the centre inside by its winding
  number) holds the ball of radius ``d`` about its centre, which lies in the solid, so no point of
  the sphere is farther than ``r - d`` from the solid; every sphere has ``r - d <= e`` (for a convex
  solid ``r - d`` is the sphere's exact excess, for others an upper bound);
- **few spheres**: candidates are the points of a grid inside the solid, each with the largest
  radius its depth allows (``d + e``), and a greedy set cover (Chvatal, A greedy heuristic for the
  set-covering problem, Mathematics of Operations Research, 1979) picks the one holding the most
  pieces not yet held until every piece is held; spheres whose pieces the others hold are dropped,
  and each radius shrinks to the farthest corner of the pieces it alone is given. A piece no grid
  candidate holds gets a sphere about its own centroid (radius at most ``e``).

The cover is of the surface (as coal's and FCL's mesh checks, which test triangles): a solid that
meets the body's solid meets its surface or lies wholly inside it. Deterministic: the same input
gives the same spheres.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from symkin.errors import GeometryError
from symkin.geometry.triangles import closest_distance, pieces, winding_number

__all__ = ["Surface", "Cover", "cover_spheres", "outer_excess"]

_MEDIAL = 2000  # points on the medial axis among them
_CANDIDATES = 3000  # grid points inside the solid the greedy cover chooses from (about)
_PIECE = 0.5  # longest piece edge, in units of the excess
_SLACK = 1e-9  # relative and absolute hair on radii so the cover survives rounding elsewhere


@dataclass(frozen=True)
class Surface:
    """A closed triangle mesh ``triangles`` (F, 3, 3) in the body's frame (metres), wound
    outward; with ``stroke`` (3,), the mesh at every offset ``t * stroke``, 0 <= t <= 1."""

    triangles: np.ndarray
    stroke: np.ndarray | None = None
    name: str = ""

    def instances(self, step: float) -> list[np.ndarray]:
        """The mesh at stroke offsets no more than ``step`` apart (just the mesh without a stroke)."""
        if self.stroke is None:
            return [self.triangles]
        n = max(1, math.ceil(float(np.linalg.norm(self.stroke)) / step))
        return [self.triangles + t * self.stroke for t in np.linspace(0.0, 1.0, n + 1)]


@dataclass(frozen=True)
class Cover:
    """Spheres covering one body: ``centres`` (S, 3), ``radii`` (S,), ``excess`` (S,), each
    sphere's bound ``r - d`` on how far it reaches out of the solid, ``pieces`` the number of convex
    pieces of the surface each held whole by a sphere."""

    centres: np.ndarray
    radii: np.ndarray
    excess: np.ndarray
    pieces: int

    def __len__(self) -> int:
        return len(self.radii)


def _check(surfaces: Sequence[Surface], max_excess: float) -> float:
    e = float(max_excess)
    if not math.isfinite(e) or e <= 0:
        raise GeometryError(f"max_excess must be a finite length > 0 (metres), got {max_excess!r}")
    if not surfaces:
        raise GeometryError("no surface to cover")
    for s in surfaces:
        T = np.asarray(s.triangles)
        if T.ndim != 3 or T.shape[1:] != (3, 3) or len(T) == 0:
            raise GeometryError(
                f"surface {s.name!r}: triangles must have shape (F, 3, 3), F >= 1, got {T.shape}"
            )
        if not np.isfinite(T).all():
            raise GeometryError(f"surface {s.name!r}: triangles contain NaN or inf")
    return e


def _depths(C: np.ndarray, surfaces: Sequence[Surface], step: float) -> np.ndarray:
    """Per point of C (N, 3), its depth inside the body's solid: the largest distance to the
    surface of a mesh instance whose winding number says the point is inside it; -inf outside all."""
    depth = np.full(len(C), -np.inf)
    for s in surfaces:
        for T in s.instances(step):
            lo, hi = T.reshape(-1, 3).min(0), T.reshape(-1, 3).max(0)
            near = np.flatnonzero(((lo <= C) & (hi >= C)).all(1))
            if not len(near):
                continue
            inside = near[winding_number(C[near], T) > 0.5]
            if len(inside):
                depth[inside] = np.maximum(depth[inside], closest_distance(C[inside], T))
    return depth


def _grid(surfaces: Sequence[Surface], step: float, count: int) -> tuple[np.ndarray, np.ndarray]:
    """Grid points inside the solid (about ``count``) and their depths."""
    pts = np.concatenate([T.reshape(-1, 3) for s in surfaces for T in s.instances(step)])
    lo, hi = pts.min(0), pts.max(0)
    ext = hi - lo
    spacing = max(
        float(np.prod(np.maximum(ext, 1e-12)) / (2 * count)) ** (1 / 3), float(ext.max()) / 200, 1e-9
    )
    G = np.zeros((0, 3))
    keep = np.zeros(0, dtype=bool)
    d = np.zeros(0)
    for _ in range(8):
        axes = [np.arange(lo[i] + spacing / 2, hi[i], spacing) for i in range(3)]
        axes = [a if len(a) else np.array([(lo[i] + hi[i]) / 2]) for i, a in enumerate(axes)]
        G = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, 3)
        d = _depths(G, surfaces, step)
        keep = d > 0
        if keep.sum() >= count / 2 or len(G) > 20 * count:
            break
        spacing /= 1.5
    return G[keep], d[keep]


def _medial(surfaces: Sequence[Surface], count: int, seed: int = 0) -> np.ndarray:
    """Centres of maximal inner balls (about ``count``, on the medial axis): from points drawn on
    each mesh, inward along the face normal as far as the ball touching there stays inside (a
    bisection on ``dist(p - t n) >= t``: the balls grow nested, so once the surface enters one it
    stays in)."""
    total = sum(len(s.triangles) for s in surfaces)
    out = []
    rng = np.random.default_rng(seed)
    for s in surfaces:
        T = s.triangles
        k = max(8, int(count * len(T) / max(total, 1)))
        nrm = np.cross(T[:, 1] - T[:, 0], T[:, 2] - T[:, 0])
        area = np.linalg.norm(nrm, axis=1)
        ok = area > 1e-18
        if not ok.any():
            continue
        T, nrm, area = T[ok], nrm[ok] / area[ok, None], area[ok]
        pick = rng.choice(len(T), size=k, p=area / area.sum())
        u, v = rng.random(k), rng.random(k)
        flip = u + v > 1
        u[flip], v[flip] = 1 - u[flip], 1 - v[flip]
        t = T[pick]
        P = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
        N = nrm[pick]  # outward for a mesh wound outward
        span = float(np.ptp(T.reshape(-1, 3), axis=0).max())
        lo, hi = np.zeros(k), np.full(k, span)
        for _ in range(16):
            mid = 0.5 * (lo + hi)
            inside = closest_distance(P - mid[:, None] * N, T) >= mid * (1 - 1e-9)
            lo, hi = np.where(inside, mid, lo), np.where(inside, hi, mid)
        out.append(P - lo[:, None] * N)
    return np.concatenate(out) if out else np.zeros((0, 3))


def _far(P: np.ndarray, C: np.ndarray) -> np.ndarray:
    """(K, J) distance from centre j to the farthest corner of piece k."""
    out = np.empty((len(P), len(C)))
    step = max(1, (1 << 22) // max(1, len(C) * P.shape[1]))
    for i in range(0, len(P), step):
        D = np.sqrt(((P[i : i + step, :, None, :] - C[None, None]) ** 2).sum(-1))
        out[i : i + step] = D.max(1)
    return out


def _holders(P: np.ndarray, C: np.ndarray, R: np.ndarray) -> list[np.ndarray]:
    """Per candidate j (centre C[j], radius R[j]), the pieces of P (K, m, 3) it holds whole."""
    mid = P.mean(1)
    reach = np.sqrt(((P - mid[:, None]) ** 2).sum(-1)).max(1)  # corner spread of each piece
    size = float(R.max() + reach.max()) if len(R) else 1.0
    cell = np.floor(mid / size).astype(np.int64)
    order = np.lexsort(cell.T[::-1])
    keys, start = np.unique(cell[order], axis=0, return_index=True)
    ends = [*start[1:], len(order)]
    bucket = {tuple(k): order[i0:i1] for k, i0, i1 in zip(keys.tolist(), start, ends)}
    offsets = [(i, j, k) for i in (-1, 0, 1) for j in (-1, 0, 1) for k in (-1, 0, 1)]
    out: list[np.ndarray] = [np.zeros(0, dtype=np.int64)] * len(C)
    home = np.floor(C / size).astype(np.int64)
    for key in {tuple(h) for h in home.tolist()}:  # candidates of one cell share their neighbours
        mine = np.flatnonzero((home == key).all(1))
        near = [bucket[n] for o in offsets if (n := (key[0] + o[0], key[1] + o[1], key[2] + o[2])) in bucket]
        if not near:
            continue
        idx = np.concatenate(near)
        for j0 in range(0, len(mine), 64):
            js = mine[j0 : j0 + 64]
            D = np.sqrt(((mid[idx, None, :] - C[None, js]) ** 2).sum(-1)) - reach[idx, None]  # (n, J)
            for col, j in enumerate(js):
                cand = idx[D[:, col] <= R[j]]
                if len(cand):
                    cand = cand[np.sqrt(((P[cand] - C[j]) ** 2).sum(-1)).max(1) <= R[j]]
                out[j] = np.sort(cand)
    return out


def _greedy(holds: list[np.ndarray], K: int) -> list[int]:
    """Chvatal's greedy set cover: candidate indices whose sets cover range(K)."""
    counts = np.array([len(h) for h in holds])
    piece = np.concatenate(holds) if holds else np.zeros(0, dtype=int)
    cand = np.repeat(np.arange(len(holds)), counts)
    covered = np.zeros(K, dtype=bool)
    chosen: list[int] = []
    while not covered.all():
        j = int(np.argmax(counts))
        if counts[j] == 0:
            raise GeometryError("internal: a piece no candidate holds")
        chosen.append(j)
        fresh = np.zeros(K, dtype=bool)
        fresh[holds[j]] = True
        fresh &= ~covered
        covered |= fresh
        hit = fresh[piece]
        counts -= np.bincount(cand[hit], minlength=len(holds))
        piece, cand = piece[~hit], cand[~hit]
    return chosen


def _by_piece(holds: list[np.ndarray], K: int) -> tuple[np.ndarray, np.ndarray]:
    """The inverse of ``holds`` as CSR: the candidates holding piece k are
    ``cands[ptr[k]:ptr[k + 1]]``."""
    counts = np.array([len(h) for h in holds])
    piece = np.concatenate(holds) if holds else np.zeros(0, dtype=int)
    cand = np.repeat(np.arange(len(holds)), counts)
    order = np.argsort(piece, kind="stable")
    ptr = np.searchsorted(piece[order], np.arange(K + 1))
    return ptr, cand[order]


def _prune(holds: list[np.ndarray], chosen: list[int], K: int) -> list[int]:
    """Drop chosen sets whose pieces the other chosen sets hold, smallest sets first."""
    cnt = np.zeros(K, dtype=int)
    for j in chosen:
        cnt[holds[j]] += 1
    keep = list(chosen)
    for j in sorted(chosen, key=lambda j: (len(holds[j]), j)):
        if (cnt[holds[j]] >= 2).all():
            cnt[holds[j]] -= 1
            keep.remove(j)
    return keep


def _merge_pairs(
    holds: list[np.ndarray], chosen: list[int], K: int, C: np.ndarray, R: np.ndarray
) -> list[int]:
    """Local search: replace two chosen sets by one candidate holding every piece only they hold,
    while such a pair exists (nearest pairs first)."""
    ptr, cands = _by_piece(holds, K)
    keep = list(chosen)
    improved = True
    while improved and len(keep) > 1:
        improved = False
        cnt = np.zeros(K, dtype=int)
        for j in keep:
            cnt[holds[j]] += 1
        S = np.array(keep)
        D = np.sqrt(((C[S][:, None] - C[S][None]) ** 2).sum(-1)) - R[S][:, None] - R[S][None]
        pairs = [(D[a, b], a, b) for a in range(len(S)) for b in range(a + 1, len(S)) if D[a, b] < 0]
        for _, a, b in sorted(pairs):
            i, j = S[a], S[b]
            mine = np.zeros(K, dtype=int)
            mine[holds[i]] += 1
            mine[holds[j]] += 1
            U = np.flatnonzero((mine > 0) & (cnt == mine))  # pieces only i and j hold
            if not len(U):
                continue
            entries = np.concatenate([cands[ptr[k] : ptr[k + 1]] for k in U])
            votes = np.bincount(entries, minlength=len(holds))
            full = np.flatnonzero(votes == len(U))
            if not len(full):
                continue
            best = int(full[np.argmax([len(holds[f]) for f in full])])
            keep = [x for x in keep if x not in (i, j)] + [best]
            improved = True
            break
    return keep


def cover_spheres(surfaces: Sequence[Surface], max_excess: float) -> Cover:
    """Spheres (module docstring) covering every point of ``surfaces`` (one rigid body, one
    frame, metres), each reaching at most ``max_excess`` out of the solid, as few as the greedy
    cover finds; largest first."""
    e = _check(surfaces, max_excess)
    h = e * _PIECE
    if any(s.stroke is not None for s in surfaces):
        P = _mixed(surfaces, h)
    else:
        P = np.concatenate([pieces(s.triangles, h) for s in surfaces])
    G, d = _grid(surfaces, h, _CANDIDATES)
    M = _medial(surfaces, _MEDIAL)
    if len(M):
        dm = _depths(M, surfaces, h)
        G, d = np.concatenate([G, M[dm > 0]]), np.concatenate([d, dm[dm > 0]])
    R = d + e
    holds = _holders(P, G, R)
    held = np.zeros(len(P), dtype=bool)
    for hset in holds:
        held[hset] = True
    if not held.all():  # pieces in corners the grid misses: a sphere about each one's centroid
        lone = np.flatnonzero(~held)
        mid = P[lone].mean(1)
        G = np.concatenate([G, mid])
        d = np.concatenate([d, np.zeros(len(lone))])
        r = np.sqrt(((P[lone] - mid[:, None]) ** 2).sum(-1)).max(1)
        R = np.concatenate([R, r])
        holds += [np.array([k]) for k in lone]
    chosen = _prune(holds, _greedy(holds, len(P)), len(P))
    chosen = _prune(holds, _merge_pairs(holds, chosen, len(P), G, R), len(P))
    C, Rc, dc = G[chosen], R[chosen], d[chosen]
    far = _far(P, C)  # (K, S)
    # each piece to the smallest sphere that holds it; radii shrink to what they then hold
    r = Rc.copy()
    for _ in range(20):
        fits = far <= r[None, :] * (1 + 1e-12)
        owner = np.where(fits, r[None, :], np.inf).argmin(1)
        r_new = np.zeros(len(C))
        np.maximum.at(r_new, owner, far[np.arange(len(P)), owner])
        if np.array_equal(r_new, r):
            break
        r = r_new
    used = r > 0
    C, r, dc = C[used], r[used], dc[used]
    r = r * (1 + _SLACK) + _SLACK
    order = np.lexsort((C[:, 2], C[:, 1], C[:, 0], -r))
    return Cover(C[order], r[order], (r - dc)[order], len(P))


def _mixed(surfaces: Sequence[Surface], h: float) -> np.ndarray:
    """Pieces of surfaces with and without strokes: triangles padded to six corners by repeating
    them (a triangle is its own prism of zero stroke)."""
    out = []
    for s in surfaces:
        X = pieces(s.triangles, h, s.stroke)
        out.append(X if X.shape[1] == 6 else np.concatenate([X, X], axis=1))
    return np.concatenate(out)


def outer_excess(
    centres: np.ndarray, radii: np.ndarray, surfaces: Sequence[Surface], per_sphere: int = 400
) -> np.ndarray:
    """Distances from points on the outer boundary of the spheres' union (``per_sphere`` points on
    each sphere, those inside no other sphere) to the body's solid (0 where inside it): how far the
    model reaches out of the real body, sampled. A swept mesh counts at stroke steps of 2 mm, so
    its distances are upper bounds."""
    C = np.asarray(centres, dtype=float).reshape(-1, 3)
    R = np.asarray(radii, dtype=float).reshape(-1)
    k = np.arange(per_sphere) + 0.5
    phi = np.arccos(1 - 2 * k / per_sphere)
    theta = np.pi * (1 + 5**0.5) * k
    U = np.stack([np.cos(theta) * np.sin(phi), np.sin(theta) * np.sin(phi), np.cos(phi)], -1)
    X = (C[:, None, :] + R[:, None, None] * U[None]).reshape(-1, 3)
    owner = np.repeat(np.arange(len(C)), per_sphere)
    D = np.sqrt(((X[:, None, :] - C[None]) ** 2).sum(-1)) - R[None]
    D[np.arange(len(X)), owner] = np.inf
    X = X[(D > -1e-12).all(1)]
    inst = [T for s in surfaces for T in s.instances(0.002)]
    inside = np.zeros(len(X), dtype=bool)
    for T in inst:
        inside |= winding_number(X, T) > 0.5
    out = np.zeros(len(X))
    if (~inside).any():
        out[~inside] = np.min([closest_distance(X[~inside], T) for T in inst], axis=0)
    return out
