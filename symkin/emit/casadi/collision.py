"""The collision distances of a model's geometry as one ``casadi.Function`` (SX): ``d = f(q)``, the
signed distance of every active pair in the order of ``kin.collision_pairs(env)``, for
``casadi.Opti`` problems (``opti.subject_to(f(q) >= margin)``) and CasADi's derivatives.

The shape points come from the generated CasADi collision module
(``templates/casadi/collision.py.j2``: straight-line link poses with the constants folded in), the
pair distances are the closed forms of :mod:`symkin.geometry.distance` written with CasADi's
``if_else``/``fmin``/``fmax``: sphere-sphere, capsule-sphere, capsule-capsule (Ericson's closest
points of two segments, :mod:`symkin.emit.segments`) and sphere-box (the box's signed distance
field). A capsule against a box has no closed form (:mod:`symkin.geometry.distance` minimises along
the segment): such an environment is refused with a GeometryError.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.emit.segments import SegmentOps, point_segment, segment_closest
from symkin.errors import GeometryError

__all__ = ["distances_function"]


def _norm(ca: Any, v: Any) -> Any:
    return ca.sqrt(ca.sumsqr(v))


def _segment_ops(ca: Any) -> SegmentOps:
    """CasADi's ``if_else``, ``dot`` and ``fmin``/``fmax`` for :mod:`symkin.emit.segments`."""
    return SegmentOps(where=ca.if_else, dot=ca.dot, clamp01=lambda x: ca.fmin(ca.fmax(x, 0.0), 1.0))


def _box_sdf(ca: Any, p: Any, center: np.ndarray, h: np.ndarray, R: np.ndarray) -> Any:
    x = ca.DM(R.T) @ (p - ca.DM(center))
    qs = [ca.fabs(x[i]) - float(h[i]) for i in range(3)]
    m = [ca.fmax(v, 0.0) for v in qs]
    s2 = m[0] * m[0] + m[1] * m[1] + m[2] * m[2]
    qmax = ca.fmax(ca.fmax(qs[0], qs[1]), qs[2])
    # outside: the distance to the box; inside: minus the depth (sqrt only where it is positive,
    # so its derivative at 0 never reaches the inside)
    return ca.if_else(s2 > 0, ca.sqrt(ca.if_else(s2 > 0, s2, 1.0)), 0.0) + ca.fmin(qmax, 0.0)


def _pair(ca: Any, A: Any, ra: float, cap_a: bool, B: Any, rb: float, cap_b: bool) -> Any:
    """Signed distance of shape A (points A: 1 or 2) against shape B."""
    if cap_a and cap_b:
        s, t = segment_closest(_segment_ops(ca), A[0], A[1], B[0], B[1])
        return _norm(ca, A[0] + s * (A[1] - A[0]) - B[0] - t * (B[1] - B[0])) - ra - rb
    if cap_a or cap_b:
        (a, b, ro), (p, rp) = ((A[0], A[1], ra), (B[0], rb)) if cap_a else ((B[0], B[1], rb), (A[0], ra))
        t = point_segment(_segment_ops(ca), p, a, b)
        return _norm(ca, a + t * (b - a) - p) - ro - rp
    return _norm(ca, A[0] - B[0]) - ra - rb


def distances_function(points: Any, tables: Any, env: Any = None, name: str = "distances") -> Any:
    """``casadi.Function`` ``name``: q (n,) -> d (M,), the signed distances of the active pairs and of
    every shape against each obstacle of ``env`` (None, an Environment or obstacles), in the order of
    :meth:`symkin.geometry.pairs.Layout.pair_labels`. ``points(q)``: the shape points as lists
    [x, y, z] of CasADi expressions (a generated collision module's ``points``); ``tables``: the
    geometry (:class:`symkin.geometry.reference.Tables`)."""
    import casadi as ca

    from symkin.geometry.pairs import as_environment

    env = as_environment(env)
    caps, radius = tables.caps, tables.radius
    if env.boxes and any(caps):
        raise GeometryError(
            "the CasADi distances have no closed form for a capsule against a box; give the boxes "
            "as spheres (symkin.geometry.fit_spheres) or use kin.distances"
        )
    q = ca.SX.sym("q", tables.n)
    X = points(q)
    pts = [[ca.vertcat(*X[f + k]) for k in range(2 if c else 1)] for f, c in zip(tables.first, caps)]
    out = [_pair(ca, pts[i], radius[i], caps[i], pts[j], radius[j], caps[j]) for i, j in tables.self_pairs]
    for o in env.spheres:
        B = [ca.DM(np.array(o.center))]
        out += [_pair(ca, pts[i], radius[i], caps[i], B, o.radius, False) for i in range(len(pts))]
    for o in env.capsules:
        B = [ca.DM(np.array(o.a)), ca.DM(np.array(o.b))]
        out += [_pair(ca, pts[i], radius[i], caps[i], B, o.radius, True) for i in range(len(pts))]
    for box in env.boxes:
        c, h, R = np.array(box.center), np.array(box.half_extents), box.R
        out += [_box_sdf(ca, pts[i][0], c, h, R) - radius[i] for i in range(len(pts))]
    d = ca.vertcat(*out) if out else ca.SX(0, 1)
    return ca.Function(name, [q], [d], ["q"], ["d"])
