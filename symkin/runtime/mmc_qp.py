"""The MMC quadratic program (eq 12 of Haviland and Corke, Maximising Manipulability During Resolved-Rate
Motion Control, 2020, with bounds): assembly, closed form, exact solution.

NumPy only: the manipulability Jacobian (eq 11), the joint velocity bounds (speed limits and
velocity dampers), the QP matrices, the solution without inequalities, and an active-set solver.

The QP: min ``0.5 lam |qd|^2 - Jm.qd`` (``+ 0.5 w |s|^2`` with a slack) s.t. ``J qd (+ s) = nu``,
``lower <= qd <= upper``. :func:`active_set_solve` is a primal-dual active-set iteration: with a
guess of which bounds hold with equality, the optimality conditions are one 6x6 linear solve;
bounds that the free joints cross join the set, bounds whose multiplier has the wrong sign leave
it. When the set stops changing, the point satisfies all the optimality conditions of this strictly
convex QP: it is its unique solution, exact to rounding. Started from the bounds the closed form
crosses it usually settles in one to three solves. ``csrc/mmc_impl.h`` has the same in C.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from symkin.core.arrays import axes_rows as _axes

__all__ = [
    "MMCQP",
    "mmc_qp",
    "mmc_closed_form",
    "joint_velocity_bounds",
    "manipulability_jacobian",
    "distance_dampers",
    "fallback_step",
    "active_set_solve",
    "active_of",
    "active_of_osqp",
    "active_rows_of",
    "active_set_rows_solve",
]


def manipulability_jacobian(J: np.ndarray, H: np.ndarray, axes: str = "all") -> tuple[np.ndarray, float]:
    """Manipulability Jacobian (MMC paper eq 11) and m (eq 8) from J (6, n) and H (n, 6, n): ((n,), m).

    ``Jm_i = m vec(J H_i^T)^T vec((J J^T)^-1)`` over the rows chosen by ``axes``. At a singular
    configuration (J J^T not invertible) Jm is returned as zeros and m as 0.
    """
    rows = _axes(axes)
    Jr = J[rows]
    A = Jr @ Jr.T
    det = float(np.linalg.det(A))
    n = J.shape[1]
    if not det > 0.0:
        return np.zeros(n), 0.0
    m = math.sqrt(det)
    try:
        B = np.linalg.solve(A, Jr)  # (r, n) = (J J^T)^-1 J
    except np.linalg.LinAlgError:
        return np.zeros(n), 0.0
    Jm = m * (H[:, rows, :].reshape(n, -1) @ B.ravel())
    if not np.isfinite(Jm).all():
        return np.zeros(n), 0.0
    return Jm, m


def joint_velocity_bounds(
    q: np.ndarray,
    qlim: np.ndarray,
    qd_max: np.ndarray,
    joint_limits: bool = False,
    rho_i: float | np.ndarray = 0.9,
    rho_s: float | np.ndarray = 0.05,
    xi: float = 1.0,
    dt: float | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    """Bounds (lower, upper), each (n,), on qd: the speed limits -alpha <= qd <= alpha (MMC paper) and,
    with ``joint_limits``, velocity dampers.

    A joint closer than ``rho_i`` (influence distance) to its upper limit gets
    ``qd_i <= xi (q_max - q_i - rho_s) / (rho_i - rho_s)``, reaching 0 at the safety distance ``rho_s``;
    symmetrically ``qd_i >= -xi (q_i - q_min - rho_s) / (rho_i - rho_s)`` near the lower limit.
    Distances are in joint units (rad or m). The damper is a continuous-time constraint: a joint
    faster than ``rho_i / dt`` can jump over the influence zone in one step of an integration with
    time step ``dt``. Given ``dt``, every joint also gets ``|step| <= distance - rho_s``, i.e.
    ``-(q_i - q_min - rho_s) / dt <= qd_i <= (q_max - q_i - rho_s) / dt``, and the dampers only
    tighten that interval (a joint within ``rho_s`` of a limit is pushed back at most to ``rho_s``
    from the other one, however large ``xi / (rho_i - rho_s)``). Bounds are kept consistent
    (lower <= upper); the speed limits come before the step bound when the two conflict.
    """
    lower, upper = -qd_max.copy(), qd_max.copy()
    if joint_limits:
        rho_i = np.broadcast_to(np.asarray(rho_i, dtype=float), q.shape)
        rho_s = np.broadcast_to(np.asarray(rho_s, dtype=float), q.shape)
        width = rho_i - rho_s
        d_hi = qlim[1] - q
        d_lo = q - qlim[0]
        upper = np.where(d_hi < rho_i, np.minimum(upper, xi * (d_hi - rho_s) / width), upper)
        lower = np.where(d_lo < rho_i, np.maximum(lower, -xi * (d_lo - rho_s) / width), lower)
        if dt is not None:  # the dampers only tighten the step bound: a push-back from within
            lo_dt, hi_dt = -(d_lo - rho_s) / dt, (d_hi - rho_s) / dt  # rho_s stops at the far side
            upper = np.clip(upper, lo_dt, hi_dt)
            lower = np.clip(lower, lo_dt, hi_dt)
        upper = np.maximum(upper, -qd_max)
        lower = np.minimum(lower, qd_max)
        bad = lower > upper
        if bad.any():
            mid = 0.5 * (lower + upper)
            lower = np.where(bad, mid, lower)
            upper = np.where(bad, mid, upper)
    return lower, upper


class MMCQP(NamedTuple):
    """The MMC quadratic program (MMC paper eq 12 with bounds): min 0.5 x^T P x + c^T x, l <= A x <= u.

    ``x = qd`` (n,), or ``(qd, s)`` (n + 6,) with an equality slack ``s``. The first 6 rows of A are
    the equality ``J qd (+ s) = nu`` (l = u = nu); the next n rows are ``lower <= qd <= upper``;
    the last ``n_distance`` rows (collision avoidance) are ``Jd qd >= l`` (u = inf; see :func:`mmc_qp`).
    """

    P: np.ndarray  # (nx, nx) diagonal: lam I_n (and slack_weight I_6)
    c: np.ndarray  # (nx,) -Jm (and 0)
    A: np.ndarray  # (6 + n, nx): [[J, (I_6)], [I_n, (0)]]
    l: np.ndarray  # (6 + n,)
    u: np.ndarray  # (6 + n,)
    J: np.ndarray  # (6, n) base-frame Jacobian
    Jm: np.ndarray  # (n,) manipulability Jacobian
    manipulability: float
    n_distance: int = 0  # rows of distance constraints after the bounds

    @property
    def lower(self) -> np.ndarray:
        """The joint velocity lower bounds (n,)."""
        return self.l[6 : 6 + self.J.shape[1]]

    @property
    def upper(self) -> np.ndarray:
        """The joint velocity upper bounds (n,)."""
        return self.u[6 : 6 + self.J.shape[1]]

    @property
    def n(self) -> int:
        return self.J.shape[1]

    @property
    def has_slack(self) -> bool:
        return self.P.shape[0] > self.J.shape[1]


def mmc_qp(
    J: np.ndarray,
    Jm: np.ndarray,
    nu: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    lam: float = 0.005,
    slack_weight: float | None = None,
    manipulability: float = float("nan"),
    Jd: np.ndarray | None = None,
    d_lower: np.ndarray | None = None,
) -> MMCQP:
    """Assemble the MMC QP: min ``0.5 lam qd^T qd - Jm^T qd`` s.t. ``J qd = nu``, ``lower <= qd <= upper``.

    With ``slack_weight`` w, the equality becomes ``J qd + s = nu`` and ``0.5 w s^T s`` is added to
    the cost, so the QP stays feasible when the bounds cannot meet nu. ``Jd`` (M, n) and
    ``d_lower`` (M,) add the rows ``Jd qd >= d_lower``: the distances' rates of change bounded
    below (collision avoidance, :func:`distance_dampers`; ``-inf`` leaves a row free).
    """
    n = J.shape[1]
    ns = 0 if slack_weight is None else 6
    nd = 0 if Jd is None else Jd.shape[0]
    P = np.zeros((n + ns, n + ns))
    P[np.arange(n), np.arange(n)] = lam
    c = np.zeros(n + ns)
    c[:n] = -Jm
    A = np.zeros((6 + n + nd, n + ns))
    A[:6, :n] = J
    A[6 : 6 + n, :n] = np.eye(n)
    if nd:
        A[6 + n :, :n] = Jd
    if ns:
        P[np.arange(n, n + 6), np.arange(n, n + 6)] = slack_weight
        A[:6, n:] = np.eye(6)
    l = np.concatenate((nu, lower, d_lower if nd else np.zeros(0)))
    u = np.concatenate((nu, upper, np.full(nd, np.inf)))
    return MMCQP(P, c, A, l, u, J, Jm, manipulability, nd)


def distance_dampers(d: np.ndarray, d_i: float, d_s: float, xi: float) -> np.ndarray:
    """Lower bounds on the rates of change of the distances ``d`` (M,): the velocity damper of
    Haviland and Corke, NEO: A Novel Expeditious Optimisation Algorithm for Reactive Motion
    Control of Manipulators (IEEE RA-L, 2021), ``d_dot >= -xi (d - d_s) / (d_i - d_s)`` for a
    distance within the influence distance ``d_i`` (the approach slows to 0 at the safety distance
    ``d_s``; below it the shapes must part), ``-inf`` (no constraint) for the others."""
    return np.where(d < d_i, -xi * (d - d_s) / (d_i - d_s), -np.inf)


def fallback_step(
    qp: MMCQP, singular_tol: float = 1e-6, damping: float = 1e-2
) -> tuple[np.ndarray, str, float]:
    """(qd (n,), fallback, scale): the step of a QP no solver answered (a singular J, an infeasible
    or failed QP), as ``csrc/mmc_impl.h`` takes it: the resolved-rate step (Haviland and Corke,
    Manipulator Differential Kinematics, Part 1, 2023, eqs 35-36) ``J^T (J J^T)^-1 nu`` for
    ``qp.J`` and the equality's ``nu`` when J's smallest singular value is at least
    ``singular_tol``, else ``J^T (J J^T + damping^2 I)^-1 nu``; scaled down as a whole into the
    bounds when they contain 0, then clipped into them. ``fallback`` is ``"rrmc"``, or ``"zero"``
    when that step is not finite."""
    J, nu = qp.J, qp.l[:6]
    lower, upper = qp.lower, qp.upper
    G = J @ J.T
    try:
        if J.shape[1] < 6:
            raise np.linalg.LinAlgError("fewer than 6 joints: J J^T is singular")
        np.linalg.cholesky(G - singular_tol**2 * np.eye(6))
        qd = J.T @ np.linalg.solve(G, nu)
    except np.linalg.LinAlgError:
        try:
            qd = J.T @ np.linalg.solve(G + damping * damping * np.eye(6), nu)
        except np.linalg.LinAlgError:
            qd = np.full(J.shape[1], np.nan)
    fallback = "rrmc"
    if not np.isfinite(qd).all():
        qd, fallback = np.zeros(qp.n), "zero"
    scale = 1.0
    if (lower <= 0).all() and (upper >= 0).all():
        with np.errstate(divide="ignore", invalid="ignore"):
            r = np.where(qd > upper, upper / qd, np.where(qd < lower, lower / qd, 1.0))
        scale = float(np.clip(r, 0.0, 1.0).min())
        qd = qd * scale
    return np.clip(qd, lower, upper), fallback, scale


def mmc_closed_form(
    J: np.ndarray, Jm: np.ndarray, nu: np.ndarray, lam: float, slack_weight: float | None = None
) -> np.ndarray:
    """Solution of eq 12 without inequalities: ``J^+ nu + (I - J^+ J) Jm / lam`` (J of full row rank).

    With ``slack_weight`` w (the equality ``J qd + s = nu``, ``0.5 w |s|^2`` in the cost), the solution
    is ``z + J^T (J J^T + (lam / w) I)^-1 (nu - J z)``, ``z = Jm / lam``, and ``s = nu - J qd``.
    """
    z = Jm / lam
    A = J @ J.T
    if slack_weight is not None:
        A[np.diag_indices(6)] += lam / slack_weight
    return z + J.T @ np.linalg.solve(A, nu - J @ z)


# -- the active-set solve ---------------------------------------------------------------------------
def active_of(qd: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Active-set guess from a point: -1 at or below ``lower``, 1 above ``upper``, 2 where they are equal."""
    act = np.where(qd < lower - 1e-12, -1, np.where(qd > upper + 1e-12, 1, 0))
    return np.where(lower == upper, 2, act)


