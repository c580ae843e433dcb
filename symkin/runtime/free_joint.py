"""Closed-form IK of a redundant arm with one joint given: ``kin.ik_all(T, free_joint=(j, values))``.

With joint ``j`` held at ``v`` the pose is ``T = P E_j(v) S``, ``E_j`` the joint's elementary
transform, ``P`` and ``S`` the chain before and after it. When ``j`` is the first joint of the
chain ``P`` is constant and the rest of the arm must reach ``P E_j(-v) P^{-1} T``; when ``j`` is the
last, ``S`` is constant and the rest must reach ``T S^{-1} E_j(-v) S``. That rest is the *sub-robot*,
the ETS without joint ``j`` (the arm with ``q_j = 0``): its geometry does not depend on ``v``, so its
closed form is derived and compiled once (:func:`symkin.runtime.analytic_ik.compile_analytic`, cached) and
each value of the sweep is one target pose of it. For a 7-joint arm the sub-robot has 6 joints and
gets every structure symkin solves, read from the base or from the tool (a spherical shoulder): the
Franka Emika Panda with ``q7`` given as in He and Liu (Analytical inverse kinematics for Franka Emika
Panda -- a geometrical solver for 7-DOF manipulators with unconventional design, ICCMA 2021), the
KUKA LBR iiwa 7 with ``q1`` or ``q7`` given. A middle joint is refused: held at ``v`` it changes the
geometry of the rest with ``v`` (for example it makes two axes parallel only at ``v = 0``).

The returned rows are full configurations (the given value in column ``j``, as given), verified,
wrapped and filtered as in :mod:`symkin.runtime.analytic_ik`; values equal mod 2 pi count once (so
the rows are distinct); ordered by the weighted distance to ``q0`` when given (else by value, then
branch). No sympy here.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np

from symkin.core.arrays import MAX_JOINT_VALUE, as_rows, real_array
from symkin.core.pose import pose_array
from symkin.errors import ConfigurationError, NoAnalyticIKError, SymkinError
from symkin.model.ets import ET, ETS
from symkin.model.kinematics import const_matrix
from symkin.model.robot import Robot
from symkin.runtime.analytic_ik import DUPLICATE_TOL, check_weights, ik_inputs, nearest_each
from symkin.runtime.ik import IKResult, check_pose

__all__ = ["FreeJointIK", "sub_robot", "free_joint_solver", "parse_free_joint", "FREE_SWEEP"]

FREE_SWEEP = 64  # values of the free joint swept by kin.ik(T, method="analytic", free_joint=j)
_TWO_PI = 2 * math.pi


def _const(ets: tuple[ET, ...]) -> np.ndarray:
    T = np.eye(4)
    for e in ets:
        T = T @ const_matrix(e.axis, e.const)  # type: ignore[arg-type]
    return T


def sub_robot(robot: Robot, j: int) -> tuple[Robot, str, np.ndarray, ET]:
    """The arm without joint ``j`` (joints after it renumbered down by one), which end of the chain
    ``j`` is (``"first"`` or ``"last"``), the constant transform on that side (``P`` or ``S``) and
    the joint's ET. ConfigurationError for a bad index, NoAnalyticIKError for a joint in the middle
    of the chain."""
    if not isinstance(j, (int, np.integer)) or isinstance(j, bool) or not 0 <= j < robot.n:
        raise ConfigurationError(f"free_joint must be a joint index 0..{robot.n - 1}, not {j!r}")
    j = int(j)
    ets = tuple(robot.ets)
    at = next(i for i, e in enumerate(ets) if e.joint == j)
    if all(e.joint is None for e in ets[:at]):
        end, side = "first", _const(ets[:at])
    elif all(e.joint is None for e in ets[at + 1 :]):
        end, side = "last", _const(ets[at + 1 :])
    else:
        chain = [e.joint for e in ets if e.joint is not None]
        raise NoAnalyticIKError(
            f"{robot.name}: free_joint={j} is in the middle of the chain: held at a value it changes the "
            f"geometry of the rest of the arm with that value, for which symkin derives no closed form. "
            f"Give the first or the last joint of the chain (free_joint={chain[0]} or {chain[-1]}), or use "
            "the numerical IK: kin.ik(T)"
        )
    rest = tuple(
        e if e.joint is None or e.joint < j else ET(e.axis, joint=e.joint - 1, flip=e.flip)
        for i, e in enumerate(ets)
        if i != at
    )
    keep = [k for k in range(robot.n) if k != j]
    sub = Robot(
        ETS(rest),
        name=f"{robot.name}_q{j}_given",
        qlim=np.asarray(robot.qlim)[:, keep],
        joint_names=tuple(robot.joint_names[k] for k in keep),
        source=f"{robot.name} with joint {j} given (symkin.runtime.free_joint)",
    )
    return sub, end, side, ets[at]


class FreeJointIK:
    """Every closed-form solution of a redundant arm for given values of one joint.

    Attributes: ``robot``, ``joint`` (the given joint's index), ``end`` (``"first"``/``"last"``),
    ``sub`` (the sub-robot) and ``solver`` (its :class:`symkin.runtime.analytic_ik.AnalyticIK`).
    """

    def __init__(self, robot: Robot, joint: int, backend: str = "c") -> None:
        from symkin.runtime.analytic_ik import compile_analytic

        self.robot = robot
        self.sub, self.end, self._side, self._et = sub_robot(robot, joint)
        self.joint = int(joint)
        try:
            self.solver = compile_analytic(self.sub, backend)
        except NoAnalyticIKError as exc:
            raise NoAnalyticIKError(
                f"{robot.name} with joint {joint} given: the remaining {self.sub.n}-joint arm has no closed "
                f"form ({exc}); try the other end joint or the numerical IK: kin.ik(T)"
            ) from None
        side_inv = np.linalg.inv(self._side)
        a = self._et.axis
        K = np.zeros((4, 4))
        if a.is_rotation:  # d/dx of the rotation about axis a: the skew matrix of e_a
            i, k = ((1, 2), (2, 0), (0, 1))[a.index]
            K[k, i], K[i, k] = 1.0, -1.0
        else:
            K[a.index, 3] = 1.0
        P, Pi = (self._side, side_inv) if self.end == "first" else (side_inv, self._side)
        self._gen = (P @ K @ Pi, P @ K @ K @ Pi)
        self._rev = np.array([e.is_revolute for e in robot.ets.joints], dtype=bool)
        self._qlim = np.asarray(robot.qlim, dtype=float)
        self.max_solutions = self.solver.max_solutions
        self._n = robot.n

    def __repr__(self) -> str:
        return f"FreeJointIK(robot={self.robot.name!r}, joint={self.joint}, rest={self.solver.kind!r})"

    def targets(self, T: np.ndarray, values: np.ndarray) -> np.ndarray:
        """The sub-robot's target poses, (N, V, 4, 4), for poses T (N, 4, 4) and values (V,):
        ``G(v) T`` (first joint) or ``T G(v)`` (last) with ``G(v) = I + sin(x) K1 + (1 - cos x) K2``
        (revolute) or ``I + x K1`` (prismatic), ``x = -v`` (the joint's sign folded in) and
        ``K1, K2`` the joint's generator and its square conjugated by the constant side."""
        x = -self._et.sign * np.asarray(values, dtype=float)
        K1, K2 = self._gen
        if self._et.axis.is_rotation:
            G = np.eye(4) + np.sin(x)[:, None, None] * K1 + (1.0 - np.cos(x))[:, None, None] * K2
        else:
            G = np.eye(4) + x[:, None, None] * K1
        if self.end == "first":
            return np.matmul(G[None], T[:, None])
        return np.matmul(T[:, None], G[None])

    def values(self, values: Any) -> np.ndarray:
        """``values`` as a 1-D array without repeats (within DUPLICATE_TOL, mod 2 pi for a revolute
        joint: such values give the same solutions), in the order given."""
        what = f"the values of free joint {self.joint}"
        v = np.atleast_1d(real_array(values, what))
        if v.ndim != 1 or v.size == 0 or not (np.abs(v) <= MAX_JOINT_VALUE).all():
            raise ConfigurationError(
                f"{what} must be a number or a 1-D array of finite numbers within +-{MAX_JOINT_VALUE:g}, "
                f"got {values!r}"[:300]
            )
        if len(v) == 1:
            return v
        key = np.remainder(v, _TWO_PI) if self._rev[self.joint] else v
        order = np.argsort(key, kind="stable")
        gap = np.diff(key[order])
        repeat = np.zeros(len(v), dtype=bool)
        repeat[order[1:]] = gap <= DUPLICATE_TOL
        # the largest and the smallest value equal mod 2 pi: one group across the wrap
        wraps = bool(self._rev[self.joint]) and key[order[0]] + _TWO_PI - key[order[-1]] <= DUPLICATE_TOL
        repeat[order[-1]] |= wraps
        if not repeat.any():
            return v
        # keep the first occurrence in the given order of each group of repeats
        group = np.cumsum(np.r_[True, gap > DUPLICATE_TOL])[np.argsort(order)]
        if wraps:
            group[group == group.max()] = 1
        _, first = np.unique(group, return_index=True)
        return v[np.sort(first)]

    def ik_all(
        self, T: Any, values: Any, q0: Any = None, joint_limits: bool = True, weights: Any = None
    ) -> np.ndarray:
        """Every distinct solution with ``q[joint]`` one of ``values``: T (4, 4) -> (k, n); T
        (N, 4, 4) -> (N, V * S, n) with NaN rows after each pose's k_i solutions (V values, S the
        sub-robot's maximum)."""
        Tb, single = _poses(T)
        v = self.values(values)
        N, V, n, j = len(Tb), len(v), self._n, self.joint
        Q0 = None if q0 is None else as_rows(q0, n, N, single, self.robot.name, "q0")
        w = None if weights is None else check_weights(weights, n)
        keep = [k for k in range(n) if k != j]
        Tv = np.ascontiguousarray(self.targets(Tb, v).reshape(N * V, 4, 4))
        q0s = None if Q0 is None else np.ascontiguousarray(np.repeat(Q0[:, keep], V, axis=0))
        ws = None if w is None else np.ascontiguousarray(w[keep])
        try:  # the C solver checks each target pose; a bad one is reported as the pose given
            sub = np.asarray(self.solver.ik_all(Tv, q0s, joint_limits, ws))  # (N*V, S, n-1)
        except SymkinError:
            check_pose(T)
            raise
        S = sub.shape[1]
        full = np.empty((N, V * S, n))
        full[..., keep] = sub.reshape(N, V * S, n - 1)
        full[..., j] = np.repeat(v, S)[None, :]  # the given values as given
        ok = ~np.isnan(full[..., keep[0]])
        if joint_limits:
            lo, hi = self._qlim[:, j]
            ok &= (full[..., j] >= lo) & (full[..., j] <= hi)
        # rows of one value are distinct (the sub-robot's filter merged them) and so are the values
        if Q0 is not None:
            d = ((1.0 if w is None else w) * (full - Q0[:, None, :]) ** 2).sum(axis=2)
            order = np.argsort(np.where(ok, d, np.inf), axis=1, kind="stable")
        else:
            order = np.argsort(~ok, axis=1, kind="stable")
        full = np.take_along_axis(full, order[..., None], axis=1)
        k = ok.sum(axis=1)
        full[np.arange(V * S)[None, :] >= k[:, None]] = np.nan
        if single:
            return full[0, : int(k[0])]
        return full

    def sweep(self, q0: np.ndarray | None, count: int = FREE_SWEEP) -> np.ndarray:
        """The default values of the given joint: ``count`` evenly over its limits (a revolute joint
        with limits wider than 2 pi: over one turn), plus ``q0[joint]`` when given."""
        lo, hi = self._qlim[:, self.joint]
        if self._rev[self.joint] and hi - lo > _TWO_PI:
            lo, hi = -math.pi, math.pi
        v = np.linspace(lo, hi, count)
        return v if q0 is None else np.append(float(q0[self.joint]), v)

    def _refine(
        self, T: np.ndarray, rows: np.ndarray, v: np.ndarray, q0: np.ndarray, joint_limits: bool, weights: Any
    ) -> np.ndarray:
        """Two finer sweeps (17 values over +- one step) around the value of the best row."""
        lo, hi = self._qlim[:, self.joint]
        h = float(np.max(np.abs(np.diff(np.sort(v))))) if len(v) > 1 else 0.1
        for _ in range(2):
            best = float(rows[0, self.joint])
            fine = np.linspace(best - h, best + h, 17)
            fine = fine[(fine >= lo) & (fine <= hi)] if joint_limits else fine
            more = self.ik_all(T, fine, q0, joint_limits, weights) if len(fine) else rows[:0]
            both = np.vstack((rows, more))
            d = ((1.0 if weights is None else weights) * (both - q0) ** 2).sum(axis=1)  # checked by ik
            rows = both[np.argsort(d, kind="stable")]
            h /= 8
        return rows

    def ik(
        self,
        Tep: Any,
        values: Any = None,
        q0: Any = None,
        weights: Any = None,
        joint_limits: bool = True,
        tol: float = 1e-6,
    ) -> IKResult:
        """The solution nearest ``q0`` (weighted) over the values as an :class:`IKResult`;
        ``success=False`` with a reason when no value gives a solution. Without ``values``: the
        :meth:`sweep`, then (with ``q0``) two finer sweeps of 17 values around the best one."""
        T, single, Q0, weights = ik_inputs(Tep, q0, weights, self.robot.n, self.robot.name)

        def solve(i: int, q0i: np.ndarray | None) -> tuple[np.ndarray, Callable[[], str]]:
            v = self.sweep(q0i) if values is None else self.values(values)
            rows = self.ik_all(T[i], v, q0i, joint_limits, weights)
            if values is None and q0i is not None and len(rows):
                rows = self._refine(T[i], rows, v, q0i, joint_limits, weights)
            why = f"no closed-form solution for the {len(v)} value(s) of joint {self.joint} tried"
            return rows, lambda: why + (" within the joint limits" if joint_limits else "")

        return nearest_each(T, single, Q0, self.robot.n, self.robot.fkine, tol, solve)


def _poses(T: Any) -> tuple[np.ndarray, bool]:
    """T as (N, 4, 4) floats (converted by the one rule, real_array) and whether it was one pose;
    the full check (check_pose) only when the shape is wrong, the values are checked by the solver."""
    Tb = pose_array(T)
    if Tb.shape == (4, 4):
        return Tb[None], True
    if Tb.ndim == 3 and Tb.shape[1:] == (4, 4):
        return Tb, False
    return check_pose(T)


_SOLVERS: dict[tuple[int, int, str], FreeJointIK] = {}


def free_joint_solver(robot: Robot, joint: int, backend: str = "c") -> FreeJointIK:
    """The :class:`FreeJointIK` of ``robot`` with ``joint`` given (kept per robot object)."""
    if robot.n < 7:
        raise ConfigurationError(
            f"free_joint= is for redundant arms (7 joints or more); {robot.name} has {robot.n}: "
            "use ik_all(T) without it"
        )
    key = (id(robot), int(joint) if isinstance(joint, (int, np.integer)) else -1, backend)
    hit = _SOLVERS.get(key)
    if hit is None or hit.robot is not robot:
        hit = _SOLVERS[key] = FreeJointIK(robot, joint, backend)
    return hit


def parse_free_joint(free_joint: Any) -> tuple[int, Any]:
    """``j`` or ``(j, values)`` -> (j, values or None)."""
    if isinstance(free_joint, tuple) and len(free_joint) == 2:
        return free_joint[0], free_joint[1]
    if isinstance(free_joint, (int, np.integer)) and not isinstance(free_joint, bool):
        return int(free_joint), None
    raise ConfigurationError(
        f"free_joint must be a joint index j or a pair (j, values), not {free_joint!r}"[:300]
    )
