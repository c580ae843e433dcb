"""Trajectories with the semantics of roboticstoolbox-python (RTB, Corke, Robotics, Vision & Control in
Python, 3e, 2023, chap 3): scalar and joint-space quintics, trapezoidal (LSPB) profiles, multi-segment
via-point paths, Cartesian paths between two poses, and resolved-rate tracking of a Cartesian path.

numpy only (matplotlib for :meth:`Trajectory.plot`). Axis values are whatever the caller interpolates
(joint values in rad or m, Cartesian coordinates); times are in seconds, or in steps where RTB uses steps
(``quintic`` and ``trapezoidal`` with an integer ``t``). Poses are (4, 4) homogeneous transforms in the
robot's base frame; spatial velocities and pose errors have rows (v, omega) in the base frame, as
``jacob0`` and :func:`symkin.runtime.ik.pose_error` (eq 37 of Haviland and Corke, Manipulator
Differential Kinematics, Part 1, 2023).

Where this module deliberately differs from RTB 1.1 (RTB's behaviour is a bug or an accident there):

- ``jtraj(q0, qf, m)`` returns ``t = linspace(0, 1, m)``, the times its velocities refer to (RTB
  returns ``linspace(0, m, m)`` with velocities per unit of normalised time).
- ``mstraj`` includes the start ``q0`` as row 0 at ``t = 0`` (RTB leaves it out and starts its time
  vector at 0 one step later); ``mstraj(...).q[1:]`` are RTB's rows, and it returns ``qd`` and ``qdd``.
  It also computes step counts with integers (RTB's ``ceil(tacc / dt)`` rounds 1.1 / 0.1 up to 12) and
  gives every segment at least one linear sample (RTB jumps back to a stale point otherwise).
- ``trapezoidal`` with ``|V| = |qf - q0| / tf`` exactly is refused (RTB divides by a zero blend time).
"""

from __future__ import annotations

import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass, field
from types import MappingProxyType
from typing import Any

import numpy as np

from symkin.core.arrays import as_config, name_of, real_array
from symkin.errors import MissingExtraError, ParameterError, PoseError
from symkin.runtime.ik_problem import check_pose, pose_error
from symkin.runtime.servo import servo_gain

__all__ = [
    "Trajectory",
    "PathResult",
    "quintic",
    "jtraj",
    "trapezoidal",
    "mstraj",
    "ctraj",
    "servo_path",
]

_EPS_STEPS = 1e-9  # slack when counting time steps: 0.3 / 0.1 is 2.9999999999999996 steps, not 3


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


def _boundary(v: Any, n: int, what: str) -> np.ndarray:
    """A boundary velocity (or another value per axis): None (zero), a number for every axis, or (n,)."""
    if v is None:
        return np.zeros(n)
    a = _finite(v, what)
    if a.ndim == 0:
        return np.full(n, float(a))
    if a.shape != (n,):
        raise ParameterError(f"{what} must be a number or {n} numbers (one per axis), got shape {a.shape}")
    return a


def _times(t: Any, normalised: bool) -> tuple[np.ndarray, float, bool]:
    """(sample times, final time tf, istime) of ``t``: an integer m (m samples: step numbers 0..m-1, or
    ``linspace(0, 1, m)`` when ``normalised``) or a strictly increasing vector of times >= 0 (the motion
    runs from time 0 to ``t[-1]``)."""
    if isinstance(t, numbers.Integral) and not isinstance(t, (bool, np.bool_)):
        m = int(t)
        if m < 2:
            raise ParameterError(f"t as a number of samples must be at least 2, got {m}")
        _room(m)
        if normalised:
            return np.linspace(0.0, 1.0, m), 1.0, True
        return np.arange(m, dtype=float), float(m - 1), False
    a = real_array(t, "t", ParameterError)
    if a.ndim != 1 or a.size < 2:
        raise ParameterError(
            f"t must be an int (number of samples) or a vector of at least 2 times, got shape {a.shape}"
        )
    if not np.isfinite(a).all():
        raise ParameterError("t must be finite (no NaN or inf)")
    if a[0] < 0:
        raise ParameterError(f"t must start at time >= 0 (the motion starts at 0), got t[0] = {a[0]}")
    dt = np.diff(a)
    if not (dt > 0).all():
        i = int(np.argmax(~(dt > 0)))
        raise ParameterError(f"t must be strictly increasing, but t[{i + 1}] = {a[i + 1]} <= t[{i}] = {a[i]}")
    return a, float(a[-1]), True


