"""The IK problem shared by the NumPy and C solvers: methods and options (:class:`IKOptions`),
results (:class:`IKResult`), the target-pose check, the angle-axis pose error (eqs 37-40 of
Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023) and the seeded random
restarts."""

from __future__ import annotations

import math
import os
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np

from symkin.core.arrays import as_batch, finite_number, name_of, per_joint, real_array, sample_bounds
from symkin.core.pose import as_poses, pose_array
from symkin.core.sizes import count
from symkin.errors import ParameterError, PoseError
from symkin.model.differential import NEAR_PI_L, angle_axis

Method = Literal["NR", "GN", "LM", "QP"]
Damping = Literal["wampler", "chan", "sugihara"]
METHODS = ("NR", "GN", "LM", "QP")
#: lam when it is not given: LM's damping, the QP's joint-velocity weight (symkin.runtime.ik_qp)
DEFAULT_LAM = {"QP": 0.01}
LM_LAM = 0.1
QP_RHO_I = 0.9  # rad or m: the QP's joint-limit dampers act within this distance of a limit
QP_RHO_S = 0.01  # rad or m: ... and stop a joint this far from it
DAMPINGS = ("wampler", "chan", "sugihara")
PINV_RCOND = 1e-12  # singular values <= PINV_RCOND * largest are dropped (same in C)
TWO_PI = 6.283185307179586
M64 = (1 << 64) - 1


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


def stacked(rows: list[tuple], n: int) -> IKResult:
    """The IKResult of N targets from their (q, success, iterations, searches, residual, reason)
    rows: arrays with a leading (N,) axis ((0, n) and (0,) for no targets)."""
    q, success, iterations, searches, residual, reason = zip(*rows, strict=True) if rows else ((),) * 6
    return IKResult(
        np.array(q, dtype=float).reshape(len(rows), n),
        np.array(success, dtype=bool),
        np.array(iterations, dtype=int),
        np.array(searches, dtype=int),
        np.array(residual, dtype=float),
        tuple(reason),
    )


