"""Quadratic-rate motion control, QRMC (Haviland and Corke, Manipulator Differential Kinematics,
Part 2: Acceleration and Advanced Applications, 2023, section "Quadratic-Rate Motion Control").

Resolved-rate control (Part 1, eqs 35-36) solves the first-order model ``J(q) qd = nu``; where J
loses rank it cannot move the end effector in the lost direction at all (that part of nu is
dropped) and near it asks for joint speeds that grow like 1/sigma_min. QRMC keeps the second-order
term of the Taylor expansion of the pose change over a horizon ``h`` at constant qd
(``Delta q = qd h``, ``Delta x = nu h``)::

    g(qd) = J qd + (h / 2) (H qd) qd - nu = 0,        (H qd) = sum_i qd_i H[i]   (6, n)

and solves it for qd. At a singular J the curvature H makes up for the lost rank: a stretched
elbow cannot move the hand inward to first order, but to second order it can (``Delta r = -L
theta^2 / 2``). The article's notebooks solve it with Newton-Raphson, ``J~ = J + H Delta q``,
``Delta x = nu`` (a horizon of 1 s: with the servo's unit gain, its time constant); ``h = dt`` is
the model of one control period, which asks for higher joint speeds near a singularity.

The solve is Levenberg-Marquardt on g: the Newton step ``x - J~^T (J~ J~^T)^-1 g`` with
``J~ = dg/dx = J + (h/2) ((H x) + [H_j x]_j)`` (the exact derivative; the article's ``J + H x``
where the second derivative is symmetric, the translational rows) while it lowers |g| and J~ is
regular, else damped (``J~ J~^T + mu I``, mu from ``damping^2``, tenfold per rejected trial), so
|g| never grows. It starts from zero: the first step is the RRMC step and the root found continues
resolved-rate control. Unconverged (at a singularity the iterate cannot leave the row space of J),
it starts again from ``qd0`` (the last answer) and from ``qd0 + seed`` (the article seeds with 0.1
rad/s per joint at a singularity). The answer is the converged one of least norm, else the one with
the smallest residual (a least-squares point: where nu asks for a direction lost even to second
order, the rest of nu is met), scaled down as a whole to the joint speed limits, like RRMC's.

:class:`QRMC` is the controller (options, the last answer, the C step for compiled C kinematics in
``csrc/qrmc_impl.h``, :mod:`symkin.runtime.qrmc_c`); :func:`qrmc` is one step. numpy only.
"""

from __future__ import annotations

import math
import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.core.arrays import axes_rows as _axes
from symkin.core.arrays import real_array
from symkin.errors import ParameterError
from symkin.model.differential import manipulability_one
from symkin.runtime.control import _number, _speed_limits, scale_to_limits
from symkin.runtime.memo import per_object
from symkin.runtime.step import CStep, StepInfo, step_nu, step_q

__all__ = [
    "QRMC",
    "qrmc",
    "QuadraticSolution",
    "quadratic_rate_solve",
    "quadratic_residual",
    "quadratic_jacobian",
]


@dataclass(frozen=True)
class QuadraticSolution:
    """A solve of the quadratic-rate model: ``qd`` (n,) rad/s or m/s per joint, its ``residual``
    max |J qd + (h/2) (H qd) qd - nu| (m/s, rad/s), the Levenberg-Marquardt ``iterations`` (trials,
    all starts) and whether it ``converged`` (residual <= tol (1 + max |nu|))."""

    qd: np.ndarray
    residual: float
    iterations: int
    converged: bool


def quadratic_residual(J: np.ndarray, H: np.ndarray, nu: np.ndarray, horizon: float, qd: Any) -> np.ndarray:
    """``g(qd) = J qd + (h/2) (H qd) qd - nu`` (6,): J (6, n), H (n, 6, n) with ``H[i] = dJ/dq_i``."""
    return _g(J, H, nu, horizon, np.asarray(qd, dtype=float))


