"""Trajectories with the semantics of roboticstoolbox-python (RTB, Corke, Robotics, Vision & Control in
Python, 3e, 2023, chap 3): scalar and joint-space quintics, trapezoidal (LSPB) profiles and multi-segment
via-point paths (Cartesian paths: :mod:`symkin.runtime.cartesian`).

numpy only (matplotlib for :meth:`Trajectory.plot`). Axis values are whatever the caller interpolates
(joint values in rad or m, Cartesian coordinates); times are in seconds, or in steps where RTB uses steps
(``quintic`` and ``trapezoidal`` with an integer ``t``).

Every function returns finite samples or raises ParameterError: inputs are finite, at most
:data:`MAX_SAMPLES` samples are made, positions near the range of a double are scaled by a power of two
while the polynomials are evaluated (exactly), and a trajectory whose velocities or accelerations
exceed a double (a distance of 1 in 1e-170 s) is refused, never returned as inf or NaN.

Where this module deliberately differs from RTB 1.5 (RTB's behaviour is a bug or an accident there):

- ``jtraj(q0, qf, m)`` returns ``t = linspace(0, 1, m)``, the times its velocities refer to (RTB
  returns ``linspace(0, m, m)`` with velocities per unit of normalised time).
- ``mstraj`` includes the start ``q0`` as row 0 at ``t = 0`` (RTB leaves it out and starts its time
  vector at 0 one step later); ``mstraj(...).q[1:]`` are RTB's rows, and its ``qd`` and ``qdd`` are
  those of the polynomial and linear pieces. It also computes step counts with integers (RTB's
  ``ceil(tacc / dt)`` rounds 1.1 / 0.1 up to 12) and gives every segment at least one linear sample
  (RTB jumps back to a stale point otherwise).
- ``trapezoidal`` with ``|V| = |qf - q0| / tf`` exactly is refused (RTB divides by a zero blend time).
- Inputs RTB turns into NaN or inf with at most a RuntimeWarning raise ParameterError here.

As in RTB 1.5, ``quintic`` and ``trapezoidal`` given a vector of times run the motion from ``t[0]`` to
``t[-1]``, and ``jtraj`` from time 0 to ``t[-1]`` (its times must be >= 0).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from symkin.core.arrays import real_array
from symkin.errors import MissingExtraError, ParameterError

__all__ = ["Trajectory", "quintic", "jtraj", "trapezoidal", "mstraj", "unit_trapezoidal", "MAX_SAMPLES"]

_EPS_STEPS = 1e-9  # slack when counting time steps: 0.3 / 0.1 is 2.9999999999999996 steps, not 3
#: The most samples a trajectory function makes (ParameterError beyond: 10**7 samples of 7 axes
#: take 1.7 GB for q, qd and qdd).
MAX_SAMPLES = 10_000_000
_BIG = 2.0**960  # axes with a position beyond it are evaluated in units of a power of two (_axis_scale)


# -- the result -------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class Trajectory:
    """A sampled trajectory: positions and their first and second time derivatives.

    Attributes:
        name: the function that made it: ``"quintic"``, ``"jtraj"``, ``"trapezoidal"`` or ``"mstraj"``.
        t: (N,) sample times (s), or step numbers 0..N-1 when ``istime`` is False.
        q: (N,) for a scalar trajectory, else (N, n): one row per sample, one column per axis.
        qd: velocity, same shape as ``q``, per second (per step when ``istime`` is False).
        qdd: acceleration, same shape as ``q``, per second squared (per step squared).
        istime: ``t`` is time; False for ``quintic``/``trapezoidal`` given a number of steps, as RTB.
        info: extra results (read-only): ``trapezoidal``: ``tblend`` (blend duration) and ``V``
            (speed of the linear segment), scalars or (n,); ``mstraj``: ``via`` (M, n) via points,
            ``segtime`` (M,) segment durations, ``arrive`` (M,) planned arrival times, ``slowest`` (M,)
            the axis that set each segment's duration (-1 with ``tsegment``).

    The arrays are read-only.
    """

    name: str
    t: np.ndarray
    q: np.ndarray
    qd: np.ndarray
    qdd: np.ndarray
    istime: bool = True
    info: Mapping[str, Any] = field(default_factory=dict)

    def __post_init__(self) -> None:
        for a in (self.t, self.q, self.qd, self.qdd):
            a.setflags(write=False)
        object.__setattr__(self, "info", MappingProxyType(dict(self.info)))

    @property
    def naxes(self) -> int:
        """Number of axes: 1 for a scalar trajectory, else the columns of ``q``."""
        return 1 if self.q.ndim == 1 else self.q.shape[1]

    @property
    def s(self) -> np.ndarray:
        """RTB's name for ``q``."""
        return self.q

    @property
    def sd(self) -> np.ndarray:
        """RTB's name for ``qd``."""
        return self.qd

    @property
    def sdd(self) -> np.ndarray:
        """RTB's name for ``qdd``."""
        return self.qdd

    def __len__(self) -> int:
        """Number of samples N."""
        return len(self.t)

    def __repr__(self) -> str:
        unit = "s" if self.istime else "steps"
        return (
            f"Trajectory({self.name!r}: {len(self)} samples x {self.naxes} axes, "
            f"t = {self.t[0]:.4g}..{self.t[-1]:.4g} {unit})"
        )

    def plot(self, title: str | None = None) -> Any:
        """A matplotlib Figure with three subplots sharing the time axis: q, qd and qdd against ``t``.

        Needs matplotlib (imported here; MissingExtraError without it). The figure is not shown:
        display it in a notebook, ``fig.savefig(path)``, or attach it to pyplot yourself.
        """
        try:
            from matplotlib.figure import Figure
        except ImportError:
            raise MissingExtraError("trajectory plots need matplotlib: pip install 'symkin[plot]'") from None
        fig = Figure(figsize=(6.4, 6.4))
        axes = fig.subplots(3, 1, sharex=True)
        d = "t" if self.istime else "k"
        labels = ("$q$", rf"$\dot q$ (1/{'s' if self.istime else 'step'})",
                  rf"$\ddot q$ (1/{'s' if self.istime else 'step'}$^2$)")  # fmt: skip
        legend = [f"q{j}" for j in range(self.naxes)] if self.q.ndim == 2 else None
        for ax, y, label in zip(axes, (self.q, self.qd, self.qdd), labels, strict=True):
            lines = ax.plot(self.t, y, marker="o", markersize=2)
            ax.set_ylabel(label)
            ax.grid(True)
            if legend is not None and ax is axes[0]:
                ax.legend(lines, legend, fontsize="small", ncol=min(self.naxes, 4))
        axes[-1].set_xlabel("t (s)" if self.istime else "k (step)")
        axes[0].set_xlim(float(self.t[0]), float(self.t[-1]))
        fig.suptitle(title or f"{self.name}: {len(self)} samples x {self.naxes} axes against {d}")
        return fig