def active_of_osqp(x: np.ndarray, y: np.ndarray, lower: np.ndarray, upper: np.ndarray) -> np.ndarray:
    """Active-set guess from OSQP's qd ``x`` and the multipliers ``y`` of its bound rows (OSQP's polish
    rule): lower where ``x - lower < -y``, upper where ``upper - x < y``."""
    act = np.where(x - lower < -y, -1, np.where(upper - x < y, 1, 0))
    return np.where(lower == upper, 2, act)


def active_set_solve(
    J: np.ndarray,
    Jm: np.ndarray,
    nu: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    lam: float,
    slack_weight: float | None,
    act: np.ndarray,
    max_iter: int | None = None,
) -> tuple[np.ndarray, int] | None:
    """Solve the MMC QP from the active-set guess ``act`` (see :func:`active_of`).

    Returns ``(x, solves)`` with ``x = qd`` (n,) or ``(qd, s)`` (n + 6,), or None when the set did
    not settle within ``max_iter`` (default 2n + 2) solves, or the equality cannot be met with the
    bounds held (no slack and fewer than 6 free joints, or J of the free joints rank-deficient: the
    answer is checked against the equality).
    """
    n = J.shape[1]
    act = np.array(act, dtype=int)
    has_slack = slack_weight is not None
    scale = float(np.abs(Jm).max(initial=0.0))
    nu_tol = 1e-9 * (1.0 + float(np.abs(nu).max()))
    z = Jm / lam
    for it in range(1, (2 * n + 2 if max_iter is None else max_iter) + 1):
        free = act == 0
        if not has_slack and np.count_nonzero(free) < 6:
            return None
        bound = np.where(act > 0, upper, lower)
        JF = J[:, free]
        M = JF @ JF.T
        M /= lam
        if has_slack:
            M.flat[::7] += 1.0 / slack_weight
        try:
            ye = np.linalg.solve(M, J @ np.where(free, z, bound) - nu)  # J_F z_F + J_A b_A - nu
        except np.linalg.LinAlgError:
            return None
        jty = ye @ J
        x = np.where(free, z - jty / lam, bound)
        tol = 1e-12 * (1.0 + np.abs(x))
        below = free & (x < lower - tol)
        above = free & (x > upper + tol)
        # the multiplier Jm - lam x - J^T ye is >= 0 at an upper bound, <= 0 at a lower one
        wrong = (act * (Jm - lam * x - jty) < -1e-12 * (1.0 + scale + lam * np.abs(x))) & (np.abs(act) == 1)
        if below.any() or above.any() or wrong.any():
            act = np.where(below, -1, np.where(above, 1, np.where(wrong, 0, act)))
            continue
        s = -ye / slack_weight if has_slack else 0.0
        if not (np.abs(J @ x + s - nu).max() <= nu_tol and np.isfinite(x).all()):
            return None
        return (np.concatenate((x, s)) if has_slack else x), it
    return None