def quadratic_jacobian(J: np.ndarray, H: np.ndarray, horizon: float, qd: Any) -> np.ndarray:
    """``J~ = dg/dqd = J + (h/2) ((H qd) + [H_j qd]_j)`` (6, n), the derivative of
    :func:`quadratic_residual`: column j of the last term is ``H[j] qd``."""
    x = np.asarray(qd, dtype=float)
    return J + 0.5 * horizon * (np.tensordot(x, H, axes=(0, 0)) + np.tensordot(H, x, axes=(2, 0)).T)


def _g(J: np.ndarray, H: np.ndarray, nu: np.ndarray, horizon: float, x: np.ndarray) -> np.ndarray:
    A = np.tensordot(x, H, axes=(0, 0))  # sum_i x_i H[i]
    return J @ x + 0.5 * horizon * (A @ x) - nu


def _regular(G: np.ndarray, tol: float) -> bool:
    """Whether G = J J^T (6 x 6) has its smallest eigenvalue at least tol^2 (J: singular value >= tol)."""
    try:
        np.linalg.cholesky(G - tol * tol * np.eye(6))
    except np.linalg.LinAlgError:
        return False
    return True


@dataclass(frozen=True)
class _Options:
    horizon: float
    iterations: int
    tol: float
    damping: float
    singular_tol: float


def _levenberg_marquardt(
    J: np.ndarray, H: np.ndarray, nu: np.ndarray, x: np.ndarray, limit: float, o: _Options
) -> tuple[np.ndarray, float, int]:
    """(the last accepted iterate from x, its max |g|, trials): see the module docstring; a trial is
    accepted when it lowers |g| (2-norm), mu then falls tenfold (to 0 below damping^2 / 1000), else it
    grows tenfold (from damping^2); mu = 0 needs a regular J~."""
    d2 = o.damping * o.damping
    mu, taken = 0.0, 0
    g = _g(J, H, nu, o.horizon, x)
    with np.errstate(over="ignore", invalid="ignore"):  # an overflowing cost ends the search
        cost = float(g @ g)
    while taken < o.iterations and not float(np.abs(g).max()) <= limit and math.isfinite(cost):
        Jt = quadratic_jacobian(J, H, o.horizon, x)
        G = Jt @ Jt.T
        if mu == 0.0 and not _regular(G, o.singular_tol):
            mu = d2
        try:
            L = np.linalg.cholesky(G + mu * np.eye(6))
        except np.linalg.LinAlgError:  # mu = 0 at a singular J~ (damping 0): no step
            break
        taken += 1
        x_new = x - Jt.T @ np.linalg.solve(L.T, np.linalg.solve(L, g))
        g_new = _g(J, H, nu, o.horizon, x_new)
        with np.errstate(over="ignore", invalid="ignore"):
            cost_new = float(g_new @ g_new)
        if cost_new < cost:
            x, g, cost = x_new, g_new, cost_new
            mu = 0.0 if mu < d2 * 1e-3 else mu / 10.0
        else:
            mu = max(10.0 * mu, d2)
            if mu == 0.0:  # damping 0: no damped step to try
                break
    return x, float(np.abs(g).max()), taken


def _iterations(value: Any) -> int:
    """Levenberg-Marquardt trials per start: an integer in 1 .. 2**31 - 1 (the C step's int32)."""
    from symkin.core.sizes import count
    from symkin.runtime.ik_problem import MAX_ITERATIONS

    return count(value, "iterations", maximum=MAX_ITERATIONS)


def quadratic_rate_solve(
    J: np.ndarray, H: np.ndarray, nu: np.ndarray, horizon: float = 1.0, qd0: Any = None, seed: Any = 0.1,
    iterations: int = 20, tol: float = 1e-10, damping: float = 1e-2, singular_tol: float = 1e-6,
) -> QuadraticSolution:  # fmt: skip
    """Solve ``J qd + (h/2) (H qd) qd = nu`` for qd (see the module docstring): from zero, then,
    unconverged, from ``qd0`` (when not zero) and ``qd0 + seed``; the converged answer of least norm,
    else the smallest residual. J (6, n) and H (n, 6, n) base frame at q, nu (6,) (v, omega), h (s)."""
    o = _Options(float(horizon), _iterations(iterations), float(tol), float(damping), float(singular_tol))
    n = J.shape[1]
    x0 = np.zeros(n) if qd0 is None else np.asarray(qd0, dtype=float)
    limit = o.tol * (1.0 + float(np.abs(nu).max()))
    x, r, taken = _levenberg_marquardt(J, H, nu, np.zeros(n), limit, o)
    for start in [x0, x0 + seed] if x0.any() else [x0 + seed]:
        if r <= limit:
            break
        x2, r2, taken2 = _levenberg_marquardt(J, H, nu, start, limit, o)
        taken += taken2
        if _better(x2, r2, x, r, limit):
            x, r = x2, r2
    return QuadraticSolution(x, r, taken, bool(r <= limit))


