"""Numerical inverse kinematics (Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, eqs
37-51), NumPy reference solver.

The error e (eq 37) is the base-frame translation error and the angle-axis vector alpha of
``R_target R^T`` (eqs 38-40); E = 1/2 e^T We e (eq 44). Steps:

- ``NR`` (eq 45): q += J^-1 e (``pinv``: pinv(We^1/2 J) We^1/2 e, the same for a square J);
- ``GN`` (eqs 46-47): q += (J^T We J)^-1 J^T We e (``pinv``: pinv of J^T We J);
- ``LM`` (eqs 48-51): q += (J^T We J + Wn)^-1 J^T We e with Wn = lam (``wampler``),
  lam E_k (``chan``, eq 50) or E_k + lam (``sugihara``, eq 51; lam is w_n).

Global search: a search runs at most ``ilimit`` iterations (one iteration evaluates the pose and,
unless it converged, takes a step); ``slimit`` searches start from q0, then ``starts[s]``, then
random configurations within the joint limits. A converged q has its revolute joints wrapped by
multiples of 2 pi into the limits; if it is still outside them it is rejected and the next search
starts. Iterations of failed searches count.

Convergence (``tol``): by default ``|e|_We = sqrt(e^T We e) < tol``, so with We = I and tol = 1e-6
the position is within 1 um and the orientation within 1 urad. The paper's criterion
``E < tol`` (``tol_on="E"``, Table 1) only bounds |e| by sqrt(2 tol): 1.4e-3 for tol = 1e-6.

Default: LM with Chan's damping, lam = 0.1, the fastest of Table 1 and the only damping that
keeps quadratic convergence near a solution (lam E_k -> 0). Constant damping (Wampler, Sugihara's
w_n) converges linearly where the solution is near a singularity: under ``|e| < 1e-6`` with
100 x 30 it failed 1.6% (Wampler 1e-4) to 7% (Sugihara 1e-3) of reachable UR5 targets, against
0% for Chan (``symkin.bench.ik``).

The C solver (:mod:`symkin.runtime.ik_c`) runs the same loop with the same random restarts
(splitmix64 streams), so the two agree iterate for iterate.
"""

from __future__ import annotations

import math
import numbers
import os
import weakref
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from symkin.errors import ParameterError, PoseError
from symkin.model.robot import as_batch, as_rows, name_of, real_array, sample_bounds

__all__ = [
    "IKResult",
    "IKOptions",
    "ik",
    "ik_trace",
    "angle_axis",
    "pose_error",
    "check_pose",
    "revolute_mask",
    "SplitMix64",
]

Method = Literal["NR", "GN", "LM"]
Damping = Literal["wampler", "chan", "sugihara"]
METHODS = ("NR", "GN", "LM")
DAMPINGS = ("wampler", "chan", "sugihara")
PINV_RCOND = 1e-12  # singular values <= PINV_RCOND * largest are dropped (same in C)
POSE_ATOL = 1e-6  # max |R^T R - I| of an accepted target
_BOTTOM_ATOL = 1e-12
_NEAR_PI_L = 1e-6
_TWO_PI = 6.283185307179586
_M64 = (1 << 64) - 1


# -- results ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False, slots=True)
class IKResult:
    """The outcome of :func:`ik`: one target, or arrays with a leading (N,) axis for N targets.

    Attributes:
        q: (n,) or (N, n) the solution; on failure the best iterate found (lowest residual).
        success: converged to ``tol`` within the joint limits.
        iterations: pose evaluations over all searches, failed ones included.
        searches: searches started.
        residual: ``|e|_We`` at ``q`` (E = residual**2 / 2).
        reason: ``"success"`` or why it failed (tuple of str for a batch).
    """

    q: np.ndarray
    success: bool | np.ndarray
    iterations: int | np.ndarray
    searches: int | np.ndarray
    residual: float | np.ndarray
    reason: str | tuple[str, ...]

    @property
    def batch(self) -> bool:
        return isinstance(self.reason, tuple)

    def __len__(self) -> int:
        if not self.batch:
            raise TypeError("a single IKResult has no len(); it is not a batch")
        return len(self.reason)

    def __getitem__(self, i: int) -> IKResult:
        """Result ``i`` of a batch."""
        if not self.batch:
            raise TypeError("a single IKResult cannot be indexed; it is not a batch")
        return IKResult(
            self.q[i],
            bool(self.success[i]),
            int(self.iterations[i]),
            int(self.searches[i]),
            float(self.residual[i]),
            self.reason[i],
        )


