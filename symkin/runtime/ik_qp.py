"""QP inverse kinematics (Haviland and Corke, Manipulator Differential Kinematics, Part 2:
Acceleration and Advanced Applications, IEEE Robotics & Automation Magazine, 2023, "advanced
numerical inverse kinematics"): the quadratic program of one step (:func:`ik_qp`, the build) and
its solution (:func:`solve_ik_qp`), NumPy reference of the C step (``csrc/mmc_ik.c``).

``ik(kin, Tep, method="QP")`` runs the search loop of :func:`symkin.runtime.ik.ik` (restarts,
limits, results) with this step. At q, with the pose error e (Part 1, eq 37) and the base-frame
Jacobian J, the step qd solves

    min_x  1/2 x^T Q x + c^T x,    x = (qd, s) in R^(n+6)
    s.t.   J qd + s = e,           lower <= qd <= upper

    Q = diag(lam 1_n, (slack_gain / sum_i |e_i|) 1_6),   c = (-manipulability Jm, 0_6)

and the next iterate is q + qd. The slack s makes every step feasible; its weight grows as the
error shrinks, so that near a solution the step is the damped least-squares step
J^T (J J^T + lam sum|e| / slack_gain 1)^-1 e, whose damping vanishes with the error. Jm is the
manipulability Jacobian (Haviland and Corke, Maximising Manipulability During Resolved-Rate Motion
Control, 2020, eq 11); ``manipulability = 0`` drops the term (and the Hessian is not evaluated).

The joint limits enter as Part 2's velocity dampers: a joint within ``rho_i`` of a limit gets
``qd_i <= xi (q_max - q_i - rho_s) / (rho_i - rho_s)`` (``qd_i >= -xi (q_i - q_min - rho_s) /
(rho_i - rho_s)`` at the lower one), so it slows to a stop ``rho_s`` from the limit. Because a step
moves the joint by qd itself (a time step of 1), every joint also gets ``|qd_i| <= distance -
rho_s`` toward each limit: an iterate inside the limits stays at least ``rho_s`` inside them
(:func:`qp_bounds`), whatever the gains. A converged q is still checked against the limits, as for
the other methods, and a solution outside them is never returned as a success.

The parameters map onto roboticstoolbox-python's ``IK_QP(kj, ks, kq, km, ps, pi)`` and Part 2's
notebook as ``lam = kj`` (lambda_q), ``slack_gain = ks`` (lambda_delta), ``xi = 1 / kq`` (1 /
lambda_Sigma), ``manipulability = 1 / km`` (1 / lambda_m), ``rho_s = ps``, ``rho_i = pi``. RTB's
dampers are the same rows, without the step bound and on every joint (symkin leaves a revolute
joint whose range spans a full turn undamped: :func:`damped_limits`); with ``xi <= rho_i -
rho_s`` the damper is the tighter of the two, and :func:`ik_qp` has RTB's matrices (tested).

The QP is the MMC's (:func:`symkin.runtime.mmc_qp.mmc_qp` with the slack): the same closed form,
active-set solve and, in C, the same embedded OSQP (:mod:`symkin.runtime.mmc_c`); with the MMC's
collision rows (``kin.ik(Tep, method="QP", collision=env)`` on C kinematics) the step also keeps
the robot's distances to the obstacles above their dampers (``d_dot >= -xi_d (d - d_s) / (d_i -
d_s)``, :func:`~symkin.runtime.mmc_qp.distance_dampers`).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from symkin.errors import ParameterError
from symkin.runtime.ik_problem import TWO_PI, IKOptions
from symkin.runtime.mmc_qp import (
    MMCQP,
    active_of,
    active_of_osqp,
    active_rows_of,
    active_set_rows_solve,
    active_set_solve,
    fallback_step,
    joint_velocity_bounds,
    manipulability_jacobian,
    mmc_closed_form,
    mmc_qp,
)

__all__ = [
    "ik_qp",
    "build_ik_qp",
    "solve_ik_qp",
    "qp_bounds",
    "damped_limits",
    "qp_step",
    "manipulability_term",
    "SINGULAR_TOL",
]

#: a J whose smallest singular value is below this has no manipulability term (Jm = 0), as in C
SINGULAR_TOL = 1e-6


def qp_bounds(q: np.ndarray, opt: IKOptions) -> tuple[np.ndarray, np.ndarray]:
    """(lower, upper), each (n,): the bounds on one step qd at q (n,): the velocity dampers within
    ``rho_i`` of a limit and ``|qd_i| <= distance - rho_s`` (no bounds without ``joint_limits``)."""
    return joint_velocity_bounds(
        q, damped_limits(opt), np.full(opt.n, np.inf), opt.joint_limits, opt.rho_i, opt.rho_s, opt.xi, dt=1.0
    )


def damped_limits(opt: IKOptions) -> np.ndarray:
    """(2, n) the limits the dampers keep the iterates within: ``opt.qlim``, but none (+-inf) for a
    revolute joint whose range spans a full turn (every angle has an equivalent within its limits,
    to which the converged q is wrapped)."""
    lo, hi = opt.qlim
    free = opt.revolute & (hi - lo >= TWO_PI)
    return np.where(free, [[-np.inf], [np.inf]], opt.qlim)


def ik_qp(
    q: Any,
    J: Any,
    e: Any,
    opt: IKOptions,
    Jm: Any = None,
    Jd: Any = None,
    d_lower: Any = None,
) -> MMCQP:
    """The QP of one step at q (n,) (module docstring): min ``1/2 x^T P x + c^T x`` s.t.
    ``l <= A x <= u``, ``x = (qd, s)``.

    Args:
        q: the configuration (n,).
        J: the base-frame Jacobian at q (6, n), rows (v, omega).
        e: the pose error at q (6,) (Part 1 eq 37), not zero.
        opt: the options (``IKOptions.of(kin, method="QP", ...)``).
        Jm: the manipulability Jacobian at q (n,) (MMC paper eq 11); None or
            ``opt.manipulability == 0``: no manipulability term.
        Jd: collision rows ``Jd qd >= d_lower`` (M, n) (see
            :func:`~symkin.runtime.mmc_qp.distance_dampers`), or None.
        d_lower: their lower bounds (M,), ``-inf`` for a free row.

    Returns:
        an :class:`~symkin.runtime.mmc_qp.MMCQP`: P (n + 6, n + 6) = diag(lam 1_n,
        slack_gain / sum|e| 1_6), c = (-manipulability Jm, 0), A = [[J, 1_6], [1_n, 0], [Jd, 0]], l
        and u: (e, lower, d_lower) and (e, upper, inf).
    """
    q, J, e = (np.asarray(x, dtype=float) for x in (q, J, e))
    n = opt.n
    if q.shape != (n,) or J.shape != (6, n) or e.shape != (6,):
        raise ParameterError(
            f"ik_qp takes q ({n},), J (6, {n}) and e (6,), got {q.shape}, {J.shape}, {e.shape}"
        )
    total = float(np.abs(e).sum())
    if not (0.0 < total < math.inf):
        raise ParameterError(
            f"the pose error must be finite and not zero (the slack's weight is slack_gain / sum|e|), got {e}"
        )
    jm = (
        np.zeros(n)
        if Jm is None or opt.manipulability == 0
        else opt.manipulability * np.asarray(Jm, dtype=float)
    )
    lower, upper = qp_bounds(q, opt)
    return mmc_qp(J, jm, e, lower, upper, float(opt.lam[0]), opt.slack_gain / total, math.nan, Jd, d_lower)


def solve_ik_qp(qp: MMCQP) -> np.ndarray:
    """The step qd (n,) of a QP from :func:`ik_qp`, as the C step finds it: the closed form when it
    lies within the bounds (and there are no collision rows within reach), else the active-set
    solve (exact when it settles), else OSQP polished by the active-set solve from OSQP's active
    set; clipped into the bounds (OSQP's tolerance). When no solver answers (only an infeasible QP:
    collision rows against the bounds), the RRMC step scaled into the bounds
    (:func:`symkin.runtime.mmc_qp.fallback_step`)."""
    n, J, nu = qp.n, qp.J, qp.l[:6]
    lam, w = float(qp.P[0, 0]), float(qp.P[n, n])
    jm = -qp.c[:n]
    lower, upper = qp.lower, qp.upper
    Jd, dl = qp.A[6 + n :, :n], qp.l[6 + n :]
    near = bool(qp.n_distance and np.isfinite(dl).any())
    qd = mmc_closed_form(J, jm, nu, lam, w)
    act = active_of(qd, lower, upper)
    if near:
        found = active_set_rows_solve(J, jm, nu, lower, upper, lam, w, Jd, dl, act, np.zeros(len(dl), bool))
    elif np.isfinite(qd).all() and (qd >= lower - 1e-12).all() and (qd <= upper + 1e-12).all():
        return qd
    else:
        found = active_set_solve(J, jm, nu, lower, upper, lam, w, act)
    if found is None:
        x, y = _osqp(qp)
        if x is None:
            return fallback_step(qp)[0]
        act = active_of_osqp(x[:n], y[6 : 6 + n], lower, upper)
        if near:
            rows = active_rows_of(x[:n], Jd, dl, y[6 + n :])
            found = active_set_rows_solve(J, jm, nu, lower, upper, lam, w, Jd, dl, act, rows)
        else:
            found = active_set_solve(J, jm, nu, lower, upper, lam, w, act)
        if found is None:
            return np.clip(x[:n], lower, upper)
    return np.clip(found[0][:n], lower, upper)


def _osqp(qp: MMCQP) -> tuple[np.ndarray | None, np.ndarray]:
    """(x, y): OSQP's solution and multipliers of the QP (set up for this one problem, cold), or
    (None, _) when it is not usable (infeasible, failed)."""
    import osqp
    import scipy.sparse as sp

    from symkin.runtime.step import OSQP_SETTINGS, OSQP_STATUS

    inf = float(osqp.constant("OSQP_INFTY"))
    solver = osqp.OSQP()
    settings = {**OSQP_SETTINGS, "polishing": False, "warm_starting": False}
    l, u = np.maximum(qp.l, -inf), np.minimum(qp.u, inf)
    solver.setup(sp.csc_matrix(qp.P), qp.c, sp.csc_matrix(qp.A), l, u, **settings)
    res = solver.solve(raise_error=False)
    status = OSQP_STATUS.get(osqp.SolverStatus(res.info.status_val).name, "error")
    x = np.asarray(res.x, dtype=float)
    usable = status in ("solved", "inaccurate", "max_iter") and x.shape == (qp.P.shape[0],)
    return (x if usable and np.isfinite(x).all() else None), np.asarray(res.y, dtype=float)


def manipulability_term(kin: Any, q: np.ndarray, J: np.ndarray) -> np.ndarray | None:
    """Jm (n,) at q for the QP, or None when J is singular (smallest singular value below
    :data:`SINGULAR_TOL`, or n < 6), as in C."""
    if J.shape[1] < 6 or math.sqrt(max(float(np.linalg.eigvalsh(J @ J.T)[0]), 0.0)) < SINGULAR_TOL:
        return None
    jh = getattr(kin, "jacob0_hessian0", None)
    H = jh(q)[1] if jh is not None else kin.hessian0(q)
    return manipulability_jacobian(J, np.asarray(H, dtype=float))[0]


def build_ik_qp(kin: Any, q: Any, Tep: Any, frame: Any = None, **options: Any) -> MMCQP:
    """The QP (:func:`ik_qp`) of the step of ``ik(kin, Tep, method="QP", **options)`` at q (n,): J0,
    the pose error and, when ``manipulability > 0``, Jm from ``kin`` (any kinematics :func:`ik`
    takes; ``frame`` as there)."""
    from symkin.core.arrays import as_config, name_of
    from symkin.errors import PoseError
    from symkin.runtime.ik_problem import check_pose, pose_error
    from symkin.runtime.task import task_kinematics

    kin = task_kinematics(kin, frame)  # a chain itself, or one frame of a model
    opt = IKOptions.of(kin, method="QP", **options)
    q = as_config(q, opt.n, name_of(kin), "q")
    T, single = check_pose(Tep)
    if not single:
        raise PoseError("build_ik_qp takes one target pose (4, 4)")
    J = np.asarray(kin.jacob0(q), dtype=float)
    e = pose_error(np.asarray(kin.fkine(q), dtype=float), T[0])
    return ik_qp(q, J, e, opt, manipulability_term(kin, q, J) if opt.manipulability > 0 else None)


def qp_step(kin: Any, opt: IKOptions, q: np.ndarray, J: np.ndarray, e: np.ndarray) -> np.ndarray:
    """The QP step qd (n,) at q (n,) with J (6, n) and the pose error e (6,) there: the search step
    of ``ik(kin, Tep, method="QP")``; raises LinAlgError when there is none."""
    Jm = manipulability_term(kin, q, J) if opt.manipulability > 0 else None
    try:
        qp = ik_qp(q, J, e, opt, Jm)
    except ParameterError as exc:  # a zero or non-finite error: no step
        raise np.linalg.LinAlgError(str(exc)) from None
    return solve_ik_qp(qp)
