"""Shared test fixtures: a private compile cache and helpers for comparing arrays."""

from __future__ import annotations

import os
import tempfile

import numpy as np
import pytest

# A private, empty compile cache for the whole session: tests never touch the user's cache.
os.environ.setdefault("SYMKIN_CACHE", tempfile.mkdtemp(prefix="symkin-test-cache-"))


def assert_close(actual, expected, rtol: float, what: str = "") -> None:
    """|actual - expected| <= rtol * max(1, max|expected|), with a NaN guard."""
    actual, expected = np.asarray(actual, dtype=float), np.asarray(expected, dtype=float)
    assert actual.shape == expected.shape, f"{what}: shape {actual.shape} != {expected.shape}"
    assert np.isfinite(actual).all(), f"{what}: non-finite values"
    scale = max(1.0, float(np.abs(expected).max(initial=0.0)))
    err = float(np.abs(actual - expected).max(initial=0.0))
    assert err <= rtol * scale, f"{what}: max error {err:.3g} > {rtol:g} * {scale:.3g}"


@pytest.fixture(scope="session")
def cache_dir() -> str:
    return os.environ["SYMKIN_CACHE"]