def failure_reason(
    success: bool, residual: float, limit_rejects: int, singular: int, ilimit: int, slimit: int
) -> str:
    """The ``reason`` text of a result (shared by the NumPy and C solvers)."""
    if success:
        return "success"
    parts = [f"no solution within {slimit} search(es) x {ilimit} iterations (best residual {residual:.3g})"]
    if limit_rejects:
        parts.append(f"{limit_rejects} converged solution(s) rejected for joint limits")
    if singular:
        parts.append(f"{singular} search(es) abandoned at a singular or diverging step")
    return "; ".join(parts)


# -- options ----------------------------------------------------------------------------------
@dataclass(frozen=True, eq=False)
class IKOptions:
    """Validated solver settings (see :func:`ik`); arrays are read-only."""

    n: int
    method: str
    damping: str
    lam: np.ndarray  # (n,)
    pinv: bool
    ilimit: int
    slimit: int
    tol: float
    tol_on: str
    joint_limits: bool
    we: np.ndarray  # (6,)
    qlim: np.ndarray  # (2, n)
    sample: np.ndarray  # (2, n) finite range of random restarts
    revolute: np.ndarray  # (n,) bool
    starts: np.ndarray  # (S, n)

    @classmethod
    def of(
        cls,
        kin: Any,
        method: str = "LM",
        damping: str = "chan",
        lam: float | Sequence[float] = 0.1,
        pinv: bool = False,
        ilimit: int = 30,
        slimit: int = 100,
        tol: float = 1e-6,
        tol_on: str = "e",
        joint_limits: bool = True,
        we: Sequence[float] | None = None,
        starts: Any = None,
    ) -> IKOptions:
        n = int(kin.n)
        if n < 1:
            raise ParameterError("inverse kinematics needs a robot with at least one joint")
        method = str(method).upper()
        if method not in METHODS:
            raise ParameterError(f"method must be one of {METHODS}, not {method!r}")
        damping = str(damping).lower()
        if damping not in DAMPINGS:
            raise ParameterError(f"damping must be one of {DAMPINGS}, not {damping!r}")
        if method == "NR" and not pinv and n != 6:
            raise ParameterError(
                f"NR without pinv needs a square Jacobian (6 joints), not {n}; use pinv=True or LM"
            )
        try:
            lam_a = np.broadcast_to(real_array(lam, "lam", ParameterError), (n,)).copy()
        except ValueError:
            raise ParameterError(f"lam must be a number or {n} numbers, got {lam!r}") from None
        if not (np.isfinite(lam_a).all() and (lam_a >= 0).all()):
            raise ParameterError(f"lam must be finite and >= 0, got {lam!r}")
        we_a = np.ones(6) if we is None else real_array(we, "we", ParameterError)
        if we_a.shape != (6,) or not np.isfinite(we_a).all() or (we_a < 0).any() or not (we_a > 0).any():
            raise ParameterError(f"we must be 6 finite weights >= 0, not all 0, got {we!r}")
        ilimit, slimit = _count(ilimit, "ilimit"), _count(slimit, "slimit")
        if ilimit * slimit > MAX_ITERATIONS:
            raise ParameterError(
                f"ilimit * slimit = {ilimit * slimit} exceeds {MAX_ITERATIONS} iterations per target "
                "(the iteration counters are 32-bit)"
            )
        try:
            tol_ok = float(tol) > 0 and math.isfinite(float(tol))
        except (TypeError, ValueError):
            tol_ok = False
        if not tol_ok:
            raise ParameterError(f"tol must be a positive number, got {tol!r}")
        if tol_on not in ("e", "E"):
            raise ParameterError(f"tol_on must be 'e' (|e|_We < tol) or 'E' (E < tol), not {tol_on!r}")
        qlim = np.asarray(kin.qlim, dtype=float)
        if qlim.shape != (2, n) or np.isnan(qlim).any():
            raise ParameterError(f"kin.qlim must be a (2, {n}) array without NaN, got shape {qlim.shape}")
        rev = revolute_mask(kin)
        # start configurations: the joint-value rule of q (as_batch), (n,) or (S, n)
        S = np.zeros((0, n)) if starts is None else as_batch(starts, n, name_of(kin), "starts")[0]
        return cls(
            n, method, damping, _ro(lam_a), bool(pinv), int(ilimit), int(slimit), float(tol), tol_on,
            bool(joint_limits), _ro(we_a), _ro(qlim), _ro(sample_range(qlim, rev)), _ro(rev), _ro(S),
        )  # fmt: skip


