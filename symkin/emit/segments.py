"""Closest points on segments written once for any array library: the CasADi collision distances
(:mod:`symkin.emit.casadi.collision`, SX expressions) and the JAX/PyTorch ones
(:mod:`symkin.runtime.diff.distance`, batched arrays) both call these with their library's
:class:`SegmentOps`.

Same algorithms, constants and degenerate cases as :mod:`symkin.geometry.distance` (the NumPy
reference): a segment whose squared length is at most ``SEG_EPS`` is a point (parameter 0), nearly
parallel segments take ``s = 0`` and then Ericson's clamping rules. Every division is guarded by a
``where`` so that no branch divides by zero (finite derivatives through the branch not taken).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from symkin.geometry.distance import PAR_EPS, SEG_EPS

__all__ = ["SegmentOps", "point_segment", "segment_closest"]


@dataclass(frozen=True)
class SegmentOps:
    """An array library's ``where(cond, a, b)`` (elementwise select), ``dot(u, v)`` (over the vector
    axis: a scalar per point) and ``clamp01(x)`` (x clamped to [0, 1])."""

    where: Callable[[Any, Any, Any], Any]
    dot: Callable[[Any, Any], Any]
    clamp01: Callable[[Any], Any]


def point_segment(ops: SegmentOps, p: Any, a: Any, b: Any) -> Any:
    """Parameter t in [0, 1] of the point of segment a-b closest to p (0 for a point segment)."""
    ab = b - a
    l2 = ops.dot(ab, ab)
    ok = l2 > SEG_EPS
    return ops.where(ok, ops.clamp01(ops.dot(p - a, ab) / ops.where(ok, l2, 1.0)), 0.0)


def segment_closest(ops: SegmentOps, a1: Any, b1: Any, a2: Any, b2: Any) -> tuple[Any, Any]:
    """Parameters (s, t) in [0, 1] of the closest points ``a1 + s (b1 - a1)`` and ``a2 + t (b2 - a2)``
    of two segments (Ericson, Real-Time Collision Detection, 2005, 5.1.9), as
    :func:`symkin.geometry.distance.segment_closest`."""
    where, dot, clamp01 = ops.where, ops.dot, ops.clamp01
    d1, d2, r = b1 - a1, b2 - a2, a1 - a2
    a, e, f, c, b = dot(d1, d1), dot(d2, d2), dot(d2, r), dot(d1, r), dot(d1, d2)
    ok1, ok2 = a > SEG_EPS, e > SEG_EPS
    a_s, e_s = where(ok1, a, 1.0), where(ok2, e, 1.0)
    denom = a * e - b * b
    skew = denom > PAR_EPS * a * e
    s_gen = where(skew, clamp01((b * f - c * e) / where(skew, denom, 1.0)), 0.0)
    t_gen = (b * s_gen + f) / e_s
    s_gen = where(t_gen < 0.0, clamp01(-c / a_s), where(t_gen > 1.0, clamp01((b - c) / a_s), s_gen))
    t_gen = clamp01(t_gen)
    s = where(ok1, where(ok2, s_gen, clamp01(-c / a_s)), 0.0)
    t = where(ok2, where(ok1, t_gen, clamp01(f / e_s)), 0.0)
    return s, t
