"""What a control step takes and reports: the q and nu checks, the OSQP settings and
:class:`StepInfo` (shared by the Python controllers and the all-C MMC step)."""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from typing import Any

import numpy as np

from symkin.core.arrays import as_config, name_of, real_array
from symkin.errors import CompileError, ConfigurationError, ParameterError

__all__ = ["OSQP_SETTINGS", "OSQP_STATUS", "StepInfo", "step_q", "step_nu", "CStep"]


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


class CStep:
    """A controller whose step runs in C (``_c``, from :meth:`_c_step`) or, when ``_c`` is None, in
    Python (MMC, QRMC)."""

    _c: Any = None

    @property
    def backend(self) -> str:
        """``"c"`` when the step runs in C, else ``"python"``."""
        return "python" if self._c is None else "c"

    @staticmethod
    def _c_step(backend: str, supported: bool, make: Any, what: str, refusal: str | None = None) -> Any:
        """``make()`` (the C step of the controller ``what``) for ``backend`` ``"auto"`` or ``"c"`` when
        its kinematics are compiled C kinematics (``supported``: :func:`symkin.runtime.mmc_c.supports`)
        and ``refusal`` (why this controller cannot run in C) is None; else None (the Python step), or
        ConfigurationError for ``"c"``. With ``"auto"`` a C step that fails to build warns."""
        if backend not in ("auto", "c", "python"):
            raise ParameterError(f"backend must be 'auto', 'c' or 'python', not {backend!r}")
        if backend == "python":
            return None
        if not supported:
            refusal = "backend='c' needs C kinematics: symkin.compile(robot, backend='c')"
        if refusal is not None:
            if backend == "c":
                raise ConfigurationError(refusal)
            return None
        try:
            return make()
        except (CompileError, OSError, RuntimeError) as exc:
            if backend == "c":
                raise
            warnings.warn(f"{what} runs in Python: the C step is unavailable ({exc})", stacklevel=3)
            return None
