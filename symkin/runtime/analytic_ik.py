"""Closed-form inverse kinematics at run time: every solution of a pose from the generated code.

:class:`AnalyticIK` wraps one generated module (C extension, NumPy or plain Python, see
:mod:`symkin.emit.analytic_ik`). The generated code computes every branch; what is returned is
filtered the same way on every backend (the C version does it in C):

1. a candidate flagged by its subproblems (clamped ``acos`` argument, singular, free joint) or of
   an arm with fewer than 6 joints is verified: ``max |T(q) - T| <= tol`` over the top 3x4 block;
2. each revolute joint is wrapped by 2 pi to the value nearest ``q0`` (0 without q0), then, if
   that is outside ``qlim``, to the value inside it when a 2 pi shift allows;
3. with ``joint_limits=True`` rows still outside ``qlim`` are dropped;
4. rows within 1e-6 of a kept one (every joint, angles mod 2 pi) are merged;
5. with ``q0`` the rows are ordered by ``sum_j w_j (q_j - q0_j)^2``.

No sympy here.
"""

from __future__ import annotations

import bisect
import functools
import math
from collections.abc import Callable
from types import ModuleType
from typing import Any

import numpy as np

from symkin.compiler.analytic_ik import analytic_key, build_analytic
from symkin.core.arrays import as_rows, real_array
from symkin.errors import ConfigurationError
from symkin.model.resolve import resolve_robot
from symkin.runtime.ik import IKResult, check_pose, pose_error_of
from symkin.runtime.ik_problem import shift_into, stacked
from symkin.runtime.memo import memoised

__all__ = [
    "AnalyticIK",
    "compile_analytic",
    "ik_inputs",
    "check_weights",
    "invalid_input",
    "nearest_each",
    "VERIFY_TOL",
    "DUPLICATE_TOL",
]

VERIFY_TOL = 1e-8  # max |T(q) - T| of a flagged candidate that is kept
DUPLICATE_TOL = 1e-6  # rows closer than this in every joint are one solution
_TWO_PI = 2 * math.pi


def check_weights(weights: Any, n: int) -> np.ndarray:
    """The distance weights of ``ik_all``: (n,) finite numbers >= 0 (converted by real_array)."""
    w = real_array(weights, "weights", items=f"{n} numbers")
    if w.shape != (n,) or not (np.isfinite(w).all() and (w >= 0).all()):
        raise ConfigurationError(
            f"weights must be {n} finite numbers >= 0; got shape {w.shape} {weights!r}"[:300]
        )
    return w


def ik_inputs(
    T: Any, q0: Any, weights: Any, n: int, name: str = "robot"
) -> tuple[np.ndarray, bool, np.ndarray | None, np.ndarray | None]:
    """The arguments of ``ik_all`` checked and converted, one rule for every backend: T -> (N, 4, 4)
    (:func:`symkin.runtime.ik.check_pose`), was_single, q0 -> (N, n) (one row per target, by
    :func:`symkin.model.robot.as_rows`: the joint-value rule of the kinematics) or None, weights ->
    (n,) or None; C-contiguous float64. The C extension calls it for any argument that is not a
    plain float64 array or that its own checks refuse, so it raises this function's errors."""
    Tb, single = check_pose(T)
    Q0 = None if q0 is None else np.ascontiguousarray(as_rows(q0, n, len(Tb), single, name, "q0"))
    w = None if weights is None else check_weights(weights, n)
    return np.ascontiguousarray(Tb), single, Q0, w


def invalid_input(what: str, value: Any, n: int) -> None:
    """Raise symkin's error for an invalid argument of ``ik_all`` that is not checked by
    :func:`ik_inputs` (called by the C extension)."""
    if what == "free_joint":
        raise ConfigurationError(
            f"free_joint= is for redundant arms (7 joints or more); this arm has {n} and a closed form: "
            "use ik_all(T) without it"
        )
    raise ConfigurationError(f"{what} must be {n} finite numbers; got {value!r}"[:300])