def _better(x2: np.ndarray, r2: float, x: np.ndarray, r: float, limit: float) -> bool:
    """Whether (x2, r2) beats (x, r): converged over not, then the smaller norm (both converged) or
    residual (neither)."""
    if (r2 <= limit) != (r <= limit):
        return r2 <= limit
    if r2 <= limit:
        return float(x2 @ x2) < float(x @ x)
    return r2 < r or not math.isfinite(r)


_QRMC: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()  # kin -> {options: QRMC}


def qrmc(
    kin: Any, q: Any, nu: Any, qd0: Any = None, horizon: float = 1.0, qd_max: Any = None, seed: Any = 0.1,
    iterations: int = 20, tol: float = 1e-10, damping: float = 1e-2, singular_tol: float = 1e-6,
    axes: str = "all",
) -> tuple[np.ndarray, StepInfo]:  # fmt: skip
    """One quadratic-rate step: joint velocities qd (n,) for the base-frame spatial velocity ``nu`` (6,),
    rows (v, omega), at q (n,), and how they were found (see :mod:`symkin.runtime.qrmc`).

    ``horizon`` (s) is the time over which the second-order model holds (1 s: the article's
    notebooks; the control period dt: the one-step model). ``qd0`` (n,), the last step's answer, is
    a start when the one from zero does not converge (default none); ``seed`` (a number or (n,),
    rad/s or m/s) offsets the last start. ``qd_max`` (else ``kin.qd_max``, else none) scales qd down
    as a whole, like :func:`symkin.rrmc`.

    ``info.status`` is ``"solved"`` when the model is met (``info.residual``, max |J qd + (h/2) (H
    qd) qd - nu| before the scaling, <= tol (1 + max |nu|)); ``"singular"`` when it is not and J is
    singular at q (nu asks for a direction the arm has lost even to second order: qd is the
    least-squares point, which meets the rest); else ``"max_iter"``. ``info.method`` is
    ``"quadratic"``, ``info.iterations`` the Levenberg-Marquardt trials, ``info.manipulability``
    that of ``axes`` at q, ``info.scale`` the speed-limit factor. Never NaN: a non-finite answer
    becomes zero (status ``"error"``, fallback ``"zero"``).

    Stateless; the servo loop runs a :class:`QRMC`, which passes its last answer as ``qd0``. On
    compiled C kinematics the step is one C call (a :class:`QRMC` kept per kinematics object and
    options).
    """
    key = (horizon, qd_max, seed, iterations, tol, damping, singular_tol, axes)
    ctrl = per_object(
        _QRMC,
        kin,
        key,
        lambda: QRMC(kin, horizon, qd_max, seed, iterations, tol, damping, singular_tol, axes),
    )
    return ctrl.step(q, nu, qd0=np.zeros(ctrl.n) if qd0 is None else qd0)


