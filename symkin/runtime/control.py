"""Resolved-rate motion control (Haviland and Corke, Manipulator Differential Kinematics, Part 1, 2023, eqs
35-36) and the Manipulability Motion Controller
(Haviland and Corke, Maximising Manipulability During Resolved-Rate Motion Control, 2020, "the MMC paper").

numpy and OSQP (the reference path). ``kin`` is any object with ``n``, ``qlim`` (2, n), optionally
``qd_max`` (n,), and the base-frame ``jacob0(q)`` (6, n) and ``hessian0(q)`` (n, 6, n) (or
``jacobm(q, axes)``); a ``jacob0_hessian0(q) -> (J, H)`` method is used when present.
:class:`symkin.Robot` is one. For compiled C kinematics, :meth:`MMC.step` runs in C
(:mod:`symkin.runtime.mmc_c`).

Solver outcomes are reported in a :class:`StepInfo`, never raised; the joint velocity returned is
always finite.
"""

from __future__ import annotations

import contextlib
import math
import weakref
from typing import Any

import numpy as np

from symkin.core.arrays import AXES_ROWS as _AXES
from symkin.core.arrays import axes_rows as _axes
from symkin.core.arrays import finite_number as _number
from symkin.core.arrays import per_joint as _per_joint
from symkin.core.arrays import real_array
from symkin.core.sizes import count
from symkin.errors import ParameterError
from symkin.runtime.memo import bounded, per_object
from symkin.runtime.mmc_qp import (
    MMCQP,
    active_of,
    active_of_osqp,
    active_rows_of,
    active_set_rows_solve,
    active_set_solve,
    distance_dampers,
    fallback_step,
    joint_velocity_bounds,
    manipulability_jacobian,
    mmc_closed_form,
    mmc_qp,
)
from symkin.runtime.step import OSQP_SETTINGS, CStep, StepInfo, step_nu, step_q
from symkin.runtime.step import OSQP_STATUS as _OSQP_STATUS
from symkin.runtime.task import task_kinematics

__all__ = [
    "MMC",
    "MMCQP",
    "StepInfo",
    "rrmc",
    "servo_rrmc_step",
    "mmc_qp",
    "mmc_closed_form",
    "joint_velocity_bounds",
    "manipulability_jacobian",
]


def _speed_limits(kin: Any, n: int, qd_max: Any) -> np.ndarray:
    """(n,) joint speed limits: the given ones, else ``kin.qd_max``, else inf."""
    if qd_max is None:
        qd_max = getattr(kin, "qd_max", None)
    if qd_max is None:
        return np.full(n, np.inf)
    try:
        a = np.broadcast_to(real_array(qd_max, "qd_max", ParameterError), (n,)).copy()
    except ValueError:
        raise ParameterError(f"qd_max must be a number or {n} numbers, got {qd_max!r}") from None
    if not (a > 0).all() or np.isnan(a).any():
        raise ParameterError(f"qd_max must be positive (inf for no limit), got {a.tolist()}")
    return a


def scale_to_limits(qd: np.ndarray, qd_max: np.ndarray) -> tuple[np.ndarray, float]:
    """Scale qd down proportionally (keeping its direction) so that |qd_i| <= qd_max_i."""
    a = np.abs(qd)
    over = a > qd_max
    if not over.any():
        return qd, 1.0
    s = float((qd_max[over] / a[over]).min())
    return qd * s, s


# -- RRMC -----------------------------------------------------------------------------------------
def rrmc(
    kin: Any,
    q: Any,
    nu: Any,
    qd_max: Any = None,
    damping: float = 1e-2,
    singular_tol: float = 1e-6,
    axes: str = "all",
    qd_null: Any = None,
) -> tuple[np.ndarray, StepInfo]:
    """Resolved-rate motion control: qd = J0(q)^-1 nu (eq 35, 6 joints) or J0(q)^+ nu (eq 36, redundant).

    ``nu`` is the base-frame spatial velocity (v, omega), shape (6,); returns (qd (n,), info).
    When J0 has a singular value below ``singular_tol`` (or fewer than 6 joints), the damped
    least-squares step ``J^T (J J^T + damping^2 I)^-1 nu`` is taken instead and the status is
    ``"singular"``. If |qd_i| exceeds the joint speed limit (``qd_max``, else ``kin.qd_max``), all of qd
    is scaled down by the same factor so its direction is kept; ``info.scale`` says by how much.

    ``axes`` is the task: ``"all"`` (the six rows of J0), ``"trans"`` (v), ``"rot"`` (omega) or the
    row indices of the task (``(0, 1, 5)``: x, y and the rotation about z, what a planar arm
    controls). With fewer rows the step solves the sub-Jacobian, ``J0[rows] qd = nu[rows]`` (the
    other entries of ``nu`` are ignored): an under-actuated arm (a planar 3R, fewer than 6 joints)
    does its task exactly where the full J0 would only give a least-squares compromise, and
    ``info`` reports the manipulability of those rows and the residual over them.

    ``qd_null`` (n,), rad/s or m/s per joint, adds the null-space motion ``(I - J^+ J) qd_null``
    (Corke, Robotics, Vision and Control, 3rd ed., 2023, chap 8: a secondary task such as moving
    away from joint limits for a redundant arm; it leaves the end-effector velocity unchanged).
    On the damped (singular) step the projector is the damped one, ``I - J^T (J J^T + damping^2 I)^-1
    J``, and the end-effector velocity changes slightly. The speed-limit scaling applies to the sum.

    On compiled C kinematics the step is one C call (:class:`symkin.runtime.mmc_c.CRRMC`, kept per
    kinematics object and options); elsewhere, and with ``qd_null``, J0 comes from ``kin.jacob0`` and
    the step from NumPy. Both solve with the Cholesky factor of J J^T, no SVD.
    """
    task = _task_rows(axes)  # for row indices, info's manipulability is that of the task's rows
    named = axes if isinstance(axes, str) else "all"
    return _rrmc(kin, q, nu, qd_max, damping, singular_tol, named, qd_null, task)