MAX_ITERATIONS = 2**31 - 1  # ilimit * slimit: the C solver counts iterations in int32


def _count(value: Any, name: str) -> int:
    """An iteration or search limit: an integer in 1 .. MAX_ITERATIONS, else ParameterError."""
    if isinstance(value, (bool, np.bool_)) or not isinstance(value, (numbers.Integral, float, np.floating)):
        raise ParameterError(f"{name} must be a positive integer, got {value!r}")
    if not (float(value).is_integer() and 1 <= value <= MAX_ITERATIONS):
        raise ParameterError(f"{name} must be an integer from 1 to {MAX_ITERATIONS}, got {value!r}")
    return int(value)


def _ro(a: np.ndarray) -> np.ndarray:
    a = np.ascontiguousarray(a)
    a.setflags(write=False)
    return a


def ets_of(kin: Any) -> Any:
    """``kin.ets``, or ``kin.robot.ets`` (compiled kinematics), or None."""
    ets = getattr(kin, "ets", None)
    return ets if ets is not None else getattr(getattr(kin, "robot", None), "ets", None)


def revolute_mask(kin: Any) -> np.ndarray:
    """(n,) bool: which joints are revolute, from ``kin.revolute`` or the ETS; else none."""
    rev = getattr(kin, "revolute", None)
    ets = ets_of(kin) if rev is None else None
    if ets is not None:
        rev = [e.is_revolute for e in ets.joints]
    if rev is None:
        return np.zeros(int(kin.n), dtype=bool)
    return np.asarray(rev, dtype=bool).reshape(int(kin.n))