def active_rows_of(
    qd: np.ndarray, Jd: np.ndarray, d_lower: np.ndarray, y: np.ndarray | None = None
) -> np.ndarray:
    """Active-set guess of the distance rows ``Jd qd >= d_lower`` (free rows: ``-inf``): the rows that
    ``qd`` violates or meets, or with OSQP's multipliers ``y`` of those rows its polish rule
    (active where ``Jd qd - d_lower < -y``)."""
    r = Jd @ qd - d_lower
    rows = r < -1e-12 * (1.0 + np.abs(d_lower)) if y is None else r < -y
    return rows & np.isfinite(d_lower)


def _chol_solve(L: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(L L^T)^-1 b."""
    return np.linalg.solve(L.T, np.linalg.solve(L, b))


def active_set_rows_solve(
    J: np.ndarray,
    Jm: np.ndarray,
    nu: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    lam: float,
    slack_weight: float,
    Jd: np.ndarray,
    d_lower: np.ndarray,
    act: np.ndarray,
    rows: np.ndarray,
    max_iter: int | None = None,
) -> tuple[np.ndarray, int, np.ndarray, np.ndarray] | None:
    """Solve the MMC QP with the slack and the distance rows ``Jd qd >= d_lower`` (MMC(collision=...))
    from the active-set guesses ``act`` (bounds, see :func:`active_of`) and ``rows`` (bool, see
    :func:`active_rows_of`).

    With the slack eliminated (``s = nu - J qd``) the cost is ``0.5 qd^T H qd - g.qd``, ``H = lam I +
    w J^T J``, ``g = Jm + w J^T nu``. Holding the active bounds and rows as equalities, the free joints
    and the rows' multipliers ``mu`` solve ``H_FF qd_F = g_F - H_FA b_A + Jd_RF^T mu``,
    ``Jd_RF qd_F = d_R - Jd_RA b_A`` (through the Schur complement ``Jd_RF H_FF^-1 Jd_RF^T``). Free
    joints beyond a bound and violated rows join the set, active bounds and rows whose multiplier
    has the wrong sign leave it (the primal-dual iteration of :func:`active_set_solve`; rows join
    one at a time, the most violated first, so the active rows stay independent); when nothing
    changes every optimality condition holds: the point is the unique solution, exact to rounding.
    Returns ``(x, solves, act, rows)``, ``x = (qd, s)`` (n + 6,) and the settled active bounds and
    rows (the guesses' forms), or None when the set did not settle within
    ``max_iter`` (default 4n + 4) solves or the active rows are dependent on the free joints.
    """
    n = J.shape[1]
    act = np.array(act, dtype=int)
    finite = np.isfinite(d_lower)
    rows = np.asarray(rows, dtype=bool) & finite
    w = slack_weight
    H = w * (J.T @ J)
    H.flat[:: n + 1] += lam
    g = Jm + w * (J.T @ nu)
    scale = float(np.abs(g).max(initial=0.0))
    limit = 4 * n + 4 if max_iter is None else max_iter
    for it in range(1, limit + 1):
        free = act == 0
        R = np.flatnonzero(rows)
        if len(R) > np.count_nonzero(free):  # more active rows than free joints: dependent
            return None
        x = np.where(act > 0, upper, lower).astype(float)
        x[free] = 0.0
        try:
            Lf = np.linalg.cholesky(H[np.ix_(free, free)])
            rhs = g[free] - H[np.ix_(free, ~free)] @ x[~free]
            xf = _chol_solve(Lf, rhs)
            mu = np.zeros(0)
            if len(R):
                B = Jd[np.ix_(R, free)]
                Y = _chol_solve(Lf, B.T)
                Ls = np.linalg.cholesky(B @ Y)
                t0 = d_lower[R] - Jd[np.ix_(R, ~free)] @ x[~free]
                mu = np.zeros(len(R))
                for _ in range(2):  # the solve, then one refinement (H's condition is about w / lam)
                    dmu = _chol_solve(Ls, t0 - B @ xf)
                    mu, xf = mu + dmu, xf + Y @ dmu
        except np.linalg.LinAlgError:
            return None
        x[free] = xf
        grad = H @ x - g - Jd[R].T @ mu  # the bounds' multipliers: >= 0 at a lower bound, <= 0 at an upper
        tol = 1e-12 * (1.0 + np.abs(x))
        below = free & (x < lower - tol)
        above = free & (x > upper + tol)
        wrong = (np.abs(act) == 1) & (act * grad > 1e-12 * (1.0 + scale + lam * np.abs(x)))
        r = Jd[finite] @ x - d_lower[finite]
        r_scale = 1.0 + np.abs(d_lower[finite]) + np.abs(Jd[finite]) @ np.abs(x)
        join = np.zeros_like(rows)
        violated = ~rows[finite] & (r < -1e-12 * r_scale)
        if violated.any():  # the most violated row joins (one at a time: a set of rows stays independent)
            depth = np.where(violated, r / np.maximum(np.linalg.norm(Jd[finite], axis=1), 1e-300), np.inf)
            join[np.flatnonzero(finite)[int(np.argmin(depth))]] = True
        leave = np.zeros_like(rows)
        leave[R] = mu < -1e-12 * (1.0 + scale)
        if below.any() or above.any() or wrong.any() or join.any() or leave.any():
            act = np.where(below, -1, np.where(above, 1, np.where(wrong, 0, act)))
            rows = (rows | join) & ~leave
            continue
        # verify: the Schur complement may be numerically singular (rows dependent on the free joints)
        r_tol = 1e-8 * r_scale
        if not (
            np.isfinite(x).all()
            and (r >= -r_tol).all()
            and (np.abs(r[rows[finite]]) <= r_tol[rows[finite]]).all()
        ):
            return None
        return np.concatenate((x, nu - J @ x)), it, act, rows
    return None
