"""Exact signed distances between collision primitives (NumPy, vectorised over batches).

Shapes
------
- sphere: centre ``c`` (..., 3), radius ``r`` (...).
- capsule: segment ``a``-``b`` (..., 3), radius ``r`` (...): every point within ``r`` of the segment.
  A zero-length segment is a sphere.
- box: centre ``center`` (..., 3), half extents ``h`` (..., 3), rotation ``R`` (..., 3, 3) whose
  columns are the box axes in world coordinates (``world = center + R @ local``).

Every argument broadcasts over leading batch dimensions; nothing loops over the batch in Python.

Conventions
-----------
A pair function ``<kind A>_<kind B>(A..., B...)`` returns ``(d, n, pa, pb)``:

- ``d`` (...): the signed distance between the shapes, negative when they overlap (minus the
  penetration depth);
- ``n`` (..., 3): the unit normal pointing from B toward A: moving A by a small displacement ``e``
  changes ``d`` by ``n . e`` to first order (moving B by ``e`` changes it by ``-n . e``);
- ``pa`` (..., 3): the point of A's core where the minimum is attained (the sphere's centre, the
  closest point of the capsule's segment);
- ``pb`` (..., 3): likewise on B's core (sphere centre, closest segment point); for a box, the point
  of the box surface nearest to ``pa``: ``pb = pa - sdf(pa) n`` (when ``pa`` is inside the box, the
  point of its nearest face, ``|sdf|`` from ``pa`` in the direction ``n``).

So ``d = n . (pa - pb) - rA - rB`` (``rB = 0`` for a box), and with ``pa`` and ``pb`` fixed to their
bodies the derivative of the distance under any motion is ``d' = n . (pa' - pb')``.

Degenerate cases are resolved deterministically: a segment whose squared length is at most
``SEG_EPS`` is a point (parameter 0); (nearly) parallel segments take ``s = 0`` and then Ericson's
clamping rules; core points closer than ``DIST_EPS`` (the normal is undefined) get ``n = (0, 0, 1)``;
a point equally close to several box faces takes the face of the lowest axis index.

One case where ``n . e`` is not the first-order change of ``d``: when a capsule's deepest point in
a box lies where two faces are equally deep (a kink of the piecewise-linear SDF along the segment:
the usual case for a capsule crossing the box's interior away from its ends), ``d`` is still
differentiable, but its gradient is a convex combination of the two faces' normals, shorter than 1
(``(a1 n2 - a2 n1) / (a1 - a2)``, ``a1 > 0 > a2`` the two faces' SDF slopes along the segment);
``n`` is the unit normal of one of the two faces (which one depends on rounding). The two faces may
be opposite ones: a capsule piercing a thin box through both of its large faces is ``h_k + r``
deep, whatever its small motions, and ``n`` is one of the two faces' normals.

Algorithms: segment-segment closest points after Ericson, Real-Time Collision Detection (2005),
5.1.9, written once for any array library (:class:`SegmentOps`: the CasADi and JAX/PyTorch
distances run the same code); the box's exact signed distance field in box coordinates (``q = |x| - h``,
``sdf = |max(q, 0)| + min(max_j q_j, 0)``); capsule-box minimises the box SDF along the segment (a
convex function of the segment parameter) by golden-section search with a fixed number of
iterations (``GOLDEN_ITERS``; on a tie both ends of the bracket move in, so that a flat stretch of
minima ends inside rather than on a kink at its edge), then compares the segment's endpoints.

The C header ``symkin/runtime/csrc/symkin_collide.h`` implements the same algorithms with the same
constants and the same order of floating-point operations, one pair at a time, so that compiled
without contraction (``-ffp-contract=off``) it agrees with this module to rounding (in practice
bit for bit).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "SegmentOps",
    "segment_closest",
    "segment_closest_with",
    "point_segment",
    "point_segment_with",
    "golden_min_with",
    "box_sdf",
    "sphere_sphere",
    "capsule_sphere",
    "capsule_capsule",
    "sphere_box",
    "capsule_box",
    "SEG_EPS",
    "PAR_EPS",
    "DIST_EPS",
    "GOLDEN_ITERS",
]

Array = NDArray[np.float64]
PairResult = tuple[Array, Array, Array, Array]

SEG_EPS = 1e-24
"""A segment whose squared length is at most this is treated as a point."""
PAR_EPS = 1e-14
"""Two segments are parallel when ``|d1|^2 |d2|^2 - (d1.d2)^2 <= PAR_EPS |d1|^2 |d2|^2``."""
DIST_EPS = 1e-15
"""Core points closer than this are coincident: the normal is then ``(0, 0, 1)``."""
GOLDEN_ITERS = 80
"""Golden-section iterations of capsule-box (the bracket shrinks by 0.618**80 ~ 2e-17)."""
_INV_PHI = 0.6180339887498948482  # (sqrt(5) - 1) / 2, the same literal as in the C header


# --- input handling -----------------------------------------------------------------------------


def _vec(x: ArrayLike, name: str) -> Array:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim < 1 or arr.shape[-1] != 3:
        raise ValueError(f"{name} must have shape (..., 3), not {arr.shape}")
    return arr


def _scalar(x: ArrayLike, name: str) -> Array:
    return np.asarray(x, dtype=np.float64)


def _mat(x: ArrayLike, name: str) -> Array:
    arr = np.asarray(x, dtype=np.float64)
    if arr.ndim < 2 or arr.shape[-2:] != (3, 3):
        raise ValueError(f"{name} must have shape (..., 3, 3), not {arr.shape}")
    return arr


def _batch_shape(vecs: tuple[Array, ...], scalars: tuple[Array, ...], mats: tuple[Array, ...]) -> tuple:
    shapes = [v.shape[:-1] for v in vecs] + [s.shape for s in scalars] + [m.shape[:-2] for m in mats]
    try:
        return np.broadcast_shapes(*shapes)
    except ValueError:
        raise ValueError(f"the batch shapes {shapes} do not broadcast together") from None


def _bvec(x: Array, shape: tuple) -> Array:
    return np.broadcast_to(x, shape + (3,))


# --- elementary operations (the same order of operations as the C header) ------------------------


def _dot(u: Array, v: Array) -> Array:
    return u[..., 0] * v[..., 0] + u[..., 1] * v[..., 1] + u[..., 2] * v[..., 2]


def _clamp01(x: Array) -> Array:
    return np.minimum(np.maximum(x, 0.0), 1.0)


def _normal(diff: Array) -> tuple[Array, Array]:
    """|diff| and diff / |diff|, or (0, 0, 1) when |diff| <= DIST_EPS."""
    length = np.sqrt(_dot(diff, diff))
    ok = length > DIST_EPS
    safe = np.where(ok, length, 1.0)
    n = np.where(ok[..., None], diff / safe[..., None], np.array([0.0, 0.0, 1.0]))
    return length, n


@dataclass(frozen=True)
class SegmentOps:
    """An array library's ``where(cond, a, b)`` (elementwise select), ``dot(u, v)`` (over the vector
    axis: a scalar per point) and ``clamp01(x)`` (x clamped to [0, 1]): what the closest points on
    segments (:func:`point_segment_with`, :func:`segment_closest_with`) need, so that NumPy (here),
    CasADi (:mod:`symkin.emit.casadi.collision`) and JAX/PyTorch (:mod:`symkin.runtime.diff.distance`)
    run one implementation. Every division is guarded by a ``where``, so no branch divides by zero
    (finite derivatives through the branch not taken)."""

    where: Callable[[Any, Any, Any], Any]
    dot: Callable[[Any, Any], Any]
    clamp01: Callable[[Any], Any]


_NUMPY = SegmentOps(where=np.where, dot=_dot, clamp01=_clamp01)


def point_segment_with(ops: SegmentOps, p: Any, a: Any, b: Any) -> Any:
    """Parameter t in [0, 1] of the point of segment a-b closest to p (0 for a point segment), in
    the array library of ``ops``."""
    ab = b - a
    l2 = ops.dot(ab, ab)
    ok = l2 > SEG_EPS
    return ops.where(ok, ops.clamp01(ops.dot(p - a, ab) / ops.where(ok, l2, 1.0)), 0.0)


def segment_closest_with(ops: SegmentOps, a1: Any, b1: Any, a2: Any, b2: Any) -> tuple[Any, Any]:
    """Parameters (s, t) of :func:`segment_closest` in the array library of ``ops``."""
    where, dot, clamp01 = ops.where, ops.dot, ops.clamp01
    d1, d2, r = b1 - a1, b2 - a2, a1 - a2
    a, e, f, c, b = dot(d1, d1), dot(d2, d2), dot(d2, r), dot(d1, r), dot(d1, d2)
    ok1, ok2 = a > SEG_EPS, e > SEG_EPS
    a_s, e_s = where(ok1, a, 1.0), where(ok2, e, 1.0)
    # both segments proper (Ericson's general case)
    denom = a * e - b * b
    skew = denom > PAR_EPS * a * e
    s_gen = where(skew, clamp01((b * f - c * e) / where(skew, denom, 1.0)), 0.0)
    t_gen = (b * s_gen + f) / e_s
    s_gen = where(t_gen < 0.0, clamp01(-c / a_s), where(t_gen > 1.0, clamp01((b - c) / a_s), s_gen))
    t_gen = clamp01(t_gen)
    # segment 2 is a point: t = 0; segment 1 is a point: s = 0
    s = where(ok1, where(ok2, s_gen, clamp01(-c / a_s)), 0.0)
    t = where(ok2, where(ok1, t_gen, clamp01(f / e_s)), 0.0)
    return s, t


def _box_sdf(p: Array, center: Array, h: Array, R: Array) -> tuple[Array, Array]:
    v = p - center
    v0, v1, v2 = v[..., 0], v[..., 1], v[..., 2]
    x0 = R[..., 0, 0] * v0 + R[..., 1, 0] * v1 + R[..., 2, 0] * v2
    x1 = R[..., 0, 1] * v0 + R[..., 1, 1] * v1 + R[..., 2, 1] * v2
    x2 = R[..., 0, 2] * v0 + R[..., 1, 2] * v1 + R[..., 2, 2] * v2
    q0 = np.abs(x0) - h[..., 0]
    q1 = np.abs(x1) - h[..., 1]
    q2 = np.abs(x2) - h[..., 2]
    m0 = np.maximum(q0, 0.0)
    m1 = np.maximum(q1, 0.0)
    m2 = np.maximum(q2, 0.0)
    ext = np.sqrt(m0 * m0 + m1 * m1 + m2 * m2)
    qmax = np.maximum(np.maximum(q0, q1), q2)
    d = ext + np.minimum(qmax, 0.0)
    # outside (ext > DIST_EPS): (p - closest) / |p - closest| in box coordinates; else (on or inside
    # the surface, or too close to it for a direction) the nearest face's outward normal, the lowest
    # axis on ties (as the C loop: k = 0; q1 > q[k]: 1; q2 > q[k]: 2)
    out = ext > DIST_EPS
    ext_s = np.where(out, ext, 1.0)
    k0 = (q0 >= q1) & (q0 >= q2)
    k1 = ~k0 & (q1 >= q2)
    k2 = ~k0 & ~k1
    n0 = np.where(
        out, np.where(x0 >= 0.0, m0, -m0) / ext_s, np.where(k0, np.where(x0 >= 0.0, 1.0, -1.0), 0.0)
    )
    n1 = np.where(
        out, np.where(x1 >= 0.0, m1, -m1) / ext_s, np.where(k1, np.where(x1 >= 0.0, 1.0, -1.0), 0.0)
    )
    n2 = np.where(
        out, np.where(x2 >= 0.0, m2, -m2) / ext_s, np.where(k2, np.where(x2 >= 0.0, 1.0, -1.0), 0.0)
    )
    n = np.stack(
        [
            R[..., 0, 0] * n0 + R[..., 0, 1] * n1 + R[..., 0, 2] * n2,
            R[..., 1, 0] * n0 + R[..., 1, 1] * n1 + R[..., 1, 2] * n2,
            R[..., 2, 0] * n0 + R[..., 2, 1] * n1 + R[..., 2, 2] * n2,
        ],
        axis=-1,
    )
    return d, n


def golden_min_with(
    ops: SegmentOps, f: Callable[[Any], Any], lo: Any, hi: Any, pair: Callable[[Any, Any], Any] | None = None
) -> Any:
    """argmin over t in [0, 1] of the convex ``f`` (vectorised) in the array library of ``ops``:
    golden-section search with GOLDEN_ITERS steps from ``lo`` and ``hi`` (zeros and ones of the
    batch shape), then the better of the bracket's midpoint and the endpoints 0 and 1. ``pair(c,
    d)`` gives each step's ``(f(c), f(d))`` (default two calls; NumPy stacks them into one).

    On a tie f(c) == f(d) a minimiser lies in [c, d] (convexity): both ends move in and both inner
    points are evaluated afresh, so a flat stretch of minima (a segment parallel to a face) ends
    in its interior rather than at a kink on its edge, where the normal would be the wrong face's.
    """
    where = ops.where
    pair = pair or (lambda c, d: (f(c), f(d)))
    zero, one = lo, hi
    c = hi - _INV_PHI * (hi - lo)
    d = lo + _INV_PHI * (hi - lo)
    fc, fd = f(c), f(d)
    for _ in range(GOLDEN_ITERS):
        # fc < fd: hi = d, d = c, c = new; fd < fc: lo = c, c = d, d = new; tie: lo = c, hi = d, both new
        left = fc < fd
        right = fd < fc
        lo = where(left, lo, c)
        hi = where(right, hi, d)
        c_new = hi - _INV_PHI * (hi - lo)
        d_new = lo + _INV_PHI * (hi - lo)
        fc_new, fd_new = pair(c_new, d_new)
        c, d = where(right, d, c_new), where(left, c, d_new)
        fc, fd = where(right, fd, fc_new), where(left, fc, fd_new)
    t = 0.5 * (lo + hi)
    ft = f(t)
    f0 = f(zero)
    take0 = f0 < ft
    t = where(take0, 0.0, t)
    ft = where(take0, f0, ft)
    f1 = f(one)
    return where(f1 < ft, 1.0, t)


# --- public functions --------------------------------------------------------------------------


def segment_closest(a1: ArrayLike, b1: ArrayLike, a2: ArrayLike, b2: ArrayLike) -> tuple[Array, Array]:
    """Parameters ``(s, t)`` in [0, 1] of the closest points ``a1 + s (b1 - a1)`` and
    ``a2 + t (b2 - a2)`` of two segments (Ericson 5.1.9). A zero-length segment takes parameter 0;
    parallel segments take ``s = 0`` and ``t`` its clamped projection (then ``s`` re-projected)."""
    A1, B1, A2, B2 = _vec(a1, "a1"), _vec(b1, "b1"), _vec(a2, "a2"), _vec(b2, "b2")
    shape = _batch_shape((A1, B1, A2, B2), (), ())
    A1, B1, A2, B2 = (_bvec(x, shape) for x in (A1, B1, A2, B2))
    return segment_closest_with(_NUMPY, A1, B1, A2, B2)


def point_segment(p: ArrayLike, a: ArrayLike, b: ArrayLike) -> Array:
    """Parameter ``t`` in [0, 1] of the point ``a + t (b - a)`` of the segment closest to ``p``
    (0 for a zero-length segment)."""
    P, A, B = _vec(p, "p"), _vec(a, "a"), _vec(b, "b")
    shape = _batch_shape((P, A, B), (), ())
    return point_segment_with(_NUMPY, _bvec(P, shape), _bvec(A, shape), _bvec(B, shape))


def box_sdf(p: ArrayLike, center: ArrayLike, h: ArrayLike, R: ArrayLike) -> tuple[Array, Array]:
    """Exact signed distance ``d`` (...) of the point ``p`` to the box and its unit gradient ``n``
    (..., 3) in world coordinates: outside, ``(p - closest) / |p - closest|``; on or inside the
    surface (or within DIST_EPS outside it), the outward normal of the nearest face (the lowest axis
    index on ties)."""
    P, C, H, M = _vec(p, "p"), _vec(center, "center"), _vec(h, "h"), _mat(R, "R")
    shape = _batch_shape((P, C, H), (), (M,))
    d, n = _box_sdf(P, C, H, M)
    return np.broadcast_to(d, shape).copy(), np.broadcast_to(n, shape + (3,)).copy()


def sphere_sphere(c1: ArrayLike, r1: ArrayLike, c2: ArrayLike, r2: ArrayLike) -> PairResult:
    """Sphere A (``c1``, ``r1``) against sphere B (``c2``, ``r2``): ``(d, n, pa, pb)``."""
    C1, R1, C2, R2 = _vec(c1, "c1"), _scalar(r1, "r1"), _vec(c2, "c2"), _scalar(r2, "r2")
    shape = _batch_shape((C1, C2), (R1, R2), ())
    pa, pb = _bvec(C1, shape).copy(), _bvec(C2, shape).copy()
    length, n = _normal(pa - pb)
    return length - R1 - R2, n, pa, pb


def capsule_sphere(a1: ArrayLike, b1: ArrayLike, r1: ArrayLike, c2: ArrayLike, r2: ArrayLike) -> PairResult:
    """Capsule A (segment ``a1``-``b1``, ``r1``) against sphere B (``c2``, ``r2``): ``(d, n, pa, pb)``."""
    A1, B1, R1 = _vec(a1, "a1"), _vec(b1, "b1"), _scalar(r1, "r1")
    C2, R2 = _vec(c2, "c2"), _scalar(r2, "r2")
    shape = _batch_shape((A1, B1, C2), (R1, R2), ())
    A1, B1, pb = _bvec(A1, shape), _bvec(B1, shape), _bvec(C2, shape).copy()
    t = point_segment_with(_NUMPY, pb, A1, B1)
    pa = A1 + t[..., None] * (B1 - A1)
    length, n = _normal(pa - pb)
    return length - R1 - R2, n, pa, pb


def capsule_capsule(
    a1: ArrayLike, b1: ArrayLike, r1: ArrayLike, a2: ArrayLike, b2: ArrayLike, r2: ArrayLike
) -> PairResult:
    """Capsule A (``a1``-``b1``, ``r1``) against capsule B (``a2``-``b2``, ``r2``): ``(d, n, pa, pb)``."""
    A1, B1, R1 = _vec(a1, "a1"), _vec(b1, "b1"), _scalar(r1, "r1")
    A2, B2, R2 = _vec(a2, "a2"), _vec(b2, "b2"), _scalar(r2, "r2")
    shape = _batch_shape((A1, B1, A2, B2), (R1, R2), ())
    A1, B1, A2, B2 = _bvec(A1, shape), _bvec(B1, shape), _bvec(A2, shape), _bvec(B2, shape)
    s, t = segment_closest_with(_NUMPY, A1, B1, A2, B2)
    pa = A1 + s[..., None] * (B1 - A1)
    pb = A2 + t[..., None] * (B2 - A2)
    length, n = _normal(pa - pb)
    return length - R1 - R2, n, pa, pb


def sphere_box(c: ArrayLike, r: ArrayLike, center: ArrayLike, h: ArrayLike, R: ArrayLike) -> PairResult:
    """Sphere A (``c``, ``r``) against box B (``center``, ``h``, ``R``): ``(d, n, pa, pb)``."""
    C, Rad = _vec(c, "c"), _scalar(r, "r")
    Ctr, H, M = _vec(center, "center"), _vec(h, "h"), _mat(R, "R")
    shape = _batch_shape((C, Ctr, H), (Rad,), (M,))
    pa = _bvec(C, shape).copy()
    sdf, n = _box_sdf(pa, Ctr, H, M)
    sdf = np.broadcast_to(sdf, shape)
    n = np.broadcast_to(n, shape + (3,)).copy()
    return sdf - Rad, n, pa, pa - sdf[..., None] * n


def capsule_box(
    a: ArrayLike, b: ArrayLike, r: ArrayLike, center: ArrayLike, h: ArrayLike, R: ArrayLike
) -> PairResult:
    """Capsule A (``a``-``b``, ``r``) against box B (``center``, ``h``, ``R``): ``(d, n, pa, pb)``.

    The box SDF along the segment is convex in the segment parameter; it is minimised by
    golden-section search (GOLDEN_ITERS steps), then compared with the endpoints; ``d = sdf(pa) - r``.
    """
    A, B, Rad = _vec(a, "a"), _vec(b, "b"), _scalar(r, "r")
    Ctr, H, M = _vec(center, "center"), _vec(h, "h"), _mat(R, "R")
    shape = _batch_shape((A, B, Ctr, H), (Rad,), (M,))
    A, B = _bvec(A, shape), _bvec(B, shape)
    ab = B - A

    def sdf_at(t: Array) -> Array:
        return _box_sdf(A + t[..., None] * ab, Ctr, H, M)[0]

    t = golden_min_with(
        _NUMPY, sdf_at, np.zeros(shape), np.ones(shape), lambda c, d: sdf_at(np.stack([c, d]))
    )
    pa = A + t[..., None] * ab
    sdf, n = _box_sdf(pa, Ctr, H, M)
    n = np.broadcast_to(n, shape + (3,)).copy()
    return sdf - Rad, n, pa, pa - sdf[..., None] * n