def nearest_each(
    T: np.ndarray,
    single: bool,
    Q0: np.ndarray | None,
    n: int,
    fk: Any,
    tol: float,
    solve: Callable[[int, np.ndarray | None], tuple[np.ndarray, Callable[[], str]]],
) -> IKResult:
    """The IKResult of the poses ``T`` (N, 4, 4) (one pose when ``single``; 0 iterations and one
    search each): for pose i the first (nearest) of the closed-form solutions ``rows`` (k, n) that
    ``solve(i, q0_i)`` returns, successful when its residual is below ``tol``; with no rows ``q0_i``
    (zeros without q0), failed, with the reason ``why()`` of the pair returned."""
    out = []
    for i in range(len(T)):
        q0 = None if Q0 is None else Q0[i]
        rows, why = solve(i, q0)
        q = rows[0] if len(rows) else np.zeros(n) if q0 is None else np.array(q0)
        r = float(np.linalg.norm(pose_error_of(np.asarray(fk(q)), T[i])))
        success = bool(len(rows)) and r < tol
        reason = "success" if success else f"closed-form solution has residual {r:.3g} >= tol {tol:g}"
        out.append((q, success, 0, 1, r, reason if len(rows) else why()))
    return IKResult(*out[0]) if single else stacked(out, n)