# -- input checks -----------------------------------------------------------------------------
def _finite(x: Any, what: str) -> np.ndarray:
    a = real_array(x, what, ParameterError)
    if not np.isfinite(a).all():
        raise ParameterError(f"{what} must be finite, got {a.tolist()}")
    return a


def _endpoints(q0: Any, qf: Any, vector: bool) -> tuple[np.ndarray, np.ndarray, bool]:
    """q0, qf as (n,) arrays of the same shape, and whether both were scalars."""
    a, b = _finite(q0, "q0"), _finite(qf, "qf")
    scalar = a.ndim == 0 and b.ndim == 0 and not vector
    a, b = np.atleast_1d(a), np.atleast_1d(b)
    if a.ndim != 1 or a.shape != b.shape or a.size == 0:
        raise ParameterError(
            f"q0 and qf must be numbers or vectors of one length, got shapes {a.shape}, {b.shape}"
        )
    return a, b, scalar


def _boundary(v: Any, n: int, what: str, per: str = "axis") -> np.ndarray:
    """A boundary velocity (or another value per axis, or ``per`` segment): None (zero), a number for
    every one, or (n,)."""
    if v is None:
        return np.zeros(n)
    a = _finite(v, what)
    if a.ndim == 0:
        return np.full(n, float(a))
    if a.shape != (n,):
        raise ParameterError(f"{what} must be a number or {n} numbers (one per {per}), got shape {a.shape}")
    return a


