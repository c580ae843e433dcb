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
    "as_config",
    "as_rows",
    "name_of",
    "axes_rows",
    "finite_number",
    "per_joint",
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
    """``x`` as an aligned float64 array in native byte order, or raise ``error`` naming ``what``.

    The conversion rule of every entry point that takes joint values or poses, on every backend
    (the C extensions convert plain arrays themselves and hand anything else to this): booleans,
    integers and floats of any byte order, alignment, layout and precision (float16 to long
    double) convert, and so do sequences and object arrays of real numbers (Python ints,
    Fractions); complex numbers, strings and other objects are refused (NumPy would drop an
    imaginary part or parse a string), and so is a finite number beyond the range of a double
    (``10**400``, a long double 1e400), which NumPy would turn into an OverflowError or inf.
    """
    if isinstance(x, np.ndarray) and (
        x.dtype.kind in "biu" or (x.dtype.kind == "f" and x.dtype.itemsize <= 8)
    ):
        a = np.asarray(x, dtype=float)
        return a if a.flags.aligned else a.copy()  # aligned: C code may read it (after ascontiguousarray)
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
        with np.errstate(over="ignore"):  # a long double beyond a double's range: refused below
            out = a.astype(float)
        if kind == "f" and a.dtype.itemsize > 8 and (np.isinf(out) & np.isfinite(a)).any():
            raise OverflowError
    except OverflowError:
        raise error(f"{what} holds a number beyond the range of a double (|x| > 1.8e308)") from None
    except (TypeError, ValueError) as exc:
        raise error(f"{what} must be an array of {items}: {exc}") from None
    return out


def finite_number(
    value: Any, name: str, minimum: float = 0.0, strict: bool = True, error: type[Exception] = ParameterError
) -> float:
    """``value`` as a finite float > ``minimum`` (``>=`` when not ``strict``), else ``error``."""
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise error(f"{name} must be a number, got {value!r}") from None
    if not (math.isfinite(x) and (x > minimum if strict else x >= minimum)):
        raise error(f"{name} must be finite and {'>' if strict else '>='} {minimum:g}, got {value!r}")
    return x


def per_joint(value: Any, n: int, name: str) -> np.ndarray:
    """A scalar or (n,) parameter as finite (n,) floats >= 0, else ParameterError."""
    try:
        a = np.broadcast_to(real_array(value, name, ParameterError), (n,)).copy()
    except ValueError:
        raise ParameterError(f"{name} must be a number or {n} numbers, got {value!r}") from None
    if not (np.isfinite(a).all() and (a >= 0).all()):
        raise ParameterError(f"{name} must be finite and >= 0, got {a.tolist()}")
    return a


def _check_range(Q: np.ndarray, what: str, single: bool) -> None:
    """ConfigurationError naming the first joint value of ``Q`` (N, n) that is NaN, inf or beyond
    +-:data:`MAX_JOINT_VALUE`."""
    ok = np.abs(Q) <= MAX_JOINT_VALUE  # False for NaN too
    if not ok.all():
        bad = np.argwhere(~ok)[0]
        where = f"[{bad[1]}]" if single else f"[{bad[0]}, {bad[1]}]"
        value = Q[tuple(bad)]
        why = "must be finite" if not np.isfinite(value) else f"must be within +-{MAX_JOINT_VALUE:g}"
        raise ConfigurationError(f"{what}{where} is {value}: joint values {why}")


def as_batch(q: Any, n: int, name: str = "robot", what: str = "q") -> tuple[np.ndarray, bool]:
    """Validate ``q`` (shape (n,) or (N, n), real, finite, within :data:`MAX_JOINT_VALUE`)
    -> ((N, n) float array, was_single).

    The rule for joint values everywhere (reference, every backend, trees, IK seeds, controllers):
    :func:`real_array` converts, then the shape and the values are checked. N = 0 is a valid batch.
    """
    Q = real_array(q, what, items=f"{n} numbers")
    single = Q.ndim == 1
    if Q.ndim == 0 or Q.ndim > 2 or Q.shape[-1] != n:
        raise ConfigurationError(
            f"{what} must have shape ({n},) or (N, {n}) for {name} with {n} joints, got shape {Q.shape}"
        )
    if single:
        Q = Q[None, :]
    _check_range(Q, what, single)
    return Q, single


def as_config(q: Any, n: int, name: str = "robot", what: str = "q") -> np.ndarray:
    """One configuration (n,) (a controller's q, a servo's start), by :func:`as_batch`'s rule."""
    Q = real_array(q, what, items=f"{n} numbers")
    if Q.shape != (n,):
        raise ConfigurationError(
            f"{what} must be one configuration, shape ({n},), for {name} with {n} joints, got shape {Q.shape}"
        )
    _check_range(Q[None], what, True)
    return Q


def name_of(kin: Any) -> str:
    """The robot name of kinematics ``kin`` (a Robot, compiled kinematics, a tree frame) for messages."""
    name = getattr(kin, "name", None)
    return name if isinstance(name, str) else "robot"


def as_rows(q: Any, n: int, N: int, one: bool, name: str = "robot", what: str = "q0") -> np.ndarray:
    """Joint values given per target (IK seeds ``q0``) -> (N, n), by :func:`as_batch`'s rule: one
    configuration (n,) for all N targets, or (N, n) with a row per target when the targets are a
    batch (``one`` False; a single (4, 4) target takes (n,) only)."""
    if one:
        return as_config(q, n, name, what)[None]
    Q, single = as_batch(q, n, name, what)
    if single:
        return np.broadcast_to(Q, (N, n))
    if Q.shape[0] != N:
        raise ConfigurationError(
            f"{what} must have shape ({n},) or ({N}, {n}), one row per target, got shape {Q.shape}"
        )
    return Q


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
    """Uniform random joint values within :func:`sample_bounds` of ``qlim``: (n,) or (N, n);
    ParameterError for an N that is not a count >= 0 or whose array would not fit in memory."""
    from symkin.core.sizes import count, room

    if N is not None:
        N = count(N, "N (the number of configurations)", minimum=0)
        room(8.0 * N * len(qlim[0]), f"{N} random configurations")
    rng = np.random.default_rng(seed)
    lo, hi = sample_bounds(qlim, revolute)
    if N is None:
        return rng.uniform(lo, hi)
    return rng.uniform(lo, hi, size=(N, lo.size))
