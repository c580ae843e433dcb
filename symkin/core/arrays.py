"""Joint-value arrays: the one rule for q (real, finite, bounded, shape (n,) or (N, n)), the
rows of J that ``axes`` picks, and random joint values within limits (leaf module)."""

from __future__ import annotations

import math
import numbers
from typing import Any, Literal

import numpy as np

from symkin.errors import ConfigurationError, ParameterError, SymkinError

__all__ = [
    "AXES_ROWS",
    "Axes",
    "MAX_JOINT_VALUE",
    "as_batch",
    "axes_rows",
    "real_array",
    "sample_bounds",
    "sample_q",
]

Axes = Literal["all", "trans", "rot"]
AXES_ROWS: dict[str, slice] = {"all": slice(0, 6), "trans": slice(0, 3), "rot": slice(3, 6)}


#: Largest |q| accepted. Beyond it a double resolves an angle to worse than 0.1 rad, and the
#: generated code's angle sums (``sin(q1 + q2)``) could overflow to inf.
MAX_JOINT_VALUE = 1e15


def real_array(
    x: Any, what: str, error: type[SymkinError] = ConfigurationError, items: str = "numbers"
) -> np.ndarray:
    """``x`` as a float64 array in native byte order, or raise ``error`` naming ``what``.

    Booleans, integers and floats of any byte order convert, and so do sequences and object
    arrays of real numbers; complex numbers, strings and other objects are refused (NumPy would
    drop an imaginary part or parse a string), so every backend accepts the same inputs.
    """
    if isinstance(x, np.ndarray) and x.dtype.kind in "biuf":
        return np.asarray(x, dtype=float)
    try:
        a = np.asarray(x)
    except (TypeError, ValueError) as exc:
        raise error(f"{what} must be an array of {items}: {exc}") from None
    kind = a.dtype.kind
    if kind == "O":
        for v in a.flat:
            if isinstance(v, (str, bytes)):
                kind = "U"
                break
            if isinstance(v, numbers.Complex) and not isinstance(v, numbers.Real):
                kind = "c"
                break
    if kind == "c":
        raise error(f"{what} must be real numbers, not complex")
    if kind not in "biufO":
        got = "strings" if kind in "US" else f"{a.dtype} values"
        raise error(f"{what} must be an array of {items}, not {got}")
    try:
        return a.astype(float)
    except (TypeError, ValueError) as exc:
        raise error(f"{what} must be an array of {items}: {exc}") from None


def as_batch(q: Any, n: int, name: str = "robot", what: str = "q") -> tuple[np.ndarray, bool]:
    """Validate ``q`` (shape (n,) or (N, n), real, finite, within :data:`MAX_JOINT_VALUE`)
    -> ((N, n) float array, was_single)."""
    Q = real_array(q, what, items=f"{n} numbers")
    single = Q.ndim == 1
    if Q.ndim == 0 or Q.ndim > 2 or Q.shape[-1] != n:
        raise ConfigurationError(
            f"{what} must have shape ({n},) or (N, {n}) for {name} with {n} joints, got shape {Q.shape}"
        )
    if single:
        Q = Q[None, :]
    ok = np.abs(Q) <= MAX_JOINT_VALUE  # False for NaN too
    if not ok.all():
        bad = np.argwhere(~ok)[0]
        where = f"[{bad[1]}]" if single else f"[{bad[0]}, {bad[1]}]"
        value = Q[tuple(bad)]
        why = "must be finite" if not np.isfinite(value) else f"must be within +-{MAX_JOINT_VALUE:g}"
        raise ConfigurationError(f"{what}{where} is {value}: joint values {why}")
    return Q, single


def axes_rows(axes: str) -> slice:
    """The rows of J0 that ``axes`` ("all", "trans", "rot") selects; ParameterError otherwise."""
    try:
        return AXES_ROWS[axes]
    except (KeyError, TypeError):
        raise ParameterError(f"axes must be one of {sorted(AXES_ROWS)}, not {axes!r}") from None


def sample_bounds(qlim: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """(2, n) range to draw random joint values from: ``qlim``, where a bound that is infinite or
    beyond +-:data:`MAX_JOINT_VALUE` (which q may not exceed) counts as no bound: it is replaced by
    one turn (``revolute``) or 2 m beyond the other bound, or +-pi / +-1 m around 0 when both are."""
    lo, hi = np.array(qlim[0], dtype=float), np.array(qlim[1], dtype=float)
    lo_free, hi_free = ~(np.abs(lo) <= MAX_JOINT_VALUE), ~(np.abs(hi) <= MAX_JOINT_VALUE)
    if lo_free.any() or hi_free.any():
        half = np.where(revolute, math.pi, 1.0)
        lo, hi = (
            np.where(lo_free, np.where(hi_free, -half, hi - 2 * half), lo),
            np.where(hi_free, np.where(lo_free, half, lo + 2 * half), hi),
        )
    return np.stack((lo, hi))


def sample_q(
    qlim: np.ndarray,
    revolute: np.ndarray,
    N: int | None = None,
    seed: int | np.random.Generator | None = None,
) -> np.ndarray:
    """Uniform random joint values within :func:`sample_bounds` of ``qlim``: (n,) or (N, n)."""
    rng = np.random.default_rng(seed)
    lo, hi = sample_bounds(qlim, revolute)
    if N is None:
        return rng.uniform(lo, hi)
    return rng.uniform(lo, hi, size=(N, lo.size))
