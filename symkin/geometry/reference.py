"""The numeric reference for collision queries (NumPy, batched over configurations): shape points in
the base frame, signed distances of the active pairs, their joint-space gradients, collision verdicts.

Link poses come from the tree's O(n) walk (:meth:`symkin.Tree` numeric kinematics, Part 1 eqs 1-5
of Haviland and Corke, Manipulator Differential Kinematics, 2023); a point x fixed to a link moves
with ``dx/dq_j = w_j x (x - o_j)`` for each revolute joint j on the link's path (``w_j`` its axis,
``o_j`` its origin, both in the base frame) and ``w_j`` for a prismatic one (the point Jacobian,
eqs 31-34 with x in place of the end effector). A pair's distance gradient is
``n . (dpa/dq - dpb/dq)`` (``pa``, ``pb`` the closest core points, ``n`` the unit normal from B
to A). The compiled C kernel (:mod:`symkin.emit.collision`) is checked against this module.

The pair math (:func:`evaluate_frames`) takes the geometry as plain numbers (:class:`Tables`):
the generated NumPy collision module (``templates/numpy/collision.py.j2``) holds them as literals
and calls it with its own straight-line link poses.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Any

import numpy as np

from symkin.core.arrays import as_batch
from symkin.geometry import distance as dist
from symkin.geometry.pairs import Layout, as_environment, layout_of
from symkin.model.geometry import Capsule, Environment

__all__ = [
    "points",
    "evaluate",
    "evaluate_frames",
    "collides_frames",
    "distances",
    "distance_jacobians",
    "in_collision",
    "witnesses",
    "Tables",
]


@dataclass(frozen=True)
class Tables:
    """A model's geometry and joints as plain numbers, all the pair math needs.

    Attributes:
        n: number of joints.
        caps: per shape, whether it is a capsule (two points) rather than a sphere (one).
        first: per shape, the index of its first point among the stacked points.
        radius: per shape, its radius (m).
        segment: per shape, the segment whose link carries it (-1: the base link).
        self_pairs: (i, j) shape indices checked against each other.
        joints: per segment, its joint: (q index, multiplier, revolute, axis 0-2, sign), or None.
        ancestors: per segment, the segments with a joint from it up to the base (itself first).
        proved: self pairs proved apart within ``qlim`` (:func:`symkin.geometry.proved_apart`):
            :func:`collides_frames` given the joint values skips them for rows within the limits.
        qlim: the joint limits (lower row, upper row) the proof holds for, or None.
    """

    n: int
    caps: tuple[bool, ...]
    first: tuple[int, ...]
    radius: tuple[float, ...]
    segment: tuple[int, ...]
    self_pairs: tuple[tuple[int, int], ...]
    joints: tuple[tuple[int, float, bool, int, float] | None, ...]
    ancestors: tuple[tuple[int, ...], ...]
    proved: tuple[tuple[int, int], ...] = ()
    qlim: tuple[tuple[float, ...], tuple[float, ...]] | None = None

    @classmethod
    def of(cls, layout: Layout) -> Tables:
        """The tables of ``layout`` (memoised on it)."""
        cached = layout.__dict__.get("_tables")
        if cached is not None:
            return cached
        tree = layout.tree
        num = tree._num
        joints: list[tuple[int, float, bool, int, float] | None] = []
        for k, seg in enumerate(tree.segments):
            s = None if seg.slot is None else tree.slots[seg.slot]
            joints.append(
                None
                if s is None
                else (s.joint, float(s.multiplier), bool(s.revolute), int(num.axis[k]), float(num.sign[k]))
            )
        out = cls(
            n=tree.n,
            caps=tuple(isinstance(s, Capsule) for s in layout.shapes),
            first=layout.point_index,
            radius=tuple(float(s.radius) for s in layout.shapes),
            segment=layout.segment,
            self_pairs=layout.self_pairs,
            joints=tuple(joints),
            ancestors=tuple(
                tuple(a for a in layout.ancestors(k) if joints[a] is not None) for k in range(len(joints))
            ),
        )
        object.__setattr__(layout, "_tables", out)
        return out

    @cached_property
    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """caps (bool), first, radius, segment as arrays."""
        return (
            np.array(self.caps, dtype=bool),
            np.array(self.first, dtype=int),
            np.array(self.radius, dtype=float),
            np.array(self.segment, dtype=int),
        )

    @cached_property
    def self_split(self) -> tuple[tuple, tuple, np.ndarray]:
        """The self pairs for :func:`collides_frames`: two spheres not proved apart (I, J, squared
        radius sums), two spheres proved apart (the same), and the pairs with a capsule (K, 2)."""
        caps, radius = self.arrays[0], self.arrays[2]
        proved = set(self.proved)

        def spheres(pairs: list[tuple[int, int]]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
            P = np.array(pairs, dtype=int).reshape(-1, 2)
            return P[:, 0], P[:, 1], (radius[P[:, 0]] + radius[P[:, 1]]) ** 2

        two = [p for p in self.self_pairs if not caps[p[0]] and not caps[p[1]]]
        others = [p for p in self.self_pairs if caps[p[0]] or caps[p[1]]]
        return (
            spheres([p for p in two if p not in proved]),
            spheres([p for p in two if p in proved]),
            np.array(others, dtype=int).reshape(-1, 2),
        )


def _shape_points(layout: Layout, L: np.ndarray) -> list[np.ndarray]:
    """Per shape, its points in the base frame, (N, k, 3) with k = 1 (sphere) or 2 (capsule)."""
    out = []
    for s, k in zip(layout.shapes, layout.segment):
        local = np.array(s.points)  # (k, 3)
        if k < 0:
            out.append(np.broadcast_to(local, (L.shape[0], *local.shape)).copy())
        else:
            out.append(np.einsum("Nij,kj->Nki", L[:, k, :3, :3], local) + L[:, k, None, :3, 3])
    return out


def points(model: Any, q: Any) -> np.ndarray:
    """Base-frame points of the geometry, (P, 3) or (N, P, 3): each sphere's centre and each
    capsule's two segment ends, in shape order."""
    layout = layout_of(model)
    Q, single = as_batch(q, layout.tree.n, layout.tree.name)
    L, _ = layout.tree._walk(Q)
    X = np.concatenate(_shape_points(layout, L), axis=1)
    return X[0] if single else X


