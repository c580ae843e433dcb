"""The QP step of numerical IK in C (``csrc/mmc_ik.c``): an MMC controller of :mod:`symkin.runtime.mmc_c`
set up for the QP of :mod:`symkin.runtime.ik_qp`, whose step the C search loop of
:class:`~symkin.runtime.ik_c.CIKSolver` calls (``method="QP"``).

The QP's weights map onto the MMC's: with a manipulability term of weight w > 0 the objective is
divided by w (the controller's ``lam`` is ``lam / w`` and the step sets the slack weight to
``slack_gain / (w sum|e|)``; the same minimiser), without one the controller evaluates J alone
(``no_jm``). The controller solves the QP also at a singular J (``singular_qp``: Jm = 0 there), and
its joint limits are those the dampers keep (:func:`~symkin.runtime.ik_qp.damped_limits`).

The embedded OSQP solvers of an MMC library are shared by its controllers, so a QP solve holds the
GIL (the IK library is called through :class:`ctypes.PyDLL`). The MMC machinery sits above the C IK
solver (its collision rows use modules that use the solver), so this module registers
:class:`QPStep` with :func:`symkin.runtime.ik_c.register_qp_step` when it is imported (by
:mod:`symkin.runtime.kinematics`, with every compiled kinematics).
"""

from __future__ import annotations

import ctypes
from typing import Any

import numpy as np

from symkin.errors import ConfigurationError, ParameterError
from symkin.runtime.cext import address, layout
from symkin.runtime.ik_c import register_qp_step
from symkin.runtime.ik_problem import IKOptions

__all__ = ["QPStep", "collision_qp_ik"]

_P, _I32, _D = ctypes.c_void_p, ctypes.c_int32, ctypes.c_double


_STEP = ctypes.PYFUNCTYPE(ctypes.c_int, _P, _P, _P, _P, _P)  # symkin_ik_step_fn, called with the GIL held


class _Ctx(ctypes.Structure):  # symkin_mmc_ik_ctx (mmc_ik.h)
    _fields_ = [("ctrl", _P), ("collision", _I32), ("pad_", _I32), ("slack", _D)]


class QPStep:
    """The C QP step for kinematics ``kin`` (compiled C, n joints) and options ``opt`` (method
    ``"QP"``): ``function`` and ``context`` are the ``symkin_ik_step_fn`` and its argument for the
    search loop's config. ``environment`` (an :class:`~symkin.geometry.pairs.Environment`) adds the
    MMC's collision rows (``collision_rows`` closest pairs within ``d_i``; needs the C collision
    kernel). Keeps the controller (and so its libraries) alive."""

    def __init__(self, kin: Any, opt: IKOptions, environment: Any = None, **collision: Any) -> None:
        from symkin.runtime import mmc_c
        from symkin.runtime.control import MMC
        from symkin.runtime.ik_qp import damped_limits

        if not mmc_c.supports(kin):
            raise ConfigurationError(
                "method='QP' in C needs compiled C kinematics with their Hessian "
                "(symkin.compile(robot, backend='c'); a tree frame's path without mimic joints); "
                "use backend='numpy'"
            )
        w = opt.manipulability
        scale = w if w > 0 else 1.0
        self.mmc = MMC(
            kin, lam=float(opt.lam[0]) / scale, qd_max=np.inf, joint_limits=opt.joint_limits, rho_i=opt.rho_i,
            rho_s=opt.rho_s, xi=opt.xi, dt=1.0, slack=True, slack_weight=1.0, backend="c",
            collision=environment, **collision,
        )  # fmt: skip
        controller = self.mmc._c
        c = controller._ctrl
        c.no_jm, c.singular_qp = int(w == 0), 1
        lo, hi = damped_limits(opt)
        c.qlo[:], c.qhi[:] = lo.tolist(), hi.tolist()
        lib = controller.lib
        layout(lib, "symkin_mmc_ik_layout", (ctypes.sizeof(_Ctx),))
        self._ctx = _Ctx(ctypes.addressof(c), int(environment is not None), 0, opt.slack_gain / scale)
        self.context = ctypes.addressof(self._ctx)
        self.function = address(lib.symkin_mmc_ik_step)
        self.n = opt.n

    def step(self, q: Any, e: Any) -> np.ndarray | None:
        """The step qd (n,) at q (n,) for the pose error e (6,) there (one C call, the search loop's),
        or None when there is none (e zero or not finite, or the step failed)."""
        q, e = (np.ascontiguousarray(x, dtype=float) for x in (q, e))
        if q.shape != (self.n,) or e.shape != (6,):
            raise ParameterError(f"step takes q ({self.n},) and e (6,), got {q.shape} and {e.shape}")
        dq = np.empty(self.n)
        failed = _STEP(self.function)(self.context, q.ctypes.data, None, e.ctypes.data, dq.ctypes.data)
        return None if failed else dq


def collision_qp_ik(kin: Any, Tep: Any, collision: Any, collision_attempts: Any = None, **kwargs: Any) -> Any:
    """``kin.ik(Tep, method="QP", collision=env, **kwargs)`` on compiled C kinematics of a chain:
    the QP step with the MMC's collision rows (the robot's closest pairs within ``d_i`` keep their
    distance dampers; options ``d_i``, ``d_s``, ``xi_d``, ``collision_rows``, ``d_i_self``,
    ``d_s_self`` of :class:`~symkin.runtime.control.MMC`), and a converged solution that collides
    is rejected (the next search starts; the reason counts them): the solver of
    :func:`symkin.runtime.collision.collision_solver` with the rows. ``collision_attempts`` is not
    used: the search loop itself keeps looking, within ``slimit`` searches."""
    from symkin.runtime.collision import collision_solver
    from symkin.runtime.ik import IK_OPTIONS

    q0, seed = kwargs.pop("q0", None), kwargs.pop("seed", None)
    rows = {k: kwargs.pop(k) for k in ROW_OPTIONS if k in kwargs}
    unknown = sorted(set(kwargs) - set(IK_OPTIONS))
    if unknown:
        raise TypeError(f"ik(method='QP', collision=...) got unexpected options {unknown}")
    solver = collision_solver(kin, collision, kwargs, rows=rows)
    if solver is None:  # pragma: no cover - C kinematics have the C kernel
        raise ConfigurationError("method='QP' with collision needs the C collision kernel")
    return solver.solve(Tep, q0, seed)


#: the MMC's collision-row options that kin.ik(method="QP", collision=...) takes
ROW_OPTIONS = ("d_i", "d_s", "xi_d", "collision_rows", "d_i_self", "d_s_self")


register_qp_step(QPStep)