class QRMC(CStep):
    """The quadratic-rate controller (see :mod:`symkin.runtime.qrmc`) with its options and last answer.

    ``step(q, nu)`` uses its last answer (none after :meth:`reset`) as ``qd0``, ``step(q, nu, qd0)``
    the one given; both return ``(qd (n,), StepInfo)`` as :func:`qrmc`. ``backend``: ``"auto"`` runs
    the step in C for compiled C kinematics (``csrc/qrmc_impl.h``, the same arithmetic),
    ``"python"`` keeps this NumPy path (the reference), ``"c"`` requires C. ``frame`` picks the task
    frame of a tree (or link frame k of a chain), as for :class:`symkin.MMC`. :func:`symkin.servo`
    takes one as ``controller=`` (or makes one for ``controller="qrmc"``).
    """

    def __init__(
        self, kin: Any, horizon: float = 1.0, qd_max: Any = None, seed: Any = 0.1, iterations: int = 20,
        tol: float = 1e-10, damping: float = 1e-2, singular_tol: float = 1e-6, axes: str = "all",
        backend: str = "auto", frame: Any = None,
    ) -> None:  # fmt: skip
        from symkin.runtime import mmc_c, qrmc_c
        from symkin.runtime.task import task_kinematics

        kin = task_kinematics(kin, frame)  # a chain itself, or one frame of a model
        self.kin, self.n = kin, int(kin.n)
        self.horizon = _number(horizon, "horizon")
        self.qd_max = _speed_limits(kin, self.n, qd_max)
        self.seed = _seed(seed, self.n)
        self.iterations = _iterations(iterations)
        self.tol = _number(tol, "tol")
        self.damping = _number(damping, "damping", strict=False)
        self.singular_tol = _number(singular_tol, "singular_tol", strict=False)
        self.axes, self._rows = axes, _axes(axes)
        self._prev = np.zeros(self.n)
        self._jh = getattr(kin, "jacob0_hessian0", None)
        self._c = self._c_step(backend, mmc_c.supports(kin), lambda: qrmc_c.CQRMC(self), "QRMC")

    def __repr__(self) -> str:
        return f"QRMC(n={self.n}, horizon={self.horizon}, axes={self.axes!r}, backend={self.backend!r})"

    def reset(self) -> None:
        """Forget the last answer."""
        self._prev = np.zeros(self.n)
        if self._c is not None:
            self._c.start(None)

    def step(self, q: Any, nu: Any, qd0: Any = None) -> tuple[np.ndarray, StepInfo]:
        """(qd (n,), StepInfo) for the spatial velocity nu (6,) at q (n,); see :func:`qrmc`."""
        if qd0 is not None:
            qd0 = _start(qd0, self.n)
        if self._c is not None:
            if qd0 is not None:
                self._c.start(qd0)
            return self._c.fast(q, nu) or self._c.step(q, nu)  # fast: None for invalid input
        q, nu = step_q(self.kin, q), step_nu(nu)
        if self._jh is not None:
            J, H = self._jh(q)
        else:
            J, H = self.kin.jacob0(q), self.kin.hessian0(q)
        J, H = np.asarray(J, dtype=float), np.asarray(H, dtype=float)
        sol = quadratic_rate_solve(
            J, H, nu, self.horizon, self._prev if qd0 is None else qd0, self.seed, self.iterations,
            self.tol, self.damping, self.singular_tol,
        )  # fmt: skip
        m = manipulability_one(J[self._rows])
        if not np.isfinite(sol.qd).all():  # stop the joints instead
            self._prev = np.zeros(self.n)
            res = float(np.abs(nu).max())
            return np.zeros(self.n), StepInfo("error", "quadratic", m, sol.iterations, "zero", res)
        self._prev = sol.qd
        qd, scale = scale_to_limits(sol.qd, self.qd_max)
        regular = _regular(J @ J.T, self.singular_tol)
        status = "solved" if sol.converged else "max_iter" if regular else "singular"
        return qd, StepInfo(status, "quadratic", m, sol.iterations, residual=sol.residual, scale=scale)


def _seed(seed: Any, n: int) -> np.ndarray:
    """The last start's offset as finite (n,) floats."""
    try:
        a = np.broadcast_to(real_array(seed, "seed", ParameterError), (n,)).astype(float)
    except ValueError:
        raise ParameterError(f"seed must be a number or {n} numbers, got {seed!r}") from None
    if not np.isfinite(a).all():
        raise ParameterError(f"seed must be finite, got {a.tolist()}")
    return a


def _start(qd0: Any, n: int) -> np.ndarray:
    a = real_array(qd0, "qd0", ParameterError)
    if a.shape != (n,) or not np.isfinite(a).all():
        raise ParameterError(f"qd0 must be {n} finite numbers, got {qd0!r}")
    return a