def _pair_kinds(X: np.ndarray, tab: tuple, I: np.ndarray, J: np.ndarray) -> tuple:
    """(d, n, pa, pb) of shapes I against shapes J (index arrays of one length), vectorised."""
    caps, first, radius, _ = tab
    N, K = X.shape[0], len(I)
    d, n, pa, pb = np.empty((N, K)), np.empty((N, K, 3)), np.empty((N, K, 3)), np.empty((N, K, 3))
    for ci in (False, True):
        for cj in (False, True):
            m = np.nonzero((caps[I] == ci) & (caps[J] == cj))[0]
            if not m.size:
                continue
            i, j = I[m], J[m]
            A, B = X[:, first[i]], X[:, first[j]]
            if ci and cj:
                res = dist.capsule_capsule(A, X[:, first[i] + 1], radius[i], B, X[:, first[j] + 1], radius[j])
            elif ci:
                res = dist.capsule_sphere(A, X[:, first[i] + 1], radius[i], B, radius[j])
            elif cj:
                dd, nn, qb, qa = dist.capsule_sphere(B, X[:, first[j] + 1], radius[j], A, radius[i])
                res = (dd, -nn, qa, qb)
            else:
                res = dist.sphere_sphere(A, radius[i], B, radius[j])
            d[:, m], n[:, m], pa[:, m], pb[:, m] = res
    return d, n, pa, pb


def _obstacles(X: np.ndarray, tab: tuple, env: Environment) -> list[tuple]:
    """Per obstacle kind: (d, n, pa) (N, O, S...) of every shape against every obstacle."""
    caps, first, radius, _ = tab
    S = len(caps)
    out = []
    sph, cap = np.nonzero(~caps)[0], np.nonzero(caps)[0]
    arrays = env.arrays()
    for kind in ("spheres", "capsules", "boxes"):
        O = arrays[kind]
        if not len(O):
            continue
        N = X.shape[0]
        d, n, pa = np.empty((N, len(O), S)), np.empty((N, len(O), S, 3)), np.empty((N, len(O), S, 3))
        for idx, is_cap in ((sph, False), (cap, True)):
            if not idx.size:
                continue
            A = X[:, None, first[idx]]  # (N, 1, K, 3)
            B = X[:, None, first[idx] + 1] if is_cap else None
            r = radius[idx]
            if kind == "spheres":
                c, ro = O[None, :, None, :3], O[None, :, None, 3]
                res = dist.capsule_sphere(A, B, r, c, ro) if is_cap else dist.sphere_sphere(A, r, c, ro)
            elif kind == "capsules":
                a, b, ro = O[None, :, None, :3], O[None, :, None, 3:6], O[None, :, None, 6]
                if is_cap:
                    res = dist.capsule_capsule(A, B, r, a, b, ro)
                else:
                    dd, nn, qb, qa = dist.capsule_sphere(a, b, ro, A, r)
                    res = (dd, -nn, qa, qb)
            else:
                c, h, R = (
                    O[None, :, None, :3],
                    O[None, :, None, 3:6],
                    O[None, :, None, 6:].reshape(1, -1, 1, 3, 3),
                )
                res = dist.capsule_box(A, B, r, c, h, R) if is_cap else dist.sphere_box(A, r, c, h, R)
            d[:, :, idx], n[:, :, idx], pa[:, :, idx] = res[0], res[1], res[2]
        M = len(O) * S  # spelled out: reshape cannot infer it for N = 0
        out.append((d.reshape(N, M), n.reshape(N, M, 3), pa.reshape(N, M, 3)))
    return out