def _count(m: float, what: str) -> int:
    """``m`` samples as an int, or ParameterError when it exceeds :data:`MAX_SAMPLES` (or is not finite)."""
    if not m <= MAX_SAMPLES:
        raise ParameterError(f"{what}: {m:.4g} samples, more than the {MAX_SAMPLES} a trajectory may have")
    return int(m)


def _times(t: Any, mode: str) -> tuple[np.ndarray, np.ndarray, float, bool]:
    """(sample times, times since the motion starts, duration T, istime) of ``t``.

    ``t``: an integer m (m samples: step numbers 0..m-1, or ``linspace(0, 1, m)`` when ``mode`` is
    ``"normalised"``), or a strictly increasing vector of finite times: the motion runs from ``t[0]``
    to ``t[-1]`` (``mode="start"``, RTB's quintic and trapezoidal) or from time 0 to ``t[-1]``
    (``"zero"``: RTB's jtraj; the times must be >= 0)."""
    if isinstance(t, numbers.Integral) and not isinstance(t, (bool, np.bool_)):
        m = int(t)
        if m < 2:
            raise ParameterError(f"t as a number of samples must be at least 2, got {m}")
        m = _count(m, "t")
        _room(m)
        if mode == "normalised":
            ts = np.linspace(0.0, 1.0, m)
            return ts, ts, 1.0, True
        ts = np.arange(m, dtype=float)
        return ts, ts, float(m - 1), False
    a = real_array(t, "t", ParameterError)
    if a.ndim != 1 or a.size < 2:
        raise ParameterError(
            f"t must be an int (number of samples) or a vector of at least 2 times, got shape {a.shape}"
        )
    if not np.isfinite(a).all():
        raise ParameterError("t must be finite (no NaN or inf)")
    if mode != "start" and a[0] < 0:
        raise ParameterError(f"t must start at time >= 0 (the motion starts at time 0), got t[0] = {a[0]}")
    dt = np.diff(a)
    if not (dt > 0).all():
        i = int(np.argmax(~(dt > 0)))
        raise ParameterError(f"t must be strictly increasing, but t[{i + 1}] = {a[i + 1]} <= t[{i}] = {a[i]}")
    if mode != "start":
        return a, a, float(a[-1]), True
    with np.errstate(over="ignore"):
        T, tau = float(a[-1] - a[0]), a - a[0]
    if not math.isfinite(T):
        raise ParameterError(f"t spans {a[0]:g} .. {a[-1]:g}: the duration exceeds the range of a double")
    return a, tau, T, True