class AnalyticIK:
    """The closed-form solver of one robot on one backend (``kin.ik_all`` calls it).

    Attributes: ``robot``, ``backend``, ``n``, ``max_solutions`` (S), ``kind`` (the structure
    found), ``files`` (generated sources), ``module``.
    """

    def __init__(
        self, robot: Any, backend: str, module: ModuleType, files: dict[str, str], kind: str, S: int
    ) -> None:
        self.robot = robot
        self.backend = backend
        self.module = module
        self.files = files
        self.kind = kind
        self.max_solutions = int(S)
        self.n = int(robot.n)
        self._rev = np.array([e.is_revolute for e in robot.ets.joints], dtype=bool)
        self._qlim = np.ascontiguousarray(robot.qlim, dtype=float)
        if backend == "c":
            # the C method has ik_all's signature and the limits bound: no Python frame per call;
            # it hands any argument its own checks do not take to ik_inputs, as the code below
            inputs = functools.partial(ik_inputs, n=self.n, name=robot.name)
            self.ik_all = module.Solver(self._qlim, VERIFY_TOL, inputs).ik_all  # type: ignore[method-assign]

    def __repr__(self) -> str:
        return (
            f"AnalyticIK(robot={self.robot.name!r}, kind={self.kind!r}, S={self.max_solutions}, "
            f"backend={self.backend!r})"
        )

    # -- all solutions ------------------------------------------------------------------------
    def ik_all(
        self,
        T: Any,
        q0: Any = None,
        joint_limits: bool = True,
        weights: Any = None,
        tol: float = VERIFY_TOL,
    ) -> np.ndarray:
        """Every distinct solution of pose ``T`` (4, 4): (k, n), k <= S, ordered by distance to
        ``q0`` when given; for ``T`` (N, 4, 4): (N, S, n) with NaN rows after the k_i solutions."""
        Tb, single, Q0, w = ik_inputs(T, q0, weights, self.n, self.robot.name)
        N = len(Tb)
        qf = np.zeros((N, self.n)) if Q0 is None else Q0
        if self.backend == "numpy":
            Q, F = self.module.raw(Tb, qf)
        else:
            pairs = [self.module.raw(Tb[i].tolist(), qf[i].tolist()) for i in range(N)]
            Q = np.array([p[0] for p in pairs], dtype=float).reshape(N, self.max_solutions, self.n)
            F = np.array([p[1] for p in pairs], dtype=int).reshape(N, self.max_solutions)
        out = np.full((N, self.max_solutions, self.n), np.nan)
        for i in range(N):
            rows = self._finish(Tb[i], Q[i], F[i], None if Q0 is None else Q0[i], w, joint_limits, tol)
            out[i, : len(rows)] = rows
        if single:
            k = int((~np.isnan(out[0, :, 0])).sum())
            return out[0, :k]
        return out

    def _fk12(self, q: np.ndarray) -> np.ndarray:
        if self.backend == "numpy":
            return np.asarray(self.module.fk(q[None]))[0]
        return np.asarray(self.module.fk(q.tolist()), dtype=float)

    def _finish(
        self,
        T: np.ndarray,
        Q: np.ndarray,
        F: np.ndarray,
        q0: np.ndarray | None,
        w: np.ndarray | None,
        drop: bool,
        tol: float,
    ) -> np.ndarray:
        """Steps 1-5 of the module docstring for one pose (the C code does the same)."""
        lo, hi = self._qlim
        kept: list[np.ndarray] = []
        dist: list[float] = []
        target = T[:3].ravel()
        for q, flag in zip(Q, F):
            if flag < 0 or not np.isfinite(q).all():
                continue
            q = q.copy()
            if (self.module.CHECK_ALL or flag) and not np.abs(self._fk12(q) - target).max() <= tol:
                continue
            for j in np.flatnonzero(self._rev):
                ref = 0.0 if q0 is None else float(q0[j])
                q[j] = shift_into(ref + math.remainder(float(q[j]) - ref, _TWO_PI), lo[j], hi[j])
            if drop and ((q < lo) | (q > hi)).any():
                continue
            if any(self._same(q, k) for k in kept):
                continue
            d = 0.0 if q0 is None else float(((1.0 if w is None else w) * (q - q0) ** 2).sum())
            at = bisect.bisect_right(dist, d)  # after the rows as near (stable)
            kept.insert(at, q)
            dist.insert(at, d)
        return np.array(kept).reshape(len(kept), self.n)

    def _same(self, a: np.ndarray, b: np.ndarray) -> bool:
        d = a - b
        d = np.where(self._rev, np.remainder(d + math.pi, _TWO_PI) - math.pi, d)
        return bool((np.abs(d) <= DUPLICATE_TOL).all())

    # -- one solution as an IK result ---------------------------------------------------------
    def ik(
        self,
        Tep: Any,
        q0: Any = None,
        weights: Any = None,
        joint_limits: bool = True,
        tol: float = 1e-6,
        fkine: Any = None,
    ) -> IKResult:
        """The solution nearest ``q0`` (weighted) as an :class:`IKResult`: ``success=False`` with a
        reason when the pose is out of reach or every solution is outside the joint limits."""
        T, single, Q0, w = ik_inputs(Tep, q0, weights, self.n, self.robot.name)
        allq = self.ik_all(T, Q0, joint_limits, w)

        def solve(i: int, q0: np.ndarray | None) -> tuple[np.ndarray, Callable[[], str]]:
            rows = allq[i][~np.isnan(allq[i][:, 0])] if allq[i].size else allq[i]
            return rows, lambda: self._why(T[i], joint_limits)

        return nearest_each(T, single, Q0, self.n, fkine or self.robot.fkine, tol, solve)

    def _why(self, T: np.ndarray, joint_limits: bool) -> str:
        if joint_limits:
            free = self.ik_all(T, joint_limits=False)
            if len(free):
                return f"all {len(free)} closed-form solution(s) lie outside the joint limits"
        return "the pose is out of reach: no closed-form solution exists"


def compile_analytic(robot: Any, backend: str = "c", cache: bool = True) -> AnalyticIK:
    """The closed-form solver of ``robot`` (a Robot, built-in name or ETS text) on ``backend``
    (memoised; see :func:`symkin.compiler.analytic_ik.build_analytic`). Raises NoAnalyticIKError
    with the reason when the arm has no closed form."""
    if isinstance(robot, str):
        robot = resolve_robot(robot)

    def make() -> AnalyticIK:
        art, meta = build_analytic(robot, backend, cache)
        return AnalyticIK(robot, backend, art.module, art.files, meta["kind"], meta["S"])

    return memoised(("analytic-ik", analytic_key(robot, backend)), make, cache)