def failure_reason(
    success: bool,
    residual: float,
    limit_rejects: int,
    singular: int,
    ilimit: int,
    slimit: int,
    collision_rejects: int = 0,
) -> str:
    """The ``reason`` text of a result (shared by the NumPy and C solvers)."""
    if success:
        return "success"
    parts = [f"no solution within {slimit} search(es) x {ilimit} iterations (best residual {residual:.3g})"]
    if limit_rejects:
        parts.append(f"{limit_rejects} converged solution(s) rejected for joint limits")
    if collision_rejects:
        parts.append(f"{collision_rejects} converged solution(s) rejected: in collision")
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
    # method="QP" (symkin.runtime.ik_qp): the slack's gain, the manipulability term's weight and
    # the joint-limit velocity dampers' gain, influence and stop distances
    slack_gain: float = 1.0
    manipulability: float = 0.0
    xi: float = 1.0
    rho_i: np.ndarray | None = None  # (n,)
    rho_s: np.ndarray | None = None  # (n,)

    @classmethod
    def of(
        cls,
        kin: Any,
        method: str = "LM",
        damping: str = "chan",
        lam: float | Sequence[float] | None = None,
        pinv: bool = False,
        ilimit: int = 30,
        slimit: int = 100,
        tol: float = 1e-6,
        tol_on: str = "e",
        joint_limits: bool = True,
        we: Sequence[float] | None = None,
        starts: Any = None,
        slack_gain: float = 1.0,
        manipulability: float = 0.0,
        xi: float = 1.0,
        rho_i: float | Sequence[float] = QP_RHO_I,
        rho_s: float | Sequence[float] = QP_RHO_S,
    ) -> IKOptions:
        n = int(kin.n)
        if n < 1:
            raise ParameterError("inverse kinematics needs a robot with at least one joint")
        method = str(method).upper()
        if method not in METHODS:
            raise ParameterError(f"method must be one of {METHODS}, not {method!r}")
        if lam is None:
            lam = DEFAULT_LAM.get(method, LM_LAM)
        damping = str(damping).lower()
        if damping not in DAMPINGS:
            raise ParameterError(f"damping must be one of {DAMPINGS}, not {damping!r}")
        if method == "NR" and not pinv and n != 6:
            raise ParameterError(
                f"NR without pinv needs a square Jacobian (6 joints), not {n}; use pinv=True or LM"
            )
        lam_a = per_joint(lam, n, "lam")
        we_a = np.ones(6) if we is None else real_array(we, "we", ParameterError)
        if we_a.shape != (6,) or not np.isfinite(we_a).all() or (we_a < 0).any() or not (we_a > 0).any():
            raise ParameterError(f"we must be 6 finite weights >= 0, not all 0, got {we!r}")
        ilimit, slimit = (
            count(ilimit, "ilimit", maximum=MAX_ITERATIONS),
            count(slimit, "slimit", maximum=MAX_ITERATIONS),
        )
        if ilimit * slimit > MAX_ITERATIONS:
            raise ParameterError(
                f"ilimit * slimit = {ilimit * slimit} exceeds {MAX_ITERATIONS} iterations per target "
                "(the iteration counters are 32-bit)"
            )
        tol = finite_number(tol, "tol")
        if tol_on not in ("e", "E"):
            raise ParameterError(f"tol_on must be 'e' (|e|_We < tol) or 'E' (E < tol), not {tol_on!r}")
        qlim = np.asarray(kin.qlim, dtype=float)
        if qlim.shape != (2, n) or np.isnan(qlim).any():
            raise ParameterError(f"kin.qlim must be a (2, {n}) array without NaN, got shape {qlim.shape}")
        rev = revolute_mask(kin)
        # start configurations: the joint-value rule of q (as_batch), (n,) or (S, n)
        S = np.zeros((0, n)) if starts is None else as_batch(starts, n, name_of(kin), "starts")[0]
        qp = _qp_options(n, method, lam_a, we_a, joint_limits, slack_gain, manipulability, xi, rho_i, rho_s)
        return cls(
            n, method, damping, _ro(lam_a), bool(pinv), int(ilimit), int(slimit), float(tol), tol_on,
            bool(joint_limits), _ro(we_a), _ro(qlim), _ro(sample_range(qlim, rev)), _ro(rev), _ro(S), *qp,
        )  # fmt: skip


MAX_ITERATIONS = 2**31 - 1  # ilimit * slimit: the C solver counts iterations in int32


def _qp_options(
    n: int, method: str, lam: np.ndarray, we: np.ndarray, joint_limits: Any, slack_gain: Any,
    manipulability: Any, xi: Any, rho_i: Any, rho_s: Any,
) -> tuple[float, float, float, np.ndarray, np.ndarray]:  # fmt: skip
    """The QP options, validated: (slack_gain, manipulability, xi, rho_i (n,), rho_s (n,))."""
    slack_gain = finite_number(slack_gain, "slack_gain")  # the MMC's checks of the same quantities
    manipulability = finite_number(manipulability, "manipulability", strict=False)
    xi = finite_number(xi, "xi")
    rho = [_ro(per_joint(rho_i, n, "rho_i")), _ro(per_joint(rho_s, n, "rho_s"))]
    if method == "QP":
        if not (lam == lam[0]).all() or not lam[0] > 0:
            raise ParameterError(
                f"method='QP' takes lam as one number > 0 (its joint-velocity weight), got {lam}"
            )
        if not (we > 0).all():
            raise ParameterError(
                f"method='QP' needs every weight of we > 0, got {we.tolist()}: its QP asks for the whole "
                "pose error (we weighs the residual only); for position-only IK use LM"
            )
        if joint_limits and not (rho[0] > rho[1]).all():
            raise ParameterError(f"rho_i ({rho_i}) must exceed rho_s ({rho_s}) for every joint")
    return slack_gain, manipulability, xi, rho[0], rho[1]


def _ro(a: np.ndarray) -> np.ndarray:
    """A read-only copy (never the caller's array: that one stays writable and may change later)."""
    a = np.array(a, order="C", copy=True)
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


