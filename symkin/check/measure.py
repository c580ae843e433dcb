"""How far a computed array is from its reference: the one error measure of ``symkin check``."""

from __future__ import annotations

import numpy as np

__all__ = ["relative_error"]


def relative_error(a: np.ndarray, b: np.ndarray) -> float:
    """max |a - b| / max(1, max |b|) (b the reference); inf when the shapes differ or a is not finite."""
    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.shape != b.shape or not np.isfinite(a).all():
        return float("inf")
    return float(np.abs(a - b).max(initial=0.0) / max(1.0, np.abs(b).max(initial=0.0)))