def sample_range(qlim: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """(2, n) range random restarts are drawn from (:func:`symkin.model.robot.sample_bounds`)."""
    return sample_bounds(qlim, revolute)


# -- random restarts --------------------------------------------------------------------------
def _mix64(z: int) -> int:
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & _M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & _M64
    return z ^ (z >> 31)


class SplitMix64:
    """The restart generator shared with the C solver: stream ``i`` of ``seed`` (target i)."""

    def __init__(self, seed: int, stream: int = 0) -> None:
        self.state = _mix64((int(seed) + _mix64(int(stream) + 1)) & _M64)

    def uniform(self) -> float:
        self.state = (self.state + 0x9E3779B97F4A7C15) & _M64
        return (_mix64(self.state) >> 11) * 2.0**-53

    def random_q(self, sample: np.ndarray) -> np.ndarray:
        lo, hi = sample
        return np.array(
            [float(lo[j]) + (float(hi[j]) - float(lo[j])) * self.uniform() for j in range(len(lo))]
        )


def new_seed() -> int:
    """A fresh random 64-bit seed (used when ``seed`` is None)."""
    return int.from_bytes(os.urandom(8), "little")


# -- pose error (eqs 37-40) -------------------------------------------------------------------
def check_pose(Tep: Any) -> tuple[np.ndarray, bool]:
    """Validate SE(3) targets: (4, 4) or (N, 4, 4) -> ((N, 4, 4) float array, was_single).

    Raises PoseError for a wrong shape, NaN/inf, a bottom row other than (0, 0, 0, 1), a
    rotation with ``max |R^T R - I| > 1e-6`` or a reflection (det R < 0).
    """
    T = real_array(Tep, "a target pose", PoseError)
    single = T.ndim == 2
    if T.ndim not in (2, 3) or T.shape[-2:] != (4, 4):
        raise PoseError(f"a target pose must have shape (4, 4) or (N, 4, 4), got {T.shape}")
    if single:
        T = T[None]

    def where(i: int) -> str:
        return "the target" if single else f"target [{i}]"

    bad = ~np.isfinite(T).all(axis=(1, 2))
    if bad.any():
        raise PoseError(f"{where(int(np.argmax(bad)))} contains NaN or inf")
    bottom = np.abs(T[:, 3] - [0.0, 0.0, 0.0, 1.0]).max(axis=1) > _BOTTOM_ATOL
    if bottom.any():
        i = int(np.argmax(bottom))
        raise PoseError(f"{where(i)} has bottom row {T[i, 3].tolist()}, not [0, 0, 0, 1]")
    R = T[:, :3, :3]
    dev = np.abs(np.swapaxes(R, 1, 2) @ R - np.eye(3)).max(axis=(1, 2))
    if (dev > POSE_ATOL).any():
        i = int(np.argmax(dev > POSE_ATOL))
        raise PoseError(
            f"{where(i)} rotation is not orthonormal: max |R^T R - I| = {dev[i]:.3g} > {POSE_ATOL:g}"
        )
    det = np.linalg.det(R)
    if (det <= 0).any():
        i = int(np.argmax(det <= 0))
        raise PoseError(f"{where(i)} rotation is a reflection (det R = {det[i]:.3g})")
    return T, single


def angle_axis(R: Any) -> np.ndarray:
    """alpha(R) (eqs 38-40): the Euler vector of rotation matrices R (..., 3, 3) -> (..., 3).

    A diagonal R gives 0 for (1, 1, 1) and pi/2 (r11 + 1, r22 + 1, r33 + 1) otherwise (eq 40);
    other matrices use eq 38, except near pi (trace < 0 and |l| < 1e-6), where l of eq 39 is
    rounding noise and the axis comes from the symmetric part of R (its sign from l).
    """
    R = np.asarray(R, dtype=float)
    l = np.stack((R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]), -1)
    tr = np.trace(R, axis1=-2, axis2=-1)
    nl = np.sqrt((l * l).sum(-1))
    diag = R[..., [0, 0, 1, 1, 2, 2], [1, 2, 0, 2, 0, 1]] == 0
    diag = diag.all(-1)
    theta = np.arctan2(nl, tr - 1.0)
    with np.errstate(invalid="ignore", divide="ignore"):
        general = np.where((nl == 0)[..., None], 0.0, (theta / nl)[..., None] * l)
        ct = (tr - 1.0) / 2.0
        M = ((R + np.swapaxes(R, -1, -2)) / 2.0 - ct[..., None, None] * np.eye(3)) / (1.0 - ct)[
            ..., None, None
        ]
        d = np.diagonal(M, axis1=-2, axis2=-1)
        k = np.argmax(d, axis=-1)  # first maximum, like the C code
        ak = np.sqrt(np.maximum(np.take_along_axis(d, k[..., None], -1), 0.0))
        col = np.take_along_axis(M, k[..., None, None], -1)[..., 0]
        ax = col / ak
        ax = np.where(np.arange(3) == k[..., None], ak, ax)
        ax = np.where(((ax * l).sum(-1) < 0)[..., None], -ax, ax)
        near_pi = theta[..., None] * ax
    eq40 = np.where((tr > 0)[..., None], 0.0, math.pi / 2 * (np.diagonal(R, axis1=-2, axis2=-1) + 1.0))
    use_general = (tr >= 0) | (nl >= _NEAR_PI_L)
    return np.where(diag[..., None], eq40, np.where(use_general[..., None], general, near_pi))