def shift_into(x: float, lo: float, hi: float) -> float:
    """x moved by the multiple of 2 pi that brings it into [lo, hi], if there is one, else x (the
    rule of the C code for a revolute joint)."""
    y = x
    if y < lo:
        y += TWO_PI * math.ceil((lo - y) / TWO_PI)
    elif y > hi:
        y -= TWO_PI * math.ceil((y - hi) / TWO_PI)
    return y if lo <= y <= hi else x


def sample_range(qlim: np.ndarray, revolute: np.ndarray) -> np.ndarray:
    """(2, n) range random restarts are drawn from (:func:`symkin.core.arrays.sample_bounds`)."""
    return sample_bounds(qlim, revolute)


# -- random restarts --------------------------------------------------------------------------
def _mix64(z: int) -> int:
    z = ((z ^ (z >> 30)) * 0xBF58476D1CE4E5B9) & M64
    z = ((z ^ (z >> 27)) * 0x94D049BB133111EB) & M64
    return z ^ (z >> 31)


class SplitMix64:
    """The restart generator shared with the C solver: stream ``i`` of ``seed`` (target i)."""

    def __init__(self, seed: int, stream: int = 0) -> None:
        self.state = _mix64((int(seed) + _mix64(int(stream) + 1)) & M64)

    def uniform(self) -> float:
        self.state = (self.state + 0x9E3779B97F4A7C15) & M64
        return (_mix64(self.state) >> 11) * 2.0**-53

    def random_q(self, sample: np.ndarray) -> np.ndarray:
        lo, hi = sample
        return np.array(
            [float(lo[j]) + (float(hi[j]) - float(lo[j])) * self.uniform() for j in range(len(lo))]
        )


def seed_of(seed: Any = None) -> int:
    """The 64-bit seed of a solve: ``seed`` modulo 2^64, or a fresh random one when None."""
    return int.from_bytes(os.urandom(8), "little") if seed is None else int(seed) & M64


# -- pose error (eqs 37-40) -------------------------------------------------------------------
def check_pose(Tep: Any) -> tuple[np.ndarray, bool]:
    """Validate SE(3) targets: (4, 4) or (N, 4, 4) -> ((N, 4, 4) float array, was_single), by the one
    pose rule (:func:`symkin.core.pose.as_poses`): PoseError for a wrong shape, NaN/inf, a bottom row
    other than (0, 0, 0, 1), a rotation with ``max |R^T R - I| > 1e-6`` or a reflection (det R <= 0)."""
    return as_poses(Tep)


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
    if tr >= 0.0 or nl >= NEAR_PI_L:  # eq 38
        if nl == 0.0:
            return np.zeros(3)
        k = math.atan2(nl, tr - 1.0) / nl
        return np.array([k * l0, k * l1, k * l2])
    return angle_axis(R)  # near a half turn: the symmetric-part formula


def pose_error(Te: Any, Tep: Any) -> np.ndarray:
    """e of eq 37 for poses Te, Tep (..., 4, 4) -> (..., 6): (t* - t, alpha(R* R^T)), base frame.

    Both are checked by the one pose rule (:func:`symkin.core.pose.as_poses`; PoseError naming
    ``Te`` or ``Tep``), then :func:`pose_error_of` computes e."""
    A, B = pose_array(Te, "Te"), pose_array(Tep, "Tep")
    for X, what in ((A, "Te"), (B, "Tep")):
        as_poses(X.reshape(-1, 4, 4) if X.ndim > 3 and X.shape[-2:] == (4, 4) else X, what)
    try:
        np.broadcast_shapes(A.shape[:-2], B.shape[:-2])
    except ValueError:
        raise PoseError(f"Te {A.shape} and Tep {B.shape}: the stacks of poses do not broadcast") from None
    return pose_error_of(A, B)


def pose_error_of(Te: Any, Tep: Any) -> np.ndarray:
    """:func:`pose_error` of poses known to be valid (no checks: the solvers' and servo loops' own).

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
