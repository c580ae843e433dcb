"""Signed distances between collision primitives in JAX or PyTorch, differentiable.

The closed forms of :mod:`symkin.geometry.distance` (same conventions, constants and degenerate
cases): sphere-sphere, capsule-sphere, capsule-capsule (Ericson, Real-Time Collision Detection,
2005, 5.1.9; the segments' closest points are :mod:`symkin.emit.segments`, shared with CasADi),
sphere-box and capsule-box (the box's signed distance field, minimised along the
segment by golden-section search). Each returns the signed distance ``d`` (...) only. Where a
distance is a minimum over a closest-point parameter (a point on a segment), the parameter is
found without gradients and the distance is evaluated there: by the envelope theorem that is the
derivative of the minimum (``n . (pa' - pb')``, the reference's distance gradient), and it spares
the autodiff the search. Lengths take their square root only where they exceed
:data:`symkin.geometry.distance.DIST_EPS` (finite gradients for touching cores).
"""

from __future__ import annotations

from typing import Any

from symkin.emit.segments import SegmentOps, point_segment, segment_closest
from symkin.geometry.distance import DIST_EPS, golden_min_with
from symkin.runtime.diff.ops import Ops

__all__ = [
    "sphere_sphere",
    "capsule_sphere",
    "capsule_capsule",
    "sphere_box",
    "capsule_box",
]


def _dot(u: Any, v: Any) -> Any:
    return (u * v).sum(-1)


def _length(ops: Ops, v: Any) -> Any:
    """|v| over the last axis, with a finite gradient where |v| <= DIST_EPS (there: 0)."""
    xp = ops.xp
    s = _dot(v, v)
    ok = s > DIST_EPS * DIST_EPS
    return xp.where(ok, xp.sqrt(xp.where(ok, s, 1.0)), 0.0)


def _segment_ops(ops: Ops) -> SegmentOps:
    """The library's ``where``, a dot over the last axis and ``clip`` for :mod:`symkin.emit.segments`."""
    return SegmentOps(where=ops.xp.where, dot=_dot, clamp01=lambda x: ops.clip(x, 0.0, 1.0))


def _box_sdf(ops: Ops, p: Any, center: Any, h: Any, R: Any) -> Any:
    """The box's exact signed distance field at p (box axes the columns of R)."""
    xp = ops.xp
    v = p - center
    x = (R * v[..., :, None]).sum(-2)  # R^T v: box coordinates
    qd = xp.abs(x) - h
    m = xp.where(qd > 0.0, qd, 0.0)
    qmax = xp.amax(qd, -1)
    return _length(ops, m) + xp.where(qmax < 0.0, qmax, 0.0)


def sphere_sphere(ops: Ops, c1: Any, r1: Any, c2: Any, r2: Any) -> Any:
    """Sphere (c1, r1) against sphere (c2, r2)."""
    return _length(ops, c1 - c2) - r1 - r2


def capsule_sphere(ops: Ops, a1: Any, b1: Any, r1: Any, c2: Any, r2: Any) -> Any:
    """Capsule (segment a1-b1, r1) against sphere (c2, r2)."""
    t = ops.detach(point_segment(_segment_ops(ops), c2, a1, b1))
    return _length(ops, a1 + t[..., None] * (b1 - a1) - c2) - r1 - r2


def capsule_capsule(ops: Ops, a1: Any, b1: Any, r1: Any, a2: Any, b2: Any, r2: Any) -> Any:
    """Capsule (a1-b1, r1) against capsule (a2-b2, r2)."""
    s, t = segment_closest(_segment_ops(ops), *(ops.detach(x) for x in (a1, b1, a2, b2)))
    pa = a1 + s[..., None] * (b1 - a1)
    pb = a2 + t[..., None] * (b2 - a2)
    return _length(ops, pa - pb) - r1 - r2


def sphere_box(ops: Ops, c: Any, r: Any, center: Any, h: Any, R: Any) -> Any:
    """Sphere (c, r) against box (center, half extents h, rotation R)."""
    return _box_sdf(ops, c, center, h, R) - r


def capsule_box(ops: Ops, a: Any, b: Any, r: Any, center: Any, h: Any, R: Any) -> Any:
    """Capsule (a-b, r) against box (center, h, R): the box SDF minimised along the segment by
    golden-section search (:func:`symkin.geometry.distance.golden_min_with`), then the endpoints,
    as :func:`symkin.geometry.distance.capsule_box`."""
    xp = ops.xp
    A, B = ops.detach(a), ops.detach(b)

    def f(t: Any) -> Any:
        return _box_sdf(ops, A + t[..., None] * (B - A), center, h, R)

    one = f(xp.zeros_like(A[..., 0])) * 0.0 + 1.0  # ones of the pair's batch shape
    t = golden_min_with(_segment_ops(ops), f, 0.0 * one, one)
    return _box_sdf(ops, a + ops.detach(t)[..., None] * (b - a), center, h, R) - r