def _angle_axis_one(R: np.ndarray) -> np.ndarray:
    """:func:`angle_axis` of one (3, 3) matrix with scalar arithmetic (the same branches)."""
    r = R.ravel().tolist()
    l0, l1, l2 = r[7] - r[5], r[2] - r[6], r[3] - r[1]
    tr = r[0] + r[4] + r[8]
    if r[1] == 0.0 and r[2] == 0.0 and r[3] == 0.0 and r[5] == 0.0 and r[6] == 0.0 and r[7] == 0.0:
        if tr > 0.0:
            return np.zeros(3)
        return math.pi / 2 * (np.array([r[0], r[4], r[8]]) + 1.0)  # eq 40
    nl = math.sqrt(l0 * l0 + l1 * l1 + l2 * l2)
    if tr >= 0.0 or nl >= _NEAR_PI_L:  # eq 38
        if nl == 0.0:
            return np.zeros(3)
        k = math.atan2(nl, tr - 1.0) / nl
        return np.array([k * l0, k * l1, k * l2])
    return angle_axis(R)  # near a half turn: the symmetric-part formula


def pose_error(Te: Any, Tep: Any) -> np.ndarray:
    """e of eq 37 for poses Te, Tep (..., 4, 4) -> (..., 6): (t* - t, alpha(R* R^T)), base frame.

    One pose pair is computed with scalar arithmetic in the order of the C code (``csrc/symkin_pose.h``),
    so both give the same numbers to the bit: the C and Python servo loops take the same steps."""
    Te, Tep = np.asarray(Te, dtype=float), np.asarray(Tep, dtype=float)
    if Te.shape == Tep.shape == (4, 4):
        a, b = Te.ravel().tolist(), Tep.ravel().tolist()
        R = np.array(
            [
                b[4 * i] * a[4 * j] + b[4 * i + 1] * a[4 * j + 1] + b[4 * i + 2] * a[4 * j + 2]
                for i in range(3)
                for j in range(3)
            ]  # fmt: skip
        ).reshape(3, 3)
        e = np.empty(6)
        e[:3] = (b[3] - a[3], b[7] - a[7], b[11] - a[11])
        e[3:] = _angle_axis_one(R)
        return e
    R = Tep[..., :3, :3] @ np.swapaxes(Te[..., :3, :3], -1, -2)
    return np.concatenate((Tep[..., :3, 3] - Te[..., :3, 3], angle_axis(R)), axis=-1)


# -- the solver -------------------------------------------------------------------------------
def wrap_into_limits(q: np.ndarray, opt: IKOptions) -> np.ndarray:
    """q with each revolute joint outside its limits moved by the multiple of 2 pi that brings it
    inside, if there is one (same as the C code)."""
    q = q.copy()
    lo, hi = opt.qlim
    for j in np.flatnonzero(opt.revolute):
        x = float(q[j])
        if x < lo[j]:
            x += _TWO_PI * math.ceil((lo[j] - x) / _TWO_PI)
        elif x > hi[j]:
            x -= _TWO_PI * math.ceil((x - hi[j]) / _TWO_PI)
        if lo[j] <= x <= hi[j]:
            q[j] = x
    return q


def _step(opt: IKOptions, J: np.ndarray, e: np.ndarray, r2: float) -> np.ndarray:
    """dq of eqs 45-51; raises LinAlgError when the system is singular."""
    we = opt.we
    if opt.method == "NR":
        if opt.pinv:
            s = np.sqrt(we)
            return np.linalg.pinv(s[:, None] * J, rcond=PINV_RCOND) @ (s * e)
        return np.linalg.solve(J, e)
    A = J.T @ (we[:, None] * J)
    g = J.T @ (we * e)
    if opt.method == "GN":
        return np.linalg.pinv(A, rcond=PINV_RCOND) @ g if opt.pinv else np.linalg.solve(A, g)
    E = 0.5 * r2
    wn = {"wampler": opt.lam, "chan": opt.lam * E, "sugihara": E + opt.lam}[opt.damping]
    return np.linalg.solve(A + np.diag(wn), g)


