"""Closest points on segments written once for any array library: the CasADi collision distances
(:mod:`symkin.emit.casadi.collision`, SX expressions) and the JAX/PyTorch ones
(:mod:`symkin.runtime.diff.distance`, batched arrays) call these with their library's
:class:`SegmentOps`; they are the code of the NumPy reference (:mod:`symkin.geometry.distance`,
which runs them with NumPy's operations), so the algorithms, constants and degenerate cases are
the same: a segment whose squared length is at most ``SEG_EPS`` is a point (parameter 0), nearly
parallel segments take ``s = 0`` and then Ericson's clamping rules.
"""

from __future__ import annotations

from symkin.geometry.distance import SegmentOps
from symkin.geometry.distance import point_segment_with as point_segment
from symkin.geometry.distance import segment_closest_with as segment_closest

__all__ = ["SegmentOps", "point_segment", "segment_closest"]