def _gradients(tab: Tables, P: np.ndarray, seg: np.ndarray, p: np.ndarray, n: np.ndarray,
               G: np.ndarray, sign: float) -> None:  # fmt: skip
    """Add ``sign * n . dp/dq`` to G (N, M, nq) for points p (N, M, 3) fixed to the links of
    ``seg`` (M,); P (N, S, 3 or 4, 4): each segment's frame just before its joint."""
    for k in np.unique(seg):
        if k < 0:
            continue
        m = np.nonzero(seg == k)[0]
        pk, nk = p[:, m], n[:, m]
        for a in tab.ancestors[k]:
            joint, mult, revolute, axis, sgn = tab.joints[a]  # type: ignore[misc]
            w = P[:, a, None, :3, axis] * sgn  # (N, 1, 3)
            col = np.cross(w, pk - P[:, a, None, :3, 3]) if revolute else np.broadcast_to(w, pk.shape)
            G[:, m, joint] += sign * mult * np.einsum("Nmi,Nmi->Nm", nk, col)


def evaluate_frames(
    tab: Tables, X: np.ndarray, P: np.ndarray, env: Any = None, jacobians: bool = False
) -> tuple[np.ndarray, Any]:
    """Signed distances (N, M) of every active pair, in :meth:`Layout.pair_labels` order (self pairs,
    then each obstacle sphere, capsule, box against every shape), and with ``jacobians`` their
    gradients (N, M, n), from the shape points X (N, P, 3) and the joint frames P (N, S, 3 or 4,
    4) of N configurations."""
    env = as_environment(env)
    arrays = tab.arrays
    N = X.shape[0]
    pairs = np.array(tab.self_pairs, dtype=int).reshape(-1, 2)
    ds, gs = [], []
    if len(pairs):
        d, n, pa, pb = _pair_kinds(X, arrays, pairs[:, 0], pairs[:, 1])
        ds.append(d)
        if jacobians:
            G = np.zeros((N, len(pairs), tab.n))
            _gradients(tab, P, arrays[3][pairs[:, 0]], pa, n, G, 1.0)
            _gradients(tab, P, arrays[3][pairs[:, 1]], pb, n, G, -1.0)
            gs.append(G)
    for d, n, pa in _obstacles(X, arrays, env):
        ds.append(d)
        if jacobians:
            G = np.zeros((N, d.shape[1], tab.n))
            _gradients(tab, P, np.tile(arrays[3], d.shape[1] // len(arrays[3])), pa, n, G, 1.0)
            gs.append(G)
    D = np.concatenate(ds, axis=1) if ds else np.zeros((N, 0))
    J = (np.concatenate(gs, axis=1) if gs else np.zeros((N, 0, tab.n))) if jacobians else None
    return D, J


CHUNK = 2048  # configurations per step of collides_frames (its (chunk, pairs, 3) temporaries)


def collides_frames(tab: Tables, X: np.ndarray, env: Any = None, Q: np.ndarray | None = None) -> np.ndarray:
    """Whether any active pair overlaps, (N,) bools, from the shape points X (N, P, 3): the
    verdicts of ``evaluate_frames(...)[0] < 0`` with less work. Two spheres are compared by their
    squared distance against the squared sum of their radii (as the C kernel does; no normals, no
    closest points); a pair with a capsule or a box is measured. Given the joint values Q (N, n),
    the pairs ``tab.proved`` are tried only for the rows outside ``tab.qlim`` (the same verdicts:
    within the limits they cannot meet)."""
    env = as_environment(env)
    arrays = tab.arrays
    caps, first, radius, _ = arrays
    (I, J, rr), (I2, J2, rr2), others = tab.self_split
    outside = None  # every row tries the proved pairs, unless Q says which are within the limits
    if len(I2) and Q is not None and tab.qlim is not None:
        lo, hi = np.asarray(tab.qlim, dtype=float)
        outside = ~((lo <= Q) & (hi >= Q)).all(axis=1)  # NaN rows too
    sph = np.nonzero(~caps)[0]
    O = env.arrays()["spheres"]
    rro = (radius[sph][:, None] + O[None, :, 3]) ** 2  # (K, M)
    # measured: capsule shapes against obstacle spheres, every shape against capsules and boxes
    measured = Environment(env.spheres if caps.any() else (), env.capsules, env.boxes)
    hit = np.zeros(X.shape[0], dtype=bool)
    for start in range(0, X.shape[0], CHUNK):
        Y = X[start : start + CHUNK]
        h = np.zeros(Y.shape[0], dtype=bool)
        if len(I):
            h |= (_squared(Y[:, first[I]] - Y[:, first[J]]) < rr).any(axis=1)
        if len(I2):
            rows = slice(None) if outside is None else np.flatnonzero(outside[start : start + CHUNK])
            Z = Y[rows]
            if len(Z):
                h[rows] |= (_squared(Z[:, first[I2]] - Z[:, first[J2]]) < rr2).any(axis=1)
        if len(others):
            h |= (_pair_kinds(Y, arrays, others[:, 0], others[:, 1])[0] < 0).any(axis=1)
        if len(O) and len(sph):
            d2 = _squared(Y[:, first[sph], None, :] - O[None, None, :, :3])  # (n, K, M)
            h |= (d2 < rro).any(axis=(1, 2))
        for d, _, _ in _obstacles(Y, arrays, measured):
            h |= (d < 0).any(axis=1)
        hit[start : start + CHUNK] = h
    return hit


def _squared(v: np.ndarray) -> np.ndarray:
    """Squared length over the last axis."""
    return np.einsum("...i,...i->...", v, v)


def evaluate(model: Any, q: Any, env: Any = None, jacobians: bool = False) -> tuple[np.ndarray, Any, bool]:
    """:func:`evaluate_frames` on the link poses of the tree's numeric walk; ``single`` says whether
    q was one configuration."""
    layout = layout_of(model)
    tree = layout.tree
    Q, single = as_batch(q, tree.n, tree.name)
    L, P = tree._walk(Q)
    X = np.concatenate(_shape_points(layout, L), axis=1)
    D, J = evaluate_frames(Tables.of(layout), X, P, env, jacobians)
    return D, J, single


def distances(model: Any, q: Any, env: Any = None) -> np.ndarray:
    """Signed distance (m) of each active pair, (M,) or (N, M); negative when shapes overlap."""
    D, _, single = evaluate(model, q, env)
    return D[0] if single else D


def distance_jacobians(model: Any, q: Any, env: Any = None) -> tuple[np.ndarray, np.ndarray]:
    """Signed distances (M,) and their gradients d d / d q (M, n); batched: (N, M), (N, M, n)."""
    D, J, single = evaluate(model, q, env, jacobians=True)
    return (D[0], J[0]) if single else (D, J)


def in_collision(model: Any, q: Any, env: Any = None) -> bool | np.ndarray:
    """Whether any active pair overlaps (signed distance < 0): a bool, or (N,) bools for a batch."""
    D, _, single = evaluate(model, q, env)
    hit = (D < 0).any(axis=1)
    return bool(hit[0]) if single else hit


def witnesses(
    model: Any, X: Any, pairs: Sequence[tuple[str, int, int]], env: Any = None
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The signed distances (K,) and witness points (K, 3), (K, 3) of the active pairs ``pairs``
    (labels as :meth:`Layout.pair_labels` gives them: ("self", i, j) or (obstacle kind, shape i,
    obstacle k)) at the shape points X (P, 3) of one configuration: ``wa`` on the surface of the
    pair's shape i, ``wb`` on the surface of its shape j or obstacle, ``wa - wb = d n`` (``n`` the
    unit normal from B to A of :mod:`symkin.geometry.distance`; ``wa = pa - r_A n`` with ``pa`` the
    closest point of A's core), so ``|wa - wb| = |d|``: the closest points of shapes apart, the
    deepest of shapes that overlap."""
    layout = layout_of(model)
    env = as_environment(env)
    arrays = Tables.of(layout).arrays
    radius = arrays[2]
    X1 = np.asarray(X, dtype=float).reshape(1, -1, 3)
    K = len(pairs)
    d, n, pa = np.empty(K), np.empty((K, 3)), np.empty((K, 3))
    kinds = {"sphere": "spheres", "capsule": "capsules", "box": "boxes"}
    for m, (kind, i, j) in enumerate(pairs):
        if kind == "self":
            dd, nn, aa, _ = _pair_kinds(X1, arrays, np.array([i]), np.array([j]))
            d[m], n[m], pa[m] = dd[0, 0], nn[0, 0], aa[0, 0]
        else:
            one = Environment(**{kinds[kind]: (getattr(env, kinds[kind])[j],)})
            dd, nn, aa = _obstacles(X1, arrays, one)[0]
            d[m], n[m], pa[m] = dd[0, i], nn[0, i], aa[0, i]
    idx = np.array([i for _, i, _ in pairs], dtype=int)
    wa = pa - radius[idx, None] * n
    return d, wa, wa - d[:, None] * n