def servo_rrmc_step(kin: Any, qd_max: Any = None, axes: str = "all") -> Any:
    """The servo loop's RRMC step ``(q, nu) -> (qd, info)``: all six rows of J0 solved (the loop
    drives the whole pose error), the manipulability of ``axes`` reported."""
    return lambda q, nu: _rrmc(kin, q, nu, qd_max, 1e-2, 1e-6, axes, None, _AXES["all"])


def _task_rows(axes: Any) -> Any:
    """The rows of J0 and nu a task keeps: a slice for "all", "trans" or "rot", else an index array
    of distinct rows 0..5 in the order given."""
    if isinstance(axes, str):
        return _axes(axes)
    try:
        rows = [int(r) for r in axes if isinstance(r, (int, np.integer)) and not isinstance(r, bool)]
        ok = len(rows) == len(axes) and 0 < len(rows) == len(set(rows)) and all(0 <= r < 6 for r in rows)
    except TypeError:
        ok = False
    if not ok:
        raise ParameterError(
            f"axes must be 'all', 'trans', 'rot' or distinct row indices 0..5 of (v, omega), not {axes!r}"
        )
    return np.array(rows)


def _rrmc(
    kin: Any,
    q: Any,
    nu: Any,
    qd_max: Any,
    damping: float,
    singular_tol: float,
    axes: str,
    qd_null: Any,
    task: Any,
) -> tuple[np.ndarray, StepInfo]:
    """:func:`rrmc` solving the rows ``task`` of J0 (a slice or indices) and reporting the
    manipulability of ``axes``; the servo loop solves all six rows whatever its ``axes``."""
    full = isinstance(task, slice) and task == _AXES["all"]
    if qd_null is None and full:
        try:  # compiled kinematics keep their C controllers (by options) in kin._c_rrmc
            c = kin._c_rrmc[(qd_max, damping, singular_tol, axes)]
        except (AttributeError, KeyError, TypeError):
            c = rrmc_controller(kin, qd_max, damping, singular_tol, axes)
        if c is not None:
            return c.fast(q, nu) or c.step(q, nu)  # fast: None for invalid input; step raises the error
    q = step_q(kin, q)
    nu = step_nu(nu)
    damping = _number(damping, "damping", strict=False)
    singular_tol = _number(singular_tol, "singular_tol", strict=False)
    J = np.asarray(kin.jacob0(q), dtype=float)
    qd, status, method, m = _rrmc_step(J, nu, damping, singular_tol, _axes(axes), task)
    if qd_null is not None:
        qd = qd + _null_motion(J[task], qd_null, damping if status == "singular" else 0.0)
    qd, scale = scale_to_limits(qd, _speed_limits(kin, kin.n, qd_max))
    res = float(np.abs(J[task] @ qd - nu[task]).max())
    return qd, StepInfo(status, method, m, residual=res, scale=scale)


def _null_motion(J: np.ndarray, qd_null: Any, damping: float) -> np.ndarray:
    """``(I - J^T (J J^T + damping^2 I)^-1 J) qd_null`` (n,): with damping 0 the projection of
    ``qd_null`` onto the null space of J (full row rank), ``(I - J^+ J) qd_null``."""
    n = J.shape[1]
    v = real_array(qd_null, "qd_null", ParameterError)
    if v.shape != (n,) or not np.isfinite(v).all():
        raise ParameterError(f"qd_null must be {n} finite numbers, got {qd_null!r}")
    G = J @ J.T + damping * damping * np.eye(J.shape[0])
    try:
        return v - J.T @ np.linalg.solve(G, J @ v)
    except np.linalg.LinAlgError:  # no damping at a singular J: no null-space step
        return np.zeros(n)


