"""What a control step takes and reports: the q and nu checks, the OSQP settings and
:class:`StepInfo` (shared by the Python controllers and the all-C MMC step)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.core.arrays import as_config, name_of, real_array
from symkin.errors import ParameterError

__all__ = ["OSQP_SETTINGS", "OSQP_STATUS", "StepInfo", "step_q", "step_nu"]


#: OSQP settings of :class:`MMC`: tight tolerances, and polishing. ``polishing`` is done by symkin,
#: not OSQP: :func:`~symkin.runtime.mmc_qp.active_set_solve` from OSQP's active set, whose answer,
#: when it settles, is the exact solution (J qd = nu to about 1e-14; OSQP's own polish left errors
#: up to 1e-5 on ill-conditioned steps with the slack), also when OSQP stopped unfinished.
#: ``polish_refine_iter`` is unused.
OSQP_SETTINGS: dict[str, Any] = {
    "eps_abs": 1e-7,
    "eps_rel": 1e-7,
    "polishing": True,
    "polish_refine_iter": 3,
    "max_iter": 4000,
    "verbose": False,
    "warm_starting": True,
}


#: StepInfo's status of each of OSQP's solver statuses (osqp.SolverStatus names)
OSQP_STATUS = {
    "OSQP_SOLVED": "solved",
    "OSQP_SOLVED_INACCURATE": "inaccurate",
    "OSQP_PRIMAL_INFEASIBLE": "infeasible",
    "OSQP_PRIMAL_INFEASIBLE_INACCURATE": "infeasible",
    "OSQP_DUAL_INFEASIBLE": "error",
    "OSQP_DUAL_INFEASIBLE_INACCURATE": "error",
    "OSQP_MAX_ITER_REACHED": "max_iter",
    "OSQP_TIME_LIMIT_REACHED": "max_iter",
}


@dataclass(frozen=True, slots=True)
class StepInfo:
    """How one control step went.

    Attributes:
        status: ``"solved"``; ``"singular"`` (J lost rank: damped step); ``"infeasible"`` (the QP has
            no solution, e.g. velocity bounds too small for nu); ``"max_iter"``/``"inaccurate"`` (OSQP
            stopped early); ``"error"`` (any other solver failure).
        method: how qd was computed: ``"inverse"``/``"pinv"``/``"damped"`` (RRMC, eqs 35-36),
            ``"closed_form"``, ``"active_set"`` or ``"osqp"`` (MMC).
        manipulability: m(q) of the chosen axes (Part 1 eq 52) at the configuration of the step.
        iterations: OSQP iterations, or the active-set solves (0 for the closed form).
        fallback: ``None``, or ``"rrmc"``/``"zero"`` when the MMC answer was replaced.
        residual: max |J qd - nu| of the returned qd.
        slack: norm of the equality slack (MMC with ``slack``), else 0.
        scale: factor (<= 1) by which qd was scaled down to respect the joint speed limits.
    """

    status: str
    method: str
    manipulability: float
    iterations: int = 0
    fallback: str | None = None
    residual: float = 0.0
    slack: float = 0.0
    scale: float = 1.0

    @property
    def ok(self) -> bool:
        """True when the step is the controller's own answer (no singularity, no fallback)."""
        return self.status == "solved" and self.fallback is None


def step_q(kin: Any, q: Any) -> np.ndarray:
    """The configuration of a step: the joint-value rule of the kinematics (as_config)."""
    return as_config(q, kin.n, name_of(kin), "q")


def step_nu(nu: Any) -> np.ndarray:
    nu = real_array(nu, "nu", ParameterError)
    if nu.shape != (6,) or not np.isfinite(nu).all():
        raise ParameterError(f"nu must be 6 finite numbers (v, omega), got {nu!r}")
    return nu