def _fkjac(kin: Any, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    return np.asarray(kin.fkine(q), dtype=float), np.asarray(kin.jacob0(q), dtype=float)


def _solve_one(kin: Any, opt: IKOptions, Tep: np.ndarray, q0: np.ndarray | None, rng: SplitMix64) -> tuple:
    """One target: (q, success, iterations, searches, residual, reason)."""
    lo, hi = opt.qlim
    best, best_q = math.inf, None
    iterations = limit_rejects = singular = 0
    q = np.zeros(opt.n)
    for s in range(opt.slimit):
        if s == 0 and q0 is not None:
            q = q0.copy()
        elif s < len(opt.starts):
            q = opt.starts[s].copy()
        else:
            q = rng.random_q(opt.sample)
        for i in range(opt.ilimit):
            T, J = _fkjac(kin, q)
            e = pose_error(T, Tep)
            iterations += 1
            r2 = float(opt.we @ (e * e))
            res = math.sqrt(r2) if r2 >= 0 else math.nan
            if not res < math.inf:
                singular += 1
                break
            if res < best:
                best, best_q = res, q.copy()
            if (0.5 * r2 < opt.tol) if opt.tol_on == "E" else (res < opt.tol):
                q = wrap_into_limits(q, opt)
                if not opt.joint_limits or bool(((q >= lo) & (q <= hi)).all()):
                    return q, True, iterations, s + 1, res, "success"
                limit_rejects += 1
                break
            if i + 1 == opt.ilimit:
                break
            try:
                with np.errstate(all="ignore"):
                    q = q + _step(opt, J, e, r2)
            except np.linalg.LinAlgError:
                singular += 1
                break
    q = wrap_into_limits(best_q if best_q is not None else q, opt)
    reason = failure_reason(False, best, limit_rejects, singular, opt.ilimit, opt.slimit)
    return q, False, iterations, opt.slimit, best, reason


def ik(
    kin: Any,
    Tep: Any,
    method: Method = "LM",
    damping: Damping = "chan",
    lam: float | Sequence[float] = 0.1,
    pinv: bool = False,
    ilimit: int = 30,
    slimit: int = 100,
    tol: float = 1e-6,
    q0: Any = None,
    seed: int | None = None,
    joint_limits: bool = True,
    we: Sequence[float] | None = None,
    tol_on: Literal["e", "E"] = "e",
    starts: Any = None,
    backend: Literal["numpy", "c"] = "numpy",
    frame: Any = None,
) -> IKResult:
    """Numerical IK: joint values q with ``kin.fkine(q)`` = ``Tep`` (eqs 37-51).

    Args:
        kin: kinematics with ``n``, ``qlim`` (2, n), ``fkine(q)`` (4, 4) and ``jacob0(q)`` (6, n)
            (a :class:`symkin.Robot` or a compiled backend); ``revolute`` or ``ets`` tells which
            joints wrap by 2 pi.
        Tep: target pose(s) 0T_e*, (4, 4) or (N, 4, 4); invalid SE(3) raises PoseError.
        method, damping, lam, pinv: the step (module docstring); ``lam`` is a scalar or (n,).
        ilimit: iterations per search; slimit: searches.
        tol, tol_on: converged when ``|e|_We < tol`` (``"e"``) or ``E < tol`` (``"E"``, the paper's).
        q0: first start, (n,) or (N, n) for N targets; then ``starts`` (S, n) for searches 1..S-1
            (search 0 too when q0 is None), then random restarts drawn from ``seed``.
        joint_limits: reject solutions outside ``kin.qlim`` (after wrapping revolute joints).
        we: the diagonal of We (6,), default ones (eq 44).
        backend: ``"numpy"`` (this module) or ``"c"`` (:class:`symkin.runtime.ik_c.CIKSolver`).
        frame: for a :class:`symkin.Tree` or its compiled kinematics, the frame (link name) whose
            pose is the task; the joints off its path are free (they keep their start values).

    Returns:
        IKResult; unreachable targets give ``success=False`` and a ``reason``.
    """
    if frame is not None or getattr(type(kin), "_symkin_tree", False):
        from symkin.model.frame_view import task_kinematics

        kin = task_kinematics(kin, frame)
    args = (method, damping, lam, pinv, ilimit, slimit, tol, tol_on, joint_limits, we, starts)
    if backend == "c":
        try:
            solver = _C_SOLVERS[kin][args]
        except (KeyError, TypeError):
            solver = _c_solver(kin, args)
        return solver.solve(Tep, q0, seed)
    opt = _options(kin, *args)
    if backend != "numpy":
        raise ParameterError(f"backend must be 'numpy' or 'c', not {backend!r}")
    T, single = check_pose(Tep)
    Q0 = _start_rows(q0, opt.n, len(T), single, name_of(kin))
    seed = new_seed() if seed is None else int(seed) & _M64
    out = [
        _solve_one(kin, opt, T[i], None if Q0 is None else Q0[i], SplitMix64(seed, i)) for i in range(len(T))
    ]
    if single:
        return IKResult(*out[0])
    if not out:  # no targets: empty arrays, like the C solver
        z = np.zeros(0, dtype=int)
        return IKResult(np.zeros((0, opt.n)), np.zeros(0, dtype=bool), z, z.copy(), np.zeros(0), ())
    q, success, iterations, searches, residual, reason = zip(*out, strict=True)
    return IKResult(
        np.array(q), np.array(success), np.array(iterations), np.array(searches), np.array(residual), reason
    )


_OPTIONS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()
_C_SOLVERS: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def _c_solver(kin: Any, args: tuple) -> Any:
    """The C solver for ``ik(kin, ..., backend="c")``, memoised per kinematics object and the
    arguments as passed when they are hashable, so a repeated call skips validating them."""
    from symkin.runtime.ik_c import solver_for

    solver = solver_for(kin, _options(kin, *args))
    try:
        cache = _C_SOLVERS.setdefault(kin, {})
        if len(cache) > 64:
            cache.clear()
        cache[args] = solver
    except TypeError:  # unhashable arguments (arrays) or an object without weak references
        pass
    return solver


def _options(kin: Any, *args: Any) -> IKOptions:
    """IKOptions.of, memoised per kinematics object for hashable arguments (validation costs
    tens of microseconds, more than a C solve)."""
    try:
        key = tuple(tuple(a) if isinstance(a, (list, tuple)) else a for a in args)
        hash(key)
        cache = _OPTIONS.setdefault(kin, {})
    except TypeError:  # unhashable arguments (arrays) or an object without weak references
        return IKOptions.of(kin, *args)
    opt = cache.get(key)
    if opt is None:
        if len(cache) > 64:
            cache.clear()
        opt = cache[key] = IKOptions.of(kin, *args)
    return opt


def _start_rows(q0: Any, n: int, N: int, single: bool, name: str = "robot") -> np.ndarray | None:
    """q0 as (N, n) rows (one per target), or None: the joint-value rule of q
    (:func:`symkin.model.robot.as_rows`), shared with the C solver and the closed form."""
    if q0 is None:
        return None
    return as_rows(q0, n, N, single, name, "q0")


def ik_trace(kin: Any, Tep: Any, q0: Any, steps: int, **options: Any) -> np.ndarray:
    """The iterates q_0 .. q_steps of one search from q0, not stopping at convergence:
    (k + 1, n), fewer rows if a step fails. For checking solvers against each other."""
    opt = IKOptions.of(kin, **options)
    T, single = check_pose(Tep)
    if not single:
        raise PoseError("ik_trace takes one target pose (4, 4)")
    q = _start_rows(q0, opt.n, 1, True, name_of(kin))[0].copy()  # type: ignore[index]
    out = [q.copy()]
    for _ in range(int(steps)):
        Te, J = _fkjac(kin, q)
        e = pose_error(Te, T[0])
        r2 = float(opt.we @ (e * e))
        if not math.isfinite(r2):
            break
        try:
            with np.errstate(all="ignore"):
                q = q + _step(opt, J, e, r2)
        except np.linalg.LinAlgError:
            break
        out.append(q.copy())
    return np.array(out)