_RRMC: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # kin -> {options: CRRMC}, if no kin._c_rrmc


def rrmc_controller(
    kin: Any, qd_max: Any = None, damping: float = 1e-2, singular_tol: float = 1e-6, axes: str = "all"
) -> Any:
    """The C controller (:class:`symkin.runtime.mmc_c.CRRMC`) of ``rrmc(kin, ..., options)``, memoised
    per kinematics object and hashable options, or None when ``kin`` is not compiled C kinematics."""
    from symkin.runtime import mmc_c

    if not mmc_c.supports(kin):
        return None

    def make() -> Any:
        _axes(axes)
        d = _number(damping, "damping", strict=False)
        tol = _number(singular_tol, "singular_tol", strict=False)
        return mmc_c.CRRMC(kin, _speed_limits(kin, int(kin.n), qd_max), d, tol, axes)

    key = (qd_max, damping, singular_tol, axes)  # unhashable (an array qd_max): a new C controller per call
    cache = getattr(kin, "_c_rrmc", None)
    return bounded(cache, key, make) if isinstance(cache, dict) else per_object(_RRMC, kin, key, make)


def _rrmc_step(
    J: np.ndarray, nu: np.ndarray, damping: float, singular_tol: float, rows: slice, task: Any = None
) -> tuple[np.ndarray, str, str, float]:
    """(qd, status, method, m) of eqs 35-36 on the task rows of J and nu (``task``: a slice or
    indices; default all six) from the Cholesky factor of G = Jt Jt^T (no SVD): Jt is regular when
    G - singular_tol^2 I is positive definite (its smallest singular value is at least
    singular_tol); then qd = Jt^T G^-1 nut (Jt^-1 nut for a square Jt) and, for the rows ``rows``
    of a full task, m = prod diag(L) = sqrt(det G), else the damped step Jt^T (G + damping^2 I)^-1
    nut. m is the manipulability of the rows ``rows`` of J (all six: of the task rows)."""
    task = _AXES["all"] if task is None else task
    full = isinstance(task, slice) and task == _AXES["all"]
    Jt, nut = J[task], nu[task]
    k, n = Jt.shape
    G = Jt @ Jt.T
    L = None
    if n >= k:
        with contextlib.suppress(np.linalg.LinAlgError):
            np.linalg.cholesky(G - singular_tol**2 * np.eye(k))
            L = np.linalg.cholesky(G)
    if full and rows == _AXES["all"]:
        if L is not None:
            m = float(np.prod(np.diagonal(L)))
        else:
            m = math.sqrt(max(float(np.linalg.det(G)), 0.0)) if n >= 6 else 0.0
    elif full:
        Gr = G[rows, rows]
        m = math.sqrt(max(float(np.linalg.det(Gr)), 0.0))
    else:  # the task's own rows
        m = math.sqrt(max(float(np.linalg.det(G)), 0.0)) if n >= k else 0.0
    if L is not None:
        return Jt.T @ np.linalg.solve(G, nut), "solved", ("inverse" if n == k else "pinv"), m
    try:
        y = np.linalg.solve(G + damping * damping * np.eye(k), nut)
    except np.linalg.LinAlgError:  # no damping at a singular J: no step
        y = np.zeros(k)
    return Jt.T @ y, "singular", "damped", m


_C_COLLISION_REFUSAL = (
    "backend='c': the C MMC step with collision avoidance needs the slack (slack=True) and the C "
    "collision kernel of the controller's joints; this MMC runs in Python (backend='auto')"
)


