"""Null-space motion control: resolved-rate control with a secondary task (Haviland and Corke,
Manipulator Differential Kinematics, Part 2: Acceleration and Advanced Applications, 2023, section
"Null-Space Projection")::

    qd = J^+ nu + k (I - J^+ J) grad gamma(q)

A redundant arm (n > 6) meets the end-effector velocity nu (6,) exactly (the projector ``I - J^+ J``
removes every end-effector motion from the second term) while climbing a performance measure gamma:
``"manipulability"``, Yoshikawa's m(q) (Part 1 eq 52) with its gradient Jm (Haviland and Corke,
Maximising Manipulability During Resolved-Rate Motion Control, 2020, eq 11; Park's choice, the
article's example), or ``"joint_limits"``, ``gamma = -c(q)`` with the joint-limit cost
:func:`joint_limit_cost` (Liegeois, Automatic Supervisory Control of the Configuration and
Behavior of Multibody Mechanisms, IEEE Trans. SMC, 1977; Siciliano, Sciavicco, Villani and Oriolo,
Robotics: Modelling, Planning and Control, 2009, sec 3.5.1), which pulls every joint toward the
middle of its range. The article's gain is ``1 / lambda``. numpy only; the step is
:func:`symkin.rrmc` with ``qd_null = k grad gamma(q)`` (its C path is bypassed).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from symkin.errors import ParameterError
from symkin.runtime.control import _number, rrmc
from symkin.runtime.step import StepInfo, step_q

__all__ = ["null_space_rrmc", "joint_limit_cost", "joint_limit_gradient", "OBJECTIVES"]

#: The secondary tasks of :func:`null_space_rrmc`.
OBJECTIVES: tuple[str, ...] = ("joint_limits", "manipulability")


def _ranges(qlim: Any, n: int) -> tuple[np.ndarray, np.ndarray]:
    """(mid-range, half the range) (n,) each; joints without a finite range get an infinite half
    range (no cost)."""
    lim = np.asarray(qlim, dtype=float)
    if lim.shape != (2, n):
        raise ParameterError(f"qlim must have shape (2, {n}), got {lim.shape}")
    lo, hi = lim
    finite = np.isfinite(lo) & np.isfinite(hi) & (hi > lo)
    lo, hi = np.where(finite, lo, 0.0), np.where(finite, hi, 0.0)
    return np.where(finite, (lo + hi) / 2.0, 0.0), np.where(finite, (hi - lo) / 2.0, np.inf)


def joint_limit_cost(q: Any, qlim: Any) -> np.ndarray | float:
    """Joint-limit cost ``c(q) = (1/n) sum_i ((q_i - mid_i) / half_i)^2`` (dimensionless): 0 with every
    joint in the middle of its range, 1 with every joint at a limit (Liegeois's measure, 1977, times
    8). ``q`` (n,) or (N, n) rad or m, ``qlim`` (2, n); joints without a finite range add nothing.
    float, or (N,)."""
    Q = np.asarray(q, dtype=float)
    n = Q.shape[-1]
    mid, half = _ranges(qlim, n)
    s = (Q - mid) / half
    c = (s * s).sum(axis=-1) / n
    return float(c) if Q.ndim == 1 else c


def joint_limit_gradient(q: Any, qlim: Any) -> np.ndarray:
    """dc/dq of :func:`joint_limit_cost`, ``2 (q_i - mid_i) / (n half_i^2)`` (1/rad or 1/m): (n,) or
    (N, n)."""
    Q = np.asarray(q, dtype=float)
    n = Q.shape[-1]
    mid, half = _ranges(qlim, n)
    return 2.0 * (Q - mid) / (n * half * half)


def null_space_rrmc(
    kin: Any, q: Any, nu: Any, objective: str = "joint_limits", gain: float = 10.0, axes: str = "all",
    qd_max: Any = None, damping: float = 1e-2, singular_tol: float = 1e-6,
) -> tuple[np.ndarray, StepInfo]:  # fmt: skip
    """RRMC with a secondary task in the null space of J0: ``qd = J^+ nu + gain (I - J^+ J) grad
    gamma(q)`` (see :mod:`symkin.runtime.null_space`), base frame, qd (n,), and the step's
    :class:`StepInfo` (as :func:`symkin.rrmc`: ``info.residual`` is max |J qd - nu|, 1e-15 or so away
    from singularities and speed limits).

    ``objective``: ``"joint_limits"`` (gamma = -:func:`joint_limit_cost` over ``kin.qlim``: away from
    the limits) or ``"manipulability"`` (gamma = m of the rows ``axes``, ``"all"``, ``"trans"`` or
    ``"rot"``; grad = ``kin.jacobm(q, axes=axes)``). ``gain`` (>= 0; the article's 1 / lambda)
    scales the null-space motion. ``qd_max`` (else ``kin.qd_max``) scales the sum down, keeping its
    direction; near a singularity the damped step and projector of :func:`symkin.rrmc` are used.
    A secondary task needs redundancy: with n <= 6 the projector is zero away from singularities.
    """
    if objective not in OBJECTIVES:
        names = ", ".join(map(repr, OBJECTIVES))
        raise ParameterError(f"objective must be one of {names}, not {objective!r}")
    k = _number(gain, "gain", strict=False)
    q = step_q(kin, q)
    if objective == "joint_limits":
        grad = -joint_limit_gradient(q, kin.qlim)
    else:
        grad = np.asarray(kin.jacobm(q, axes=axes), dtype=float)
    return rrmc(kin, q, nu, qd_max=qd_max, damping=damping, singular_tol=singular_tol, qd_null=k * grad)
