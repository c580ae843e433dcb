"""symkin.emit.segments with NumPy's operations against the NumPy reference
(symkin.geometry.distance), which spells the same algorithm out on its own, including the
degenerate cases: point segments and (nearly) parallel ones."""

from __future__ import annotations

import numpy as np

from symkin.emit.segments import SegmentOps, point_segment, segment_closest
from symkin.geometry import distance as gd

NP = SegmentOps(where=np.where, dot=lambda u, v: (u * v).sum(-1), clamp01=lambda x: np.clip(x, 0.0, 1.0))


def _segments(n: int = 400) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(0)
    a1, b1, a2, b2 = rng.normal(size=(4, n, 3))
    b1[:40] = a1[:40]  # segment 1 a point
    b2[30:70] = a2[30:70]  # segment 2 a point (both for 30..39)
    b2[100:140] = a2[100:140] + 2.0 * (b1[100:140] - a1[100:140])  # parallel
    return a1, b1, a2, b2


def test_segment_closest_is_the_reference_to_the_bit():
    a1, b1, a2, b2 = _segments()
    s, t = segment_closest(NP, a1, b1, a2, b2)
    s_ref, t_ref = gd.segment_closest(a1, b1, a2, b2)
    assert np.array_equal(s, s_ref) and np.array_equal(t, t_ref)
    assert (s[:40] == 0).all() and (t[30:70] == 0).all()


def test_point_segment_is_the_reference_to_the_bit():
    a1, b1, p, _ = _segments()
    t = point_segment(NP, p, a1, b1)
    assert np.array_equal(t, gd.point_segment(p, a1, b1))
    assert (t[:40] == 0).all() and ((t >= 0) & (t <= 1)).all()