def _positive(x: Any, what: str, allow_zero: bool = False) -> float:
    ok = isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)) and math.isfinite(x)
    if not ok or x < 0 or (x == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{what} must be a finite number {bound}, got {x!r}")
    return float(x)


def _shaped(q: np.ndarray, scalar: bool) -> np.ndarray:
    return q[:, 0].copy() if scalar else q


def _axis_scale(*sizes: np.ndarray) -> np.ndarray:
    """Per axis, a power of two S: 1, or, where some ``|size|`` (positions, velocity x duration)
    exceeds 2**960, one with every ``|size| / S < 2``. Positions divided by S keep the polynomials'
    sums and products (a few hundred times the largest size) within a double; dividing and
    multiplying by a power of two is exact."""
    with np.errstate(over="ignore", invalid="ignore"):
        m = np.max(np.abs(np.stack(sizes)), axis=0)
    big = np.isfinite(m) & (m > _BIG)
    return np.where(big, np.ldexp(1.0, np.frexp(np.where(big, m, 1.0))[1] - 1), 1.0)


def _checked(name: str, t: np.ndarray, q: np.ndarray, qd: np.ndarray, qdd: np.ndarray, hint: str) -> None:
    """ParameterError unless the times and samples are finite (a value beyond a double's range)."""
    for a, what in ((t, "times"), (q, "positions"), (qd, "velocities"), (qdd, "accelerations")):
        if not np.isfinite(a).all():
            raise ParameterError(f"{name}: its {what} exceed the range of a double (|x| > 1.8e308); {hint}")


# -- quintic polynomials ----------------------------------------------------------------------
def _quintic(
    q0: np.ndarray, qf: np.ndarray, qd0: np.ndarray, qd1: np.ndarray, T: float, t: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, qd, qdd (len(t), n) of the quintic from (q0, qd0, 0) at time 0 to (qf, qd1, 0) at time T,
    at times t: RTB's ``jtraj`` polynomial in normalised time s = t / T, each axis in units of its
    :func:`_axis_scale`. Values beyond a double come out inf or NaN (see :func:`_checked`)."""
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        S = _axis_scale(q0, qf, qd0 * T, qd1 * T)
        a, v0, v1 = q0 / S, qd0 / S * T, qd1 / S * T
        d = qf / S - a
        A = 6 * d - 3 * (v1 + v0)
        B = -15 * d + (8 * v0 + 7 * v1)
        C = 10 * d - (6 * v0 + 4 * v1)
        s = (t / T)[:, None]
        q = (((((A * s + B) * s + C) * s) * s + v0) * s + a) * S
        q = np.where(s == 0, q0, q)  # q0 itself at the start (q0 / S may have lost bits to underflow)
        qd = (((((5 * A * s + 4 * B) * s + 3 * C) * s) * s + v0) / T) * S
        qdd = ((((20 * A * s + 12 * B) * s + 6 * C) * s) / T / T) * S
    return q, qd, qdd


_SHORT = "give a longer duration or nearer endpoints"


def quintic(q0: Any, qf: Any, t: Any, qd0: Any = None, qdf: Any = None) -> Trajectory:
    """A quintic polynomial from ``q0`` to ``qf`` (numbers, or vectors (n,) for n axes at once) with
    boundary velocities ``qd0``, ``qdf`` (default 0) and zero boundary accelerations (RTB's ``quintic``).

    ``t``: an int m, m samples at steps 0..m-1 (``istime`` False: qd per step, qdd per step squared,
    as RTB), or a strictly increasing vector of times, the motion running from ``t[0]`` to ``t[-1]``
    (as RTB 1.5). ``q`` is (N,) for scalar endpoints, else (N, n). ParameterError for values beyond
    a double (see the module docstring).
    """
    a, b, scalar = _endpoints(q0, qf, vector=False)
    t, tau, T, istime = _times(t, "start")
    q, qd, qdd = _quintic(a, b, _boundary(qd0, a.size, "qd0"), _boundary(qdf, a.size, "qdf"), T, tau)
    _checked("quintic", t, q, qd, qdd, _SHORT)
    return Trajectory("quintic", t, _shaped(q, scalar), _shaped(qd, scalar), _shaped(qdd, scalar), istime)


def jtraj(q0: Any, qf: Any, t: Any, qd0: Any = None, qd1: Any = None) -> Trajectory:
    """Joint-space quintic from ``q0`` (n,) to ``qf`` (n,) (RTB's ``jtraj``): zero boundary
    accelerations, boundary velocities ``qd0``, ``qd1`` (default 0), all axes starting and stopping together.

    ``t``: an int m, m samples over normalised time 0..1 (``t = linspace(0, 1, m)``), or a strictly
    increasing vector of times >= 0, the polynomial scaled to run from time 0 to ``t[-1]`` (as RTB).
    ``q``, ``qd``, ``qdd`` are (N, n), per second. ParameterError for values beyond a double.
    """
    a, b, _ = _endpoints(q0, qf, vector=True)
    t, tau, T, _ = _times(t, "normalised")
    q, qd, qdd = _quintic(a, b, _boundary(qd0, a.size, "qd0"), _boundary(qd1, a.size, "qd1"), T, tau)
    _checked("jtraj", t, q, qd, qdd, _SHORT)
    return Trajectory("jtraj", t, q, qd, qdd, True)


# -- trapezoidal (LSPB) -----------------------------------------------------------------------
def _lspb(
    a: np.ndarray, b: np.ndarray, T: float, t: np.ndarray, V: np.ndarray | None, scalar: bool = False
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """q, qd, qdd (len(t), n), tblend and V (n,) of the trapezoidal profiles from ``a`` to ``b`` over
    [0, T] at times t, with linear speeds |V| (n,) (None: 1.5 |b - a| / T). In normalised time
    s = t / T and distance f (q = a (1 - f) + b f, exact at both ends and never beyond them) the
    profile has speed
    vn = |V| T / |b - a| in (1, 2], blends of duration beta = 1 - 1 / vn and acceleration vn / beta."""
    n = a.size
    moving = a != b
    with np.errstate(over="ignore", invalid="ignore", divide="ignore", under="ignore"):
        S = _axis_scale(a, b, np.zeros(n) if V is None else V * T)
        d = b / S - a / S
        dist = np.where(moving, np.abs(d), 1.0)
        if V is None:
            vn = np.full(n, 1.5)
        else:
            w = V / S * T  # the distance at speed |V| over T
            for j in np.flatnonzero(moving):
                where = "" if scalar else f" (axis {j})"
                lo = abs(b[j] - a[j]) / T
                if not w[j] > dist[j]:
                    raise ParameterError(
                        f"V = {V[j]:.6g} is too small{where}: |V| must exceed |qf - q0| / tf = {lo:.6g} "
                        "to arrive in time"
                    )
                if w[j] > 2 * dist[j] * (1 + 1e-12):
                    raise ParameterError(
                        f"V = {V[j]:.6g} is too large{where}: |V| must be at most 2 |qf - q0| / tf = "
                        f"{2 * lo:.6g} (there is no linear segment beyond it)"
                    )
            vn = np.where(moving, np.minimum(w / dist, 2.0), 1.5)
        beta = 1 - 1 / vn
        k = vn / beta
        s = (t / T)[:, None]
        r = 1 - s
        cases = [s <= beta, s <= 1 - beta, s <= 1]
        f = np.select(cases, [k / 2 * s * s, vn * s + (1 - vn) / 2, 1 - k / 2 * r * r], 1.0)
        fd = np.select(cases, [k * s, vn + 0 * s, k * r], 0.0)
        fdd = np.select(cases, [k + 0 * s, 0 * s, -k + 0 * s], 0.0)
        q = np.where(moving, a * (1 - f) + b * f, a)  # within [a, b]: no overflow; q0 where it stays
        qd = np.where(moving, (d * fd / T) * S, 0.0)
        qdd = np.where(moving, (d * fdd / T / T) * S, 0.0)
        tb = np.where(moving, beta * T, np.inf)
        v = np.where(moving, (d * vn / T) * S, 0.0)
    return q, qd, qdd, tb, v


def unit_trapezoidal(s: np.ndarray) -> np.ndarray:
    """The path parameter (N,) of ``trapezoidal(0, 1, ...)`` at normalised times ``s`` (N,) in [0, 1]:
    rest to rest with a constant-speed middle third (RTB's ``ctraj`` profile)."""
    return _lspb(np.zeros(1), np.ones(1), 1.0, np.asarray(s, dtype=float), None)[0][:, 0]


def trapezoidal(q0: Any, qf: Any, t: Any, V: Any = None) -> Trajectory:
    """Linear segment with parabolic blends from ``q0`` to ``qf`` (RTB's ``trapezoidal``, ``lspb``):
    constant acceleration from rest for ``tblend``, constant speed ``V``, constant deceleration to rest
    at the end, symmetric. Numbers, or vectors (n,) with one profile per axis over the same times.

    ``t`` as :func:`quintic`: an int m (steps 0..m-1, duration ``tf = m - 1``) or times, the motion
    running from ``t[0]`` to ``t[-1]`` (``tf = t[-1] - t[0]``, as RTB 1.5).
    ``V``: the speed of the linear segment, a number or (n,) (its sign is taken from ``qf - q0``);
    default RTB's ``1.5 (qf - q0) / tf``, which makes ``tblend = tf / 3``. An axis that moves needs
    ``|qf - q0| / tf < |V| <= 2 |qf - q0| / tf`` (slower cannot arrive in time; faster than the upper
    bound has no linear segment): ParameterError otherwise, and for values beyond a double. ``info``
    holds ``tblend`` and ``V``.
    """
    a, b, scalar = _endpoints(q0, qf, vector=False)
    t, tau, T, istime = _times(t, "start")
    speed = None if V is None else np.abs(_boundary(V, a.size, "V"))
    q, qd, qdd, tb, v = _lspb(a, b, T, tau, speed, scalar)
    _checked("trapezoidal", t, q, qd, qdd, _SHORT)
    info = {"tblend": float(tb[0]) if scalar else tb, "V": float(v[0]) if scalar else v}
    return Trajectory(
        "trapezoidal", t, _shaped(q, scalar), _shaped(qd, scalar), _shaped(qdd, scalar), istime, info
    )


# -- multi-segment ----------------------------------------------------------------------------
def _steps(x: float, dt: float, what: str) -> int:
    """ceil(x / dt) with slack for rounding (RTB's ``ceil(x / dt)``); ParameterError beyond
    :data:`MAX_SAMPLES`."""
    with np.errstate(over="ignore"):
        r = float(x) / dt
    _room(_count(r, what))
    return max(0, math.ceil(r - _EPS_STEPS))


def _room(samples: float, n: int | None = None) -> None:
    """ParameterError when ``samples`` samples of t, q, qd and qdd (of ``n`` axes; None: at least
    one) would not fit in memory."""
    from symkin.core.sizes import room

    axes = f" x {n} axes" if n else ""
    room(8.0 * samples * (1 + 3 * (n or 1)), f"a trajectory of {samples:.6g} samples{axes}")


def mstraj(
    viapoints: Any,
    dt: float,
    tacc: Any,
    qdmax: Any = None,
    tsegment: Any = None,
    q0: Any = None,
    qd0: Any = None,
    qdf: Any = None,
) -> Trajectory:
    """Multi-segment multi-axis trajectory through via points (RTB's ``mstraj``), sampled every ``dt`` s.

    ``viapoints`` (M, n): one row per via point; the motion starts at ``q0`` (n,), default the first
    row (which then is not a via point), and ends at rest (``qdf``, default 0) at the last row. Between
    consecutive points the axes move together along a straight line at constant velocity; around each
    intermediate via point a quintic blend of duration ``tacc`` (s, a number or one per segment, rounded
    up to a multiple of dt) joins the two velocities, so the path passes near, not through, the via
    point. The first segment starts (from ``qd0``, default rest) and the last ends with a blend of half
    of ``tacc``.

    Segment durations: ``qdmax`` (a number or (n,), > 0): each segment lasts as long as its slowest axis
    needs at speed ``qdmax`` (rounded up to dt) plus the blend, at least ``2 tacc``; so the linear parts
    stay below ``qdmax`` (the blends from and to rest reach up to 1.5 times the linear speed, as in RTB).
    Or ``tsegment`` (M,): the duration of each segment (s). Give exactly one of them.

    Returns ``t = dt * arange(N)``, ``q[0] = q0`` and ``q``, ``qd``, ``qdd`` (N, n) from the linear and
    polynomial pieces; ``info`` holds ``via``, ``segtime``, ``arrive`` and ``slowest``. With ``tacc`` an
    even multiple of dt the duration ``t[-1]`` is ``sum(segtime)``. ParameterError beyond
    :data:`MAX_SAMPLES` samples (a tiny ``dt`` or ``qdmax``, a huge ``tacc``) and for values beyond a
    double (via points too far apart).
    """
    dt = _positive(dt, "dt")
    W = _finite(viapoints, "viapoints")
    if W.ndim != 2 or W.shape[0] < 1 or W.shape[1] < 1:
        raise ParameterError(f"viapoints must be a matrix (M, n), one via point per row, got shape {W.shape}")
    if q0 is None:
        if W.shape[0] < 2:
            raise ParameterError(
                "viapoints needs at least 2 rows (the start and one via point) when q0 is None"
            )
        start, W = W[0], W[1:]
    else:
        start = _finite(q0, "q0")
        if start.shape != (W.shape[1],):
            raise ParameterError(f"q0 must have shape ({W.shape[1]},), one value per column of viapoints")
    ns, n = W.shape
    if (qdmax is None) == (tsegment is None):
        raise ParameterError("give exactly one of qdmax (axis speeds) and tsegment (segment durations)")
    if qdmax is not None:
        speed = _boundary(qdmax, n, "qdmax")
        if not (speed > 0).all():
            raise ParameterError(f"qdmax must be > 0, got {speed.tolist()}")
    else:
        seg_t = _finite(tsegment, "tsegment")
        if seg_t.shape != (ns,) or not (seg_t > 0).all():
            raise ParameterError(
                f"tsegment must be {ns} durations > 0 (one per segment), got {seg_t.tolist()}"
            )
    acc_t = _boundary(_finite(tacc, "tacc"), ns, "tacc", "segment")  # _finite: tacc=None is an error
    if (acc_t < 0).any():
        raise ParameterError(f"tacc must be >= 0, got {acc_t.tolist()}")
    v_start, v_end = _boundary(qd0, n, "qd0"), _boundary(qdf, n, "qdf")

    durations, speeds = (seg_t, None) if tsegment is not None else (None, speed)
    with np.errstate(over="ignore", invalid="ignore"):  # overflow is caught by _checked at the end
        return _mstraj_pieces(start, W, dt, acc_t, v_start, v_end, durations, speeds)


def _mstraj_pieces(
    start: np.ndarray, W: np.ndarray, dt: float, acc_t: np.ndarray, v_start: np.ndarray, v_end: np.ndarray,
    seg_t: np.ndarray | None, speed: np.ndarray | None,
) -> Trajectory:  # fmt: skip
    """:func:`mstraj` of checked inputs: the blends and linear parts of each segment (``seg_t``
    the durations, or None for ``speed``, the axes' qdmax)."""
    ns, n = W.shape
    pieces = [(start[None], v_start[None], np.zeros((1, n)))]  # (q, qd, qdd) of each piece
    q_prev, v_prev, last = start, v_start, start
    clock = 0
    segtime, arrive, slowest = np.zeros(ns), np.zeros(ns), np.full(ns, -1)
    ka2 = 0
    for seg in range(ns):
        q_next = W[seg]
        ka = _steps(acc_t[seg], dt, f"tacc / dt of segment {seg}")  # blend duration, steps
        ka2 = (ka + 1) // 2  # half of it, rounded up
        kx = ka2 if seg == 0 else ka  # this blend's duration
        dq = q_next - q_prev
        if seg_t is None:
            need = np.abs(dq) / speed  # each axis' time at qdmax (inf: beyond a double)
            tt = kx + np.array([_steps(x, dt, f"segment {seg} at qdmax, in steps of dt") for x in need])
            slowest[seg] = int(np.argmax(tt))
            kseg = int(tt.max())
            if kseg <= 2 * ka:  # RTB: best with some linear motion
                kseg = 2 * ka
            kseg = max(kseg, 2 * ka2 + 1)  # at least one linear sample
            tseg = kseg * dt
            if not math.isfinite(tseg):
                raise ParameterError(
                    f"mstraj: segment {seg} lasts {kseg} steps of dt = {dt:g} s, beyond a double"
                )
        else:
            tseg = float(seg_t[seg])
            _count(tseg / dt, f"tsegment[{seg}] / dt")
            if round(tseg / dt) - ka2 < ka2 + 1:
                raise ParameterError(
                    f"tsegment[{seg}] = {tseg:g} s is too short for blends of {ka * dt:g} s: it needs "
                    f"at least {(2 * ka2 + 1) * dt:g} s (the blends and one linear step of dt)"
                )
        _room(clock + kx + tseg / dt + ka2, n)  # the samples so far and this segment's
        segtime[seg] = tseg
        arrive[seg] = clock * dt + tseg + (ka2 * dt if seg > 0 else 0.0)
        v = dq / tseg
        if kx > 0:  # the blend from the previous segment's velocity into this one's
            tau = np.arange(1, kx + 1) * dt
            pieces.append(_quintic(last, q_prev + ka2 * dt * v, v_prev, v, kx * dt, tau))
        clock += kx
        k = np.arange(ka2 + 1, round(tseg / dt) - ka2 + 1)  # the linear part
        s = (k * dt / tseg)[:, None]
        pieces.append(((1 - s) * q_prev + s * q_next, np.broadcast_to(v, (len(k), n)), np.zeros((len(k), n))))
        last = pieces[-1][0][-1]
        clock += len(k)
        _count(clock, "mstraj")
        q_prev, v_prev = q_next, v
    if ka2 > 0:  # the final blend to rest (or qdf) at the last via point
        tau = np.arange(1, ka2 + 1) * dt
        pieces.append(_quintic(last, q_prev, v_prev, v_end, ka2 * dt, tau))
    q_all, qd_all, qdd_all = (np.concatenate(p) for p in zip(*pieces))
    t = dt * np.arange(len(q_all))
    _checked("mstraj", t, q_all, qd_all, qdd_all, "give via points nearer each other, or a smaller dt")
    info = {"via": W.copy(), "segtime": segtime, "arrive": arrive, "slowest": slowest}
    return Trajectory("mstraj", t, q_all, qd_all, qdd_all, True, info)