def _positive(x: Any, what: str, allow_zero: bool = False) -> float:
    ok = isinstance(x, numbers.Real) and not isinstance(x, (bool, np.bool_)) and math.isfinite(x)
    if not ok or x < 0 or (x == 0 and not allow_zero):
        bound = ">= 0" if allow_zero else "> 0"
        raise ParameterError(f"{what} must be a finite number {bound}, got {x!r}")
    return float(x)


def _shaped(q: np.ndarray, scalar: bool) -> np.ndarray:
    return q[:, 0].copy() if scalar else q


# -- quintic polynomials ----------------------------------------------------------------------
def _quintic(
    q0: np.ndarray, qf: np.ndarray, qd0: np.ndarray, qd1: np.ndarray, T: float, t: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q, qd, qdd (len(t), n) of the quintic from (q0, qd0, 0) at time 0 to (qf, qd1, 0) at time T,
    at times t: RTB's ``jtraj`` polynomial in normalised time s = t / T."""
    d = qf - q0
    A = 6 * d - 3 * (qd1 + qd0) * T
    B = -15 * d + (8 * qd0 + 7 * qd1) * T
    C = 10 * d - (6 * qd0 + 4 * qd1) * T
    E = qd0 * T
    s = (t / T)[:, None]
    q = ((((A * s + B) * s + C) * s) * s + E) * s + q0
    qd = ((((5 * A * s + 4 * B) * s + 3 * C) * s) * s + E) / T
    qdd = (((20 * A * s + 12 * B) * s + 6 * C) * s) / T**2
    return q, qd, qdd


def quintic(q0: Any, qf: Any, t: Any, qd0: Any = None, qdf: Any = None) -> Trajectory:
    """A quintic polynomial from ``q0`` to ``qf`` (numbers, or vectors (n,) for n axes at once) with
    boundary velocities ``qd0``, ``qdf`` (default 0) and zero boundary accelerations (RTB's ``quintic``).

    ``t``: an int m, m samples at steps 0..m-1 (``istime`` False: qd per step, qdd per step squared,
    as RTB), or a strictly increasing vector of times >= 0, the motion running from time 0 to ``t[-1]``.
    ``q`` is (N,) for scalar endpoints, else (N, n).
    """
    a, b, scalar = _endpoints(q0, qf, vector=False)
    t, T, istime = _times(t, normalised=False)
    q, qd, qdd = _quintic(a, b, _boundary(qd0, a.size, "qd0"), _boundary(qdf, a.size, "qdf"), T, t)
    return Trajectory("quintic", t, _shaped(q, scalar), _shaped(qd, scalar), _shaped(qdd, scalar), istime)


def jtraj(q0: Any, qf: Any, t: Any, qd0: Any = None, qd1: Any = None) -> Trajectory:
    """Joint-space quintic from ``q0`` (n,) to ``qf`` (n,) (RTB's ``jtraj``): zero boundary
    accelerations, boundary velocities ``qd0``, ``qd1`` (default 0), all axes starting and stopping together.

    ``t``: an int m, m samples over normalised time 0..1 (``t = linspace(0, 1, m)``), or a strictly
    increasing vector of times >= 0, the polynomial scaled to run from time 0 to ``t[-1]``. ``q``,
    ``qd``, ``qdd`` are (N, n), per second.
    """
    a, b, _ = _endpoints(q0, qf, vector=True)
    t, T, _ = _times(t, normalised=True)
    q, qd, qdd = _quintic(a, b, _boundary(qd0, a.size, "qd0"), _boundary(qd1, a.size, "qd1"), T, t)
    return Trajectory("jtraj", t, q, qd, qdd, True)


# -- trapezoidal (LSPB) -----------------------------------------------------------------------
def trapezoidal(q0: Any, qf: Any, t: Any, V: Any = None) -> Trajectory:
    """Linear segment with parabolic blends from ``q0`` to ``qf`` (RTB's ``trapezoidal``, ``lspb``):
    constant acceleration from rest for ``tblend``, constant speed ``V``, constant deceleration to rest
    at ``tf``, symmetric. Numbers, or vectors (n,) with one profile per axis over the same times.

    ``t`` as :func:`quintic`: an int m (steps 0..m-1, ``tf = m - 1``) or times from 0 to ``tf = t[-1]``.
    ``V``: the speed of the linear segment, a number or (n,) (its sign is taken from ``qf - q0``);
    default RTB's ``1.5 (qf - q0) / tf``, which makes ``tblend = tf / 3``. An axis that moves needs
    ``|qf - q0| / tf < |V| <= 2 |qf - q0| / tf`` (slower cannot arrive in time; faster than the upper
    bound has no linear segment): ParameterError otherwise. ``info`` holds ``tblend`` and ``V``.
    """
    a, b, scalar = _endpoints(q0, qf, vector=False)
    t, T, istime = _times(t, normalised=False)
    d = b - a
    if V is None:
        v = 1.5 * d / T
    else:
        Va = _boundary(V, a.size, "V")
        v = np.abs(Va) * np.sign(d)
        for j in range(a.size):
            where = "" if scalar else f" (axis {j})"
            lo, hi = abs(d[j]) / T, 2 * abs(d[j]) / T
            if d[j] != 0 and not abs(v[j]) > lo:
                raise ParameterError(
                    f"V = {abs(Va[j]):.6g} is too small{where}: |V| must exceed |qf - q0| / tf = {lo:.6g} "
                    "to arrive in time"
                )
            if abs(v[j]) > hi * (1 + 1e-12):
                raise ParameterError(
                    f"V = {abs(Va[j]):.6g} is too large{where}: |V| must be at most 2 |qf - q0| / tf = "
                    f"{hi:.6g} (there is no linear segment beyond it)"
                )
    moving = v != 0
    vs = np.where(moving, v, 1.0)
    tb = np.where(moving, (a - b + v * T) / vs, np.inf)
    acc = np.where(moving, v / np.where(moving, tb, 1.0), 0.0)
    tk = t[:, None]
    blend1, linear, blend2 = tk <= tb, tk <= T - tb, tk <= T
    q = np.select(
        [blend1, linear, blend2],
        [
            a + acc / 2 * tk**2,
            (b + a - v * T) / 2 + v * tk,
            b - acc / 2 * T**2 + acc * T * tk - acc / 2 * tk**2,
        ],
        b,
    )
    qd = np.select([blend1, linear, blend2], [acc * tk, v + 0 * tk, acc * T - acc * tk], 0.0)
    qdd = np.select([blend1, linear, blend2], [acc + 0 * tk, 0 * tk, -acc + 0 * tk], 0.0)
    q = np.where(moving, q, a)  # an axis that does not move stays at q0
    info = {"tblend": float(tb[0]) if scalar else tb, "V": float(v[0]) if scalar else v}
    return Trajectory(
        "trapezoidal", t, _shaped(q, scalar), _shaped(qd, scalar), _shaped(qdd, scalar), istime, info
    )


# -- multi-segment ----------------------------------------------------------------------------
def _steps(x: float, dt: float) -> int:
    """ceil(x / dt) with slack for rounding (RTB's ``ceil(x / dt)``); ParameterError when that many
    samples would not fit in memory."""
    _room(x / dt)
    return max(0, math.ceil(x / dt - _EPS_STEPS))


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
    even multiple of dt the duration ``t[-1]`` is ``sum(segtime)``.
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
        speed = _finite(qdmax, "qdmax")
        speed = np.full(n, float(speed)) if speed.ndim == 0 else speed
        if speed.shape != (n,) or not (speed > 0).all():
            raise ParameterError(
                f"qdmax must be a number or {n} numbers, all > 0, got {np.asarray(qdmax).tolist()}"
            )
    else:
        seg_t = _finite(tsegment, "tsegment")
        if seg_t.shape != (ns,) or not (seg_t > 0).all():
            raise ParameterError(
                f"tsegment must be {ns} durations > 0 (one per segment), got {seg_t.tolist()}"
            )
    acc_t = _finite(tacc, "tacc")
    acc_t = np.full(ns, float(acc_t)) if acc_t.ndim == 0 else acc_t
    if acc_t.shape != (ns,):
        raise ParameterError(
            f"tacc must be a number or {ns} numbers (one per segment), got shape {acc_t.shape}"
        )
    if (acc_t < 0).any():
        raise ParameterError(f"tacc must be >= 0, got {acc_t.tolist()}")
    v_start, v_end = _boundary(qd0, n, "qd0"), _boundary(qdf, n, "qdf")

    pieces = [(start[None], v_start[None], np.zeros((1, n)))]  # (q, qd, qdd) of each piece
    q_prev, v_prev, last = start, v_start, start
    clock = 0
    segtime, arrive, slowest = np.zeros(ns), np.zeros(ns), np.full(ns, -1)
    ka2 = 0
    for seg in range(ns):
        q_next = W[seg]
        ka = _steps(float(acc_t[seg]), dt)  # blend duration, steps
        ka2 = (ka + 1) // 2  # half of it, rounded up
        kx = ka2 if seg == 0 else ka  # this blend's duration
        dq = q_next - q_prev
        if tsegment is None:
            tt = kx + np.array([_steps(float(x), dt) for x in np.abs(dq) / speed])
            slowest[seg] = int(np.argmax(tt))
            kseg = int(tt.max())
            if kseg <= 2 * ka:  # RTB: best with some linear motion
                kseg = 2 * ka
            kseg = max(kseg, 2 * ka2 + 1)  # at least one linear sample
            tseg = kseg * dt
        else:
            tseg = float(seg_t[seg])
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
        q_prev, v_prev = q_next, v
    if ka2 > 0:  # the final blend to rest (or qdf) at the last via point
        tau = np.arange(1, ka2 + 1) * dt
        pieces.append(_quintic(last, q_prev, v_prev, v_end, ka2 * dt, tau))
    q_all, qd_all, qdd_all = (np.concatenate(p) for p in zip(*pieces))
    info = {"via": W.copy(), "segtime": segtime, "arrive": arrive, "slowest": slowest}
    return Trajectory("mstraj", dt * np.arange(len(q_all)), q_all, qd_all, qdd_all, True, info)


# -- Cartesian --------------------------------------------------------------------------------
def _se3(T: Any, what: str) -> np.ndarray:
    """A validated (4, 4) pose (a numpy array, or anything with a ``.A`` array such as spatialmath's SE3)."""
    if not isinstance(T, np.ndarray) and hasattr(T, "A"):
        T = T.A
    try:
        T_all, single = check_pose(T)
    except PoseError as exc:
        msg = str(exc)
        raise PoseError(
            msg.replace("the target", what) if "the target" in msg else f"{what}: {msg}"
        ) from None
    if not single:
        raise PoseError(f"{what} must be one pose (4, 4), got shape {np.shape(T)}")
    return T_all[0]


def _quaternion(R: np.ndarray) -> np.ndarray:
    """Unit quaternion (w, x, y, z) of a rotation matrix (Shepperd's method, w >= 0 where it can)."""
    tr = np.trace(R)
    cands = np.array([tr, R[0, 0], R[1, 1], R[2, 2]])
    i = int(np.argmax(cands))
    if i == 0:
        r = math.sqrt(1.0 + tr) * 2
        q = [r / 4, (R[2, 1] - R[1, 2]) / r, (R[0, 2] - R[2, 0]) / r, (R[1, 0] - R[0, 1]) / r]
    elif i == 1:
        r = math.sqrt(max(1.0 + R[0, 0] - R[1, 1] - R[2, 2], 0.0)) * 2
        q = [(R[2, 1] - R[1, 2]) / r, r / 4, (R[0, 1] + R[1, 0]) / r, (R[0, 2] + R[2, 0]) / r]
    elif i == 2:
        r = math.sqrt(max(1.0 + R[1, 1] - R[0, 0] - R[2, 2], 0.0)) * 2
        q = [(R[0, 2] - R[2, 0]) / r, (R[0, 1] + R[1, 0]) / r, r / 4, (R[1, 2] + R[2, 1]) / r]
    else:
        r = math.sqrt(max(1.0 + R[2, 2] - R[0, 0] - R[1, 1], 0.0)) * 2
        q = [(R[1, 0] - R[0, 1]) / r, (R[0, 2] + R[2, 0]) / r, (R[1, 2] + R[2, 1]) / r, r / 4]
    q = np.array(q)
    q /= np.linalg.norm(q)
    return -q if q[0] < 0 else q


def _rotations(q: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) of unit quaternions (N, 4) (w, x, y, z)."""
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        -2,
    )


def _slerp(q0: np.ndarray, q1: np.ndarray, s: np.ndarray) -> np.ndarray:
    """Spherical linear interpolation (N, 4) of unit quaternions along the shorter arc."""
    dot = float(q0 @ q1)
    if dot < 0:  # q and -q are the same rotation: take the short way
        q1, dot = -q1, -dot
    theta = math.acos(min(dot, 1.0))
    if theta < 1e-9:
        q = (1 - s)[:, None] * q0 + s[:, None] * q1
    else:
        q = (np.sin((1 - s) * theta)[:, None] * q0 + np.sin(s * theta)[:, None] * q1) / math.sin(theta)
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def ctraj(T0: Any, T1: Any, t: Any = None, s: Any = None) -> np.ndarray:
    """Cartesian path from pose ``T0`` to ``T1`` (both (4, 4) in the same frame): (N, 4, 4) poses.

    The path parameter ``s`` in [0, 1] moves the origin along the straight line ``(1 - s) p0 + s p1``
    and the rotation along the geodesic from R0 to R1 (SLERP of unit quaternions, the shorter way), as
    RTB's ``ctraj`` (``T0.interp(T1, s)``). ``t``: an int N, ``s`` from ``trapezoidal(0, 1, N)`` (rest
    to rest with a constant-speed middle third), or a vector of times, ``s`` from
    ``trapezoidal(0, 1, t / t[-1])``. Or give ``s`` (N,) itself. ``s = 0`` and ``s = 1`` give ``T0``
    and ``T1`` exactly. PoseError for a T0 or T1 that is not SE(3).
    """
    A, B = _se3(T0, "T0"), _se3(T1, "T1")
    if (t is None) == (s is None):
        raise ParameterError("give exactly one of t (samples or times) and s (path parameters in [0, 1])")
    if t is not None:
        if isinstance(t, numbers.Integral) and not isinstance(t, (bool, np.bool_)):
            sv = trapezoidal(0.0, 1.0, int(t)).q
        else:
            times, T, _ = _times(t, normalised=False)
            sv = trapezoidal(0.0, 1.0, times / T).q
    else:
        sv = real_array(s, "s", ParameterError)
        if sv.ndim != 1 or sv.size < 1:
            raise ParameterError(f"s must be a vector of path parameters, got shape {sv.shape}")
        if not (np.isfinite(sv).all() and (sv >= 0).all() and (sv <= 1).all()):
            raise ParameterError("s must hold path parameters in [0, 1] (no NaN)")
    out = np.zeros((len(sv), 4, 4))
    out[:, 3, 3] = 1.0
    out[:, :3, 3] = (1 - sv)[:, None] * A[:3, 3] + sv[:, None] * B[:3, 3]
    out[:, :3, :3] = _rotations(_slerp(_quaternion(A[:3, :3]), _quaternion(B[:3, :3]), sv))
    out[sv == 0, :3, :3] = A[:3, :3]
    out[sv == 1, :3, :3] = B[:3, :3]
    return out


# -- tracking a Cartesian path ----------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class PathResult:
    """Resolved-rate tracking of a path of N poses (:func:`servo_path`).

    Attributes:
        q: (N, n) configurations, ``q[0] = q0``, ``q[i + 1] = q[i] + dt qd[i]``.
        qd: (N - 1, n) joint velocities.
        e: (N, 6) base-frame pose error (eq 37) of ``fkine(q[i])`` to ``poses[i]``: rows (position m,
            Euler vector rad).
        position_error: (N,) ``|e[:, :3]|``, metres.
        angle_error: (N,) ``|e[:, 3:]|``, the rotation angle between actual and wanted pose, radians.
        dt: the time step (s; 1.0 for one unit per step when not given).
    """

    q: np.ndarray
    qd: np.ndarray
    e: np.ndarray
    position_error: np.ndarray
    angle_error: np.ndarray
    dt: float

    @property
    def t(self) -> np.ndarray:
        """(N,) time of each configuration."""
        return np.arange(len(self.q)) * self.dt

    @property
    def max_position_error(self) -> float:
        """Largest position error over the path (m)."""
        return float(self.position_error.max())

    @property
    def max_angle_error(self) -> float:
        """Largest orientation error over the path (rad)."""
        return float(self.angle_error.max())

    def __repr__(self) -> str:
        return (
            f"PathResult({len(self.q)} poses, max_position_error={self.max_position_error:.3g} m, "
            f"max_angle_error={self.max_angle_error:.3g} rad)"
        )


def servo_path(
    kin: Any,
    poses: Any,
    q0: Any,
    gain: float | Any = 1.0,
    dt: float | None = None,
    frame: Any = None,
    feedforward: bool = True,
    damping: float = 0.0,
) -> PathResult:
    """Track the Cartesian path ``poses`` (N, 4, 4) (base frame, e.g. from :func:`ctraj`) with
    resolved-rate motion control from configuration ``q0`` (n,).

    At step i: the pose error ``e_i`` (eq 37, :func:`symkin.runtime.ik.pose_error`) of
    ``kin.fkine(q_i, frame=frame)`` to ``poses[i]``; the commanded base-frame spatial velocity
    ``nu = nu_ff + k e_i`` with the feed-forward ``nu_ff = pose_error(poses[i], poses[i + 1]) / dt``
    (the velocity that carries pose i to pose i + 1 in dt) and the feedback gain ``k`` (eq 42: a
    number, ``(k_t, k_r)`` or six values, 1/s); ``qd_i`` the least-squares (minimum-norm) solution of
    ``J0(q_i) qd = nu`` with ``J0 = kin.jacob0(q_i, frame=frame)`` (or the damped least-squares
    ``J^T (J J^T + damping^2 I)^-1 nu``); ``q_{i+1} = q_i + dt qd_i``.

    ``dt`` (s) is the time between consecutive poses; None means one time unit per pose, so that
    ``gain = 1`` corrects the whole error of a step in the next one. ``feedforward=False`` drops
    ``nu_ff`` (a pure position-based servo chasing each pose, one step behind). ``kin`` is any object
    with ``n``, ``fkine`` and ``jacob0`` (a :class:`symkin.Robot`, compiled kinematics, a tree with
    ``frame``); ``frame`` is passed to both when given. There are no joint limits or speed limits.
    """
    n = int(kin.n)
    q = as_config(q0, n, name_of(kin), "q0").copy()
    if not isinstance(poses, np.ndarray) and hasattr(poses, "A"):  # spatialmath SE3 with N values
        poses = np.asarray(poses.A)
    try:
        P, single = check_pose(poses)
    except PoseError as exc:
        raise PoseError(f"poses: {exc}") from None
    if single or len(P) == 0:
        raise ParameterError(f"poses must be a path of N >= 1 poses, shape (N, 4, 4), got {np.shape(poses)}")
    dt = 1.0 if dt is None else _positive(dt, "dt")
    k = servo_gain(gain)
    lam = _positive(damping, "damping", allow_zero=True)
    kw = {} if frame is None else {"frame": frame}
    N = len(P)
    Q, QD, E = np.zeros((N, n)), np.zeros((N - 1, n)), np.zeros((N, 6))
    for i in range(N):
        Q[i] = q
        E[i] = pose_error(np.asarray(kin.fkine(q, **kw), dtype=float), P[i])
        if i == N - 1:
            break
        nu = k * E[i]
        if feedforward:
            nu = nu + pose_error(P[i], P[i + 1]) / dt
        J = np.asarray(kin.jacob0(q, **kw), dtype=float)
        if lam > 0:
            qd = J.T @ np.linalg.solve(J @ J.T + lam**2 * np.eye(6), nu)
        else:
            qd = np.linalg.lstsq(J, nu, rcond=None)[0]
        QD[i] = qd
        q = q + dt * qd
    pos, ang = np.linalg.norm(E[:, :3], axis=1), np.linalg.norm(E[:, 3:], axis=1)
    return PathResult(Q, QD, E, pos, ang, dt)