# -- MMC: the controller ---------------------------------------------------------------------------
class MMC(CStep):
    """Manipulability Motion Controller (MMC paper eq 12), one OSQP problem per controller.

    ``step(q, nu)`` returns joint velocities (n,) achieving the base-frame spatial velocity ``nu`` (6,)
    while maximising the manipulability of ``axes``, within ``-alpha <= qd <= alpha`` (``qd_max``, else
    ``kin.qd_max``, else unbounded; pass ``np.inf`` for none) and, with ``joint_limits``, velocity
    dampers (see :func:`joint_velocity_bounds`; give the control period ``dt`` to also bound each
    step's joint motion by the distance to the limit, which keeps fast joints inside).

    The QP is built by :meth:`build` (an :class:`MMCQP`, testable on its own) and solved by
    :meth:`solve`. When ``closed_form`` is true and the unconstrained-by-bounds solution
    :func:`mmc_closed_form` (with the slack when there is one) lies within the bounds, it is the
    QP's solution and OSQP is skipped.
    When it does not and ``active_set`` is true, the bounds it crosses start an active-set solve
    (:func:`~symkin.runtime.mmc_qp.active_set_solve`), whose answer, when it settles, is the QP's
    exact solution (``method="active_set"``). Otherwise OSQP, set up once and updated per step (warm-started),
    solves it; ``closed_form=False`` sends every step to OSQP.

    ``backend``: ``"auto"`` (default) runs :meth:`step` in C when ``kin`` is compiled C kinematics
    (``symkin.compile(robot, backend="c")``): kinematics, closed form, active set and an embedded
    OSQP built for this QP (:mod:`symkin.runtime.mmc_c`), the same answers within solver
    tolerance; ``"python"`` keeps this NumPy + OSQP path (the reference); ``"c"`` requires C.
    :meth:`build` and :meth:`solve` always run in Python. ``frame`` picks the task frame: a tree's
    frame name (:class:`symkin.Tree` or its compiled kinematics) or link frame k of a chain.

    ``collision=env`` (an Environment or obstacles; ``True``: self-collision only; the model needs
    geometry) adds one row per active pair of the robot's geometry: the velocity damper
    ``d_dot >= -xi_d (d - d_s) / (d_i - d_s)`` for every distance below the influence distance
    ``d_i`` (NEO's form, :func:`~symkin.runtime.mmc_qp.distance_dampers`), with ``d_dot = Jd qd``
    from the distance Jacobians (:meth:`symkin.Kinematics.distance_jacobians`), for the
    ``collision_rows`` (32) closest pairs within ``d_i``. Pairs of the robot's own shapes use
    ``d_i_self`` (0.05 m) and ``d_s_self`` (1 mm: the sphere models already pad the links, and a
    pair driven to d = 0 by the damper would sit at exact contact, where rounding makes the
    checker call every further step colliding): sphere models hold pairs that stay a few
    centimetres apart at every configuration (the built-in Panda's closest self pair is 1.2 cm
    apart at qr), which obstacle margins would push apart forever and which would crowd the
    obstacles out of the rows. The dampers act on a linearisation, so a step may still end slightly
    inside a margin or a pair: :func:`symkin.servo` checks every configuration it returns with the
    collision checker and shortens or stops a step that collides. When any pair lies within its
    ``d_i`` and there is a slack, the step is first the active-set solve with the rows
    (:func:`~symkin.runtime.mmc_qp.active_set_rows_solve`, from the last step's settled set, then
    from the bounds the closed form crosses), else OSQP polished by the same solve. On C
    kinematics with the C collision kernel and the slack, the whole step (distances, rows, QP) is
    one C call, like the step without obstacles.

    ``slack`` (default: on with ``joint_limits`` or ``collision``) adds a slack ``s`` on the
    equality, weighted by ``slack_weight``, so the QP stays feasible when the dampers or speed
    limits cannot meet nu; ``info.slack`` is |s|. Without it such a step is ``"infeasible"``. At a
    singular configuration (smallest singular value of J below ``singular_tol``) and when OSQP
    fails, the RRMC step scaled into the bounds is returned and ``info.fallback`` says so.
    """

    def __init__(
        self,
        kin: Any,
        lam: float = 0.005,
        qd_max: Any = None,
        axes: str = "all",
        joint_limits: bool = False,
        rho_i: float | np.ndarray = 0.9,
        rho_s: float | np.ndarray = 0.05,
        xi: float = 1.0,
        dt: float | None = None,
        slack: bool | None = None,
        slack_weight: float = 1e4,
        closed_form: bool = True,
        active_set: bool = True,
        singular_tol: float = 1e-6,
        osqp_settings: dict[str, Any] | None = None,
        backend: str = "auto",
        frame: Any = None,
        collision: Any = None,
        d_i: float = 0.3,
        d_s: float = 0.05,
        xi_d: float = 1.0,
        collision_rows: int = 32,
        d_i_self: float = 0.05,
        d_s_self: float = 0.001,
    ) -> None:
        self._collision = self._env = None
        self._warm: tuple[np.ndarray, np.ndarray] | None = None  # the last obstacle step's active sets
        if collision is not None and collision is not False:
            from symkin.geometry.pairs import as_environment
            from symkin.runtime.collision import collision_of

            self._collision = collision_of(kin)
            self._env = as_environment(None if collision is True else collision)
        self.d_i, self.d_s = _number(d_i, "d_i"), _number(d_s, "d_s", strict=False)
        self.xi_d = _number(xi_d, "xi_d")
        if self._collision is not None and not self.d_i > self.d_s:
            raise ParameterError(f"d_i ({d_i}) must exceed d_s ({d_s})")
        self.d_i_self = _number(d_i_self, "d_i_self")
        self.d_s_self = _number(d_s_self, "d_s_self", strict=False)
        if self._collision is not None and not self.d_i_self > self.d_s_self:
            raise ParameterError(f"d_i_self ({d_i_self}) must exceed d_s_self ({d_s_self})")
        self.collision_rows = count(collision_rows, "collision_rows")
        kin = task_kinematics(kin, frame)  # a chain itself, or one frame of a model
        self.kin = kin
        self.n = int(kin.n)
        if self.n < 1:
            raise ParameterError("MMC needs a robot with at least one joint")
        self.lam = _number(lam, "lam")
        self.axes = axes
        self._rows = _axes(axes)
        self.qd_max = _speed_limits(kin, self.n, qd_max)
        self._bounded = bool(joint_limits) or bool(np.isfinite(self.qd_max).any())
        self.qlim = np.asarray(kin.qlim, dtype=float)
        self.joint_limits = bool(joint_limits)
        ri, rs = _per_joint(rho_i, self.n, "rho_i"), _per_joint(rho_s, self.n, "rho_s")
        if self.joint_limits and not (ri > rs).all():
            raise ParameterError(f"rho_i ({rho_i}) must exceed rho_s ({rho_s})")
        self.rho_i, self.rho_s, self.xi = rho_i, rho_s, _number(xi, "xi")
        self.dt = None if dt is None else _number(dt, "dt")
        self.slack = (self.joint_limits or self._collision is not None) if slack is None else bool(slack)
        self.slack_weight = _number(slack_weight, "slack_weight")
        self.closed_form = bool(closed_form)
        self.active_set = bool(active_set)
        self.singular_tol = _number(singular_tol, "singular_tol", strict=False)
        self.settings = {**OSQP_SETTINGS, **(osqp_settings or {})}
        self._jh = getattr(kin, "jacob0_hessian0", None)
        self._solver: Any = None  # osqp.OSQP, set up on the first step that needs it (osqp imported then)
        self._raw: Any = None
        self._polish = bool(self.settings.get("polishing"))
        from symkin.runtime import mmc_c

        c_ok = self._collision is None or (
            self.slack
            and getattr(self._collision, "kernel", None) is not None
            and self._collision.n == self.n  # the kernel takes this controller's joint values
        )
        refusal = None if c_ok else _C_COLLISION_REFUSAL
        self._c = self._c_step(backend, mmc_c.supports(kin), lambda: mmc_c.CMMC(self), "MMC", refusal)

    def __repr__(self) -> str:
        return (
            f"MMC(n={self.n}, lam={self.lam}, axes={self.axes!r}, joint_limits={self.joint_limits}, "
            f"slack={self.slack}, backend={self.backend!r})"
        )

    # -- build ----------------------------------------------------------------------------------
    def kinematics(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        """(J0 (6, n), Jm (n,), m) at q."""
        J, Jm, m, _, _ = self._terms(q)
        return J, Jm, m

    def _terms(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray, float, float, np.ndarray | None]:
        """(J0, Jm, m, smallest singular value of J0, (J0 J0^T)^-1 J0 or None when singular)."""
        kin = self.kin
        H = None
        if self._jh is not None:
            J, H = self._jh(q)
        elif hasattr(kin, "hessian0"):
            J, H = kin.jacob0(q), kin.hessian0(q)
        else:
            J = kin.jacob0(q)
        J = np.asarray(J, dtype=float)
        n = self.n
        B = None
        if n >= 6:
            w, V = np.linalg.eigh(J @ J.T)  # one decomposition: s_min, m and (J J^T)^-1
            s_min = math.sqrt(max(float(w[0]), 0.0))
            if s_min >= self.singular_tol:
                B = V @ ((V.T @ J) / w[:, None])
        else:
            s_min = 0.0
        if H is None:
            Jm = np.asarray(kin.jacobm(q, axes=self.axes), dtype=float)
            Jr = J[self._rows]
            m = math.sqrt(max(float(np.linalg.det(Jr @ Jr.T)), 0.0))
        elif B is not None and self.axes == "all":
            m = math.sqrt(float(w.prod()))
            Jm = m * (np.asarray(H, dtype=float).reshape(n, -1) @ B.ravel())  # eq 11
        else:
            Jm, m = manipulability_jacobian(J, np.asarray(H, dtype=float), self.axes)
        return J, Jm, m, s_min, B

    def bounds(self, q: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(lower, upper) bounds on qd at q, each (n,)."""
        return joint_velocity_bounds(
            q, self.qlim, self.qd_max, self.joint_limits, self.rho_i, self.rho_s, self.xi, self.dt
        )

    def build(self, q: Any, nu: Any) -> MMCQP:
        """The QP of eq 12 at configuration q (n,) for the spatial velocity nu (6,)."""
        q = step_q(self.kin, q)
        nu = step_nu(nu)
        J, Jm, m = self.kinematics(q)
        lower, upper = self.bounds(q)
        Jd, dl, _ = self._distance_rows(q)
        return mmc_qp(J, Jm, nu, lower, upper, self.lam, self.slack_weight if self.slack else None, m, Jd, dl)

    def _distance_rows(self, q: np.ndarray) -> tuple[np.ndarray | None, np.ndarray | None, np.ndarray]:
        """Collision avoidance rows (Jd, lower bounds on d_dot, the pairs of the rows: indices into
        the distances) at q; (None, None, []) without collision."""
        if self._collision is None:
            return None, None, np.zeros(0, dtype=int)
        d, Jd = self._collision.distance_jacobians(q, self._env)
        K = min(self.collision_rows, len(d))
        is_self = np.arange(len(d)) < len(self._collision.layout.self_pairs)  # self pairs come first
        d_i = np.where(is_self, self.d_i_self, self.d_i)
        near = np.flatnonzero(d < d_i)
        near = near[np.argsort(d[near], kind="stable")[:K]]  # the closest pairs within their d_i
        rows, lower = np.zeros((K, self.n)), np.full(K, -np.inf)  # K rows always: OSQP's sparsity is fixed
        rows[: len(near)] = Jd[near]
        d_s = np.where(is_self[near], self.d_s_self, self.d_s)
        lower[: len(near)] = distance_dampers(d[near], d_i[near], d_s, self.xi_d)
        return rows, lower, near

    def step(self, q: Any, nu: Any) -> tuple[np.ndarray, StepInfo]:
        """Joint velocity qd (n,) for the spatial velocity nu (6,) at q (n,), and how it was found.

        Same answer as ``solve(build(q, nu))``; the QP matrices are only assembled when the closed
        form does not settle the step. On the C path (:attr:`backend`) the whole step is one C call.
        """
        if self._c is not None:
            return self._c.fast(q, nu) or self._c.step(q, nu)  # fast: None for invalid input
        nu = step_nu(nu)
        try:
            qd, info = self._step(step_q(self.kin, q), nu)
        except np.linalg.LinAlgError:  # non-finite kinematics (e.g. overflow): no answer
            qd, info = np.full(self.n, math.nan), StepInfo("error", "closed_form", math.nan)
        if not np.isfinite(qd).all():  # never "solved" with NaN or inf: stop the joints instead
            res = float(np.abs(nu).max())  # max |J 0 - nu|
            return np.zeros(self.n), StepInfo("error", info.method, info.manipulability, 0, "zero", res)
        return qd, info

    def _step(self, q: np.ndarray, nu: np.ndarray) -> tuple[np.ndarray, StepInfo]:
        J, Jm, m, s_min, B = self._terms(q)
        lower, upper = self.bounds(q)
        Jd, dl, pairs = self._distance_rows(q)
        near = dl is not None and bool(np.isfinite(dl).any())
        warm, self._warm = self._warm, None
        if self.closed_form and B is not None and not near:
            if self.slack:
                qd = mmc_closed_form(J, Jm, nu, self.lam, self.slack_weight)
            else:
                z = Jm / self.lam
                qd = z + B.T @ (nu - J @ z)  # J^+ nu + (I - J^+ J) Jm / lam
            done = self._closed_form_step(J, Jm, nu, lower, upper, m, qd, self._bounded)
            if done is not None:
                return done
        elif self.closed_form and B is not None and self.active_set and self.slack:
            # obstacle rows: the active-set solve with the rows, first from the last step's active
            # bounds and pairs (a servo run's next step usually keeps them), then from the bounds
            # the closed form crosses (the rows it violates join one at a time)
            starts = []
            if warm is not None:
                act = np.where(lower == upper, 2, np.where(warm[0] == 2, 0, warm[0]))
                rows = np.zeros(len(dl), dtype=bool)
                rows[: len(pairs)] = np.isin(pairs, warm[1])
                starts.append((act, rows))
            qd = mmc_closed_form(J, Jm, nu, self.lam, self.slack_weight)
            starts.append((active_of(qd, lower, upper), np.zeros(len(dl), dtype=bool)))
            w = self.slack_weight
            for act, rows in starts:
                found = active_set_rows_solve(J, Jm, nu, lower, upper, self.lam, w, Jd, dl, act, rows)
                if found is not None:  # its active bounds and pairs start the next step
                    x, solves, act, rows = found
                    self._warm = (act, pairs[rows[: len(pairs)]])
                    return self._active_set_answer(J, nu, lower, upper, m, x, solves)
        qp = mmc_qp(J, Jm, nu, lower, upper, self.lam, self.slack_weight if self.slack else None, m, Jd, dl)
        return self._solve(qp, s_min, try_closed_form=False, pairs=pairs)

    def _closed_form_step(
        self,
        J: np.ndarray,
        Jm: np.ndarray,
        nu: np.ndarray,
        lo: np.ndarray,
        hi: np.ndarray,
        m: float,
        qd: np.ndarray,
        bounded: bool = True,
    ) -> tuple[np.ndarray, StepInfo] | None:
        """The closed form ``qd`` as the step's answer when it is finite and (``bounded``) within the
        bounds; else the active-set solution started from the bounds it crosses, or None."""
        if math.isfinite(qd.sum()) and (
            not bounded or ((qd >= lo - 1e-12).all() and (qd <= hi + 1e-12).all())
        ):
            e = nu - J @ qd
            slack = float(np.linalg.norm(e)) if self.slack else 0.0
            return qd, StepInfo("solved", "closed_form", m, residual=float(np.abs(e).max()), slack=slack)
        if not self.active_set:
            return None
        w = self.slack_weight if self.slack else None
        found = active_set_solve(J, Jm, nu, lo, hi, self.lam, w, active_of(qd, lo, hi))
        return None if found is None else self._active_set_answer(J, nu, lo, hi, m, *found)

    def _active_set_answer(
        self, J: np.ndarray, nu: np.ndarray, lower: np.ndarray, upper: np.ndarray, m: float, x: np.ndarray,
        solves: int,
    ) -> tuple[np.ndarray, StepInfo]:  # fmt: skip
        """An active-set solution x (qd, or (qd, s)) as the step's answer: qd clipped into the bounds."""
        qd = np.clip(x[: self.n], lower, upper)
        res, slack = float(np.abs(J @ qd - nu).max()), float(np.linalg.norm(x[self.n :]))
        return qd, StepInfo("solved", "active_set", m, solves, residual=res, slack=slack)

    def solve(self, qp: MMCQP) -> tuple[np.ndarray, StepInfo]:
        """Solve a QP from :meth:`build`."""
        w = np.linalg.eigvalsh(qp.J @ qp.J.T) if self.n >= 6 else np.zeros(1)
        return self._solve(qp, math.sqrt(max(float(w[0]), 0.0)), self.closed_form)

    def _solve(
        self, qp: MMCQP, s_min: float, try_closed_form: bool, pairs: np.ndarray | None = None
    ) -> tuple[np.ndarray, StepInfo]:
        J, nu, m, n = qp.J, qp.l[:6], qp.manipulability, self.n
        lower, upper = qp.lower, qp.upper
        w = self.slack_weight if qp.has_slack else None
        near = bool(qp.n_distance and np.isfinite(qp.l[6 + n :]).any())
        if s_min < self.singular_tol:
            return self._fallback(qp, "singular", "closed_form", 0)
        if try_closed_form and not near:  # the closed form and the active set know only the bounds
            qd = mmc_closed_form(J, qp.Jm, nu, self.lam, w)
            done = self._closed_form_step(J, qp.Jm, nu, lower, upper, m, qd)
            if done is not None:
                return done
        x, status, iters = self._osqp(qp)
        usable = x is not None and status in ("solved", "inaccurate", "max_iter")
        if usable and self._polish and (qp.has_slack or not near):
            # polish: the active-set solve from OSQP's active set (and, near obstacles, with the slack
            # only, its active rows), which when it settles is the exact solution, also of a QP that
            # OSQP left unfinished (see OSQP_SETTINGS)
            y = self._raw.solution.y if self._raw is not None else np.zeros(qp.A.shape[0])
            act = active_of_osqp(x[:n], y[6 : 6 + n], lower, upper)
            if near:
                Jd, dl = qp.A[6 + n :, :n], qp.l[6 + n :]
                rows = active_rows_of(x[:n], Jd, dl, y[6 + n :])
                found = active_set_rows_solve(J, qp.Jm, nu, lower, upper, self.lam, w, Jd, dl, act, rows)
                if found is not None and pairs is not None:  # the next step starts from this active set
                    self._warm = (found[2], pairs[found[3][: len(pairs)]])
            else:
                found = active_set_solve(J, qp.Jm, nu, lower, upper, self.lam, w, act)
            if found is not None:
                x, status = found[0], "solved"
        if usable:
            qd = np.clip(x[:n], lower, upper)  # remove solver-tolerance overshoot of the bounds
            res = float(np.abs(J @ qd - nu).max())
            # an unfinished iterate, clipped into the bounds, is kept when the QP has a slack (the
            # equality is soft anyway) or when it meets the equality; else the RRMC step is used
            if status == "solved" or qp.has_slack or res <= 1e-6 * (1.0 + float(np.abs(nu).max())):
                slack = float(np.linalg.norm(x[n:])) if qp.has_slack else 0.0
                return qd, StepInfo(status, "osqp", m, iters, residual=res, slack=slack)
        # infeasible, error, or an unusable iterate: the RRMC step, and restart the next solve from it
        qd, info = self._fallback(qp, status if status != "solved" else "error", "osqp", iters)
        self._warm_start(qd, qp)
        return qd, info

    def _warm_start(self, qd: np.ndarray, qp: MMCQP) -> None:
        if self._solver is None:
            return
        import osqp

        x = np.zeros(qp.P.shape[0])
        x[: self.n] = qd
        if qp.has_slack:
            x[self.n :] = qp.l[:6] - qp.J @ qd
        with contextlib.suppress(ValueError, RuntimeError, osqp.interface.OSQPException):
            self._solver.warm_start(x=x, y=np.zeros(qp.A.shape[0]))

    def _osqp(self, qp: MMCQP) -> tuple[np.ndarray | None, str, int]:
        """Update (q-dependent values, bounds) and solve the OSQP problem; (x, status, iterations)."""
        import osqp  # only here (and in _setup): `import symkin` and the C path do without it

        if self._solver is None:
            self._inf = float(osqp.constant("OSQP_INFTY"))
            self._status_names = {int(s): _OSQP_STATUS.get(s.name, "error") for s in osqp.SolverStatus}
        l = np.maximum(qp.l, -self._inf)
        u = np.minimum(qp.u, self._inf)
        try:
            if self._solver is None:
                self._setup(qp, l, u)
            else:
                Ax = qp.A[self._A_rows, self._A_cols]
                raw = self._raw
                if raw is not None:
                    raw.update_data_vec(q=qp.c, l=l, u=u)
                    raw.update_data_mat(P_x=None, P_i=None, A_x=Ax, A_i=None)
                else:  # pragma: no cover - other osqp builds
                    self._solver.update(q=qp.c, l=l, u=u, Ax=Ax)
            if self._raw is not None:
                self._raw.solve()
                info, x = self._raw.info, self._raw.solution.x
            else:  # pragma: no cover
                res = self._solver.solve(raise_error=False)
                info, x = res.info, res.x
        except (ValueError, RuntimeError, osqp.interface.OSQPException):  # pragma: no cover - defensive
            self._solver = None
            return None, "error", 0
        status = self._status_names.get(int(info.status_val), "error")
        iters = int(info.iter)

        x = np.array(x, dtype=float)
        if x.shape != (qp.P.shape[0],) or not np.isfinite(x).all():
            return None, status if status != "solved" else "error", iters
        return x, status, iters

    def _setup(self, qp: MMCQP, l: np.ndarray, u: np.ndarray) -> None:
        """Set up OSQP once with the fixed sparsity: P diagonal, A = [[J, I], [I, 0]] (J block dense)."""
        import osqp
        import scipy.sparse as sp

        pattern = qp.A != 0
        pattern[:6, : self.n] = True  # the J block stays structurally dense whatever its values
        pattern[6 + self.n :, : self.n] = True  # so do the distance rows
        self._A_rows, self._A_cols = _csc_order(pattern)
        indptr = np.concatenate(([0], np.cumsum(pattern.sum(axis=0))))
        A = sp.csc_matrix((qp.A[self._A_rows, self._A_cols], self._A_rows, indptr), shape=qp.A.shape)
        nx = qp.P.shape[0]
        P = sp.csc_matrix((np.diag(qp.P).copy(), np.arange(nx), np.arange(nx + 1)), shape=(nx, nx))
        solver = osqp.OSQP()
        solver.setup(P, qp.c, A, l, u, **{**self.settings, "polishing": False})  # see OSQP_SETTINGS
        self._solver = solver
        # the compiled binding under osqp.OSQP: its update/solve skip the Python wrapper's copies and
        # result namespace (about 16 us per step); the public calls are used if it is missing
        raw = getattr(solver, "_solver", None)
        ok = all(hasattr(raw, a) for a in ("update_data_vec", "update_data_mat", "solve", "info", "solution"))
        self._raw = raw if ok else None

    def _fallback(self, qp: MMCQP, status: str, method: str, iters: int) -> tuple[np.ndarray, StepInfo]:
        """The RRMC step scaled into [lower, upper] (or zero), never NaN."""
        qd, fallback, scale = fallback_step(qp, self.singular_tol)
        res = float(np.abs(qp.J @ qd - qp.l[:6]).max())
        return qd, StepInfo(status, method, qp.manipulability, iters, fallback, res, scale=scale)


def _csc_order(pattern: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the nonzeros of a boolean pattern in CSC (column-major) order."""
    cols, rows = np.nonzero(pattern.T)
    return rows, cols
