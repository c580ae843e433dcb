"""Compiled kinematics: the object :func:`symkin.compile` returns (no sympy here).

It has the numeric reference's methods and shapes (``fkine``, ``link_poses``, ``jacob0``,
``jacobe``, ``hessian0``, ``hessiane``, ``manipulability``, ``jacobm``, ``cond``, ``jacobs``,
``jacobb``, ``jacob0_dot``) plus the fused ``fkine_jacob0`` and ``jacob0_hessian0`` used by IK and
control; the last four are computed here from the generated functions. On the C backend the methods are
the extension module's functions themselves, so a call costs one C function call.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property
from types import MethodType
from typing import Any

import numpy as np

from symkin.compiler.compile import Artifact, build, cache_key
from symkin.core.arrays import as_batch, axes_rows
from symkin.errors import ConfigurationError
from symkin.model.robot import Robot, cond_of, jacob_dot_of, jacobm_of, manipulability_of, space_jacobian
from symkin.runtime.casadi_calls import chain_functions
from symkin.runtime.compiled import CompiledModel
from symkin.runtime.ik import ik
from symkin.runtime.manip import jacobm_one, manipulability_one
from symkin.runtime.memo import memoised

__all__ = ["Kinematics", "KIN_METHODS", "kinematics_of", "load_chain"]

C_IK_MAX_JOINTS = 12  # SYMKIN_IK_NMAX of the C solver; longer chains use the NumPy solver

KIN_METHODS = (
    "fkine",
    "link_poses",
    "jacob0",
    "jacobe",
    "hessian0",
    "hessiane",
    "fkine_jacob0",
    "jacob0_hessian0",
)


def _rebuild(robot: Robot, backend: str) -> Kinematics:
    """The kinematics of ``robot`` on ``backend`` (the unpickler of :class:`Kinematics`)."""
    return load_chain(robot, backend)


def load_chain(
    robot: Robot, backend: str = "c", cache: bool = True, strategy: str | None = None
) -> Kinematics:
    """The compiled kinematics of the chain ``robot`` on ``backend`` (memoised per cache key: every
    attribute of the robot, see :mod:`symkin.compiler.compile`)."""
    key = cache_key(robot, backend, strategy)
    return memoised(
        key, lambda: kinematics_of(robot, build(robot, backend, cache, strategy, key), backend), cache
    )


def kinematics_of(robot: Robot, art: Artifact, backend: str) -> Kinematics:
    """The :class:`Kinematics` of ``robot`` around its built code ``art``."""
    if backend == "casadi":
        fns = art.module.functions()
        kin = Kinematics(
            robot, backend, chain_functions(robot, fns, KIN_METHODS), art.files, art.path, art.module
        )
        kin.functions = fns  # type: ignore[attr-defined]
        return kin
    names = (*KIN_METHODS, "manipulability", "jacobm") if backend == "c" else KIN_METHODS
    functions = {name: getattr(art.module, name) for name in names}
    return Kinematics(robot, backend, functions, art.files, art.path, art.module)


class Kinematics(CompiledModel):
    """Generated kinematics of ``robot`` on one backend ("c", "numpy" or "casadi").

    Attributes: ``robot``, ``backend``, ``n``, ``qlim``, ``qd_max``, ``name``, ``files`` (the
    generated sources), ``path`` (the compiled library or module), ``module``.
    """

    fkine: Callable[[Any], np.ndarray]
    link_poses: Callable[[Any], np.ndarray]
    jacob0: Callable[[Any], np.ndarray]
    jacobe: Callable[[Any], np.ndarray]
    hessian0: Callable[[Any], np.ndarray]
    hessiane: Callable[[Any], np.ndarray]
    fkine_jacob0: Callable[[Any], tuple[np.ndarray, np.ndarray]]
    jacob0_hessian0: Callable[[Any], tuple[np.ndarray, np.ndarray]]

    METHODS = KIN_METHODS

    def _setup(self, functions: dict[str, Callable[..., Any]]) -> None:
        self.robot = self.model
        self._ik_solver: Any = None  # the C IK solver with the default options, after a first call
        self._ik_fast: Callable[[Any], Any] | None = None  # its solve of one target (None: check)
        self._c_rrmc: dict[tuple, Any] = {}  # C RRMC controllers by options (symkin.runtime.control.rrmc)
        if "manipulability" in functions:
            self.manipulability = functions["manipulability"]
            self.jacobm = functions["jacobm"]

    def __repr__(self) -> str:
        return f"Kinematics(robot={self.robot.name!r}, n={self.n}, backend={self.backend!r})"

    def __reduce__(self) -> tuple[Any, tuple[Robot, str]]:
        """Pickle as (robot, backend): unpickling compiles again, which loads the generated code
        from the compile cache of the process that unpickles (a Dask worker, say) when it is there."""
        return (_rebuild, (self.robot, self.backend))

    def manipulability(self, q: Any, axes: str = "all") -> np.ndarray | float:  # type: ignore[no-redef]
        """Yoshikawa manipulability of the chosen rows of J0 (eq 52): float, or (N,) for a batch.

        One configuration takes the backend's single-configuration J0 and no determinant routine
        (:func:`symkin.runtime.manip.manipulability_one`)."""
        rows = axes_rows(axes)
        if type(q) is np.ndarray and q.ndim == 1:  # jacob0 checks q
            return manipulability_one(self.jacob0(q)[rows])
        Q, single = as_batch(q, self.n, self.name)
        if single:
            return manipulability_one(self.jacob0(Q[0])[rows])
        return manipulability_of(self.jacob0(Q)[:, rows])

    def jacobm(self, q: Any, axes: str = "all") -> np.ndarray:  # type: ignore[no-redef]
        """Manipulability Jacobian (Haviland and Corke, Maximising Manipulability During Resolved-Rate
        Motion Control, 2020, eq 11), (n,) or (N, n)."""
        rows = axes_rows(axes)
        Q, single = as_batch(q, self.n, self.name)
        if single:
            J, H = self.jacob0_hessian0(Q[0])
            return jacobm_one(J[rows], H[:, rows])
        J, H = self.jacob0_hessian0(Q)
        return jacobm_of(J[:, rows], H[:, :, rows])

    def cond(self, q: Any, axes: str = "all") -> np.ndarray | float:
        """Condition number of the chosen rows of J0 (eq 53), inf at a singular configuration."""
        rows = axes_rows(axes)
        Q, single = as_batch(q, self.n, self.name)
        c = cond_of(self.jacob0(Q)[:, rows])
        return float(c[0]) if single else c

    def jacobs(self, q: Any) -> np.ndarray:
        """Space Jacobian of Lynch and Park's Modern Robotics: (6, n) or (N, 6, n), rows
        (omega, v_s) with v_s = v_e - omega x p_e the velocity of the point at the base origin."""
        Q, single = as_batch(q, self.n, self.name)
        if single:
            T, J = self.fkine_jacob0(Q[0])
            return space_jacobian(T[None], J[None])[0]
        return space_jacobian(*self.fkine_jacob0(Q))

    def jacobb(self, q: Any) -> np.ndarray:
        """Body Jacobian of Modern Robotics: (6, n) or (N, 6, n), rows (omega, v) in the
        end-effector frame (``jacobe`` with its row blocks swapped)."""
        Je = self.jacobe(q)
        return np.concatenate((Je[..., 3:, :], Je[..., :3, :]), axis=-2)

    def jacob0_dot(self, q: Any, qd: Any) -> np.ndarray:
        """dJ0/dt = sum_i H0[i] qd_i at joint velocity ``qd`` (as roboticstoolbox's ``jacob0_dot``):
        (6, n), or (N, 6, n) for q and qd of shape (N, n). Rows (v, omega), base frame."""
        Q, single = as_batch(q, self.n, self.name)
        Qd, _ = as_batch(qd, self.n, self.name, "qd")
        if Qd.shape[0] != Q.shape[0]:
            raise ConfigurationError(f"q and qd hold {Q.shape[0]} and {Qd.shape[0]} configurations")
        if single:
            return np.tensordot(Qd[0], self.hessian0(Q[0]), axes=(0, 0))
        return jacob_dot_of(self.hessian0(Q), Qd)

    def _repr_markdown_(self) -> str:
        """Notebook view: the backend, the generated files and the robot's joint table."""
        from symkin.model.describe import md_text, robot_markdown

        files = ", ".join(f"`{md_text(f)}`" for f in sorted(self.files))
        head = f"**{md_text(self.name)}** compiled for the **{self.backend}** backend ({files})"
        methods = (
            "fkine, link_poses, jacob0, jacobe, jacobs, jacobb, jacob0_dot, hessian0, hessiane, "
            "manipulability, jacobm, cond, ik"
        )
        return robot_markdown(self.robot, head) + f"Methods: {methods}.\n"

    @cached_property
    def c_fkjac(self) -> Any:
        """The C entry point ``fkine_jacob0(q, T, J)`` as a ctypes function (C backend only), for
        the C IK solver."""
        if self.backend != "c" or self.path is None:
            raise AttributeError("c_fkjac exists only on the C backend")
        from symkin.emit.c.build import load_library

        return getattr(load_library(self.path), f"{self.c_prefix}_fkine_jacob0")

    def ik(self, Tep: Any, **kwargs: Any) -> Any:
        """Numerical inverse kinematics (eqs 37-51); see :func:`symkin.runtime.ik.ik` for the options.

        On the C backend the whole solver loop runs in C on the generated kinematics; on the
        NumPy and CasADi backends the NumPy solver calls the generated functions. A call with the
        default options goes straight to the C solver; after the first one, ``kin.ik`` is the C
        solver's entry point itself, which solves one target without a Python frame (one target
        costs little more than the solve itself) and passes any other call on to this method. It
        is thread-safe.

        ``method="analytic"``: the closed form (:meth:`ik_all`), returning the solution nearest
        ``q0`` (options ``q0``, ``weights``, ``joint_limits``, ``tol``); ``success=False`` with a
        reason when the pose is out of reach or every solution is outside the joint limits. For a
        redundant arm ``free_joint=j`` sweeps joint ``j`` (64 values over its limits, or one turn,
        plus ``q0[j]``) and ``free_joint=(j, values)`` tries the given values; see :meth:`ik_all`.
        """
        if not kwargs and self._ik_fast is not None:
            res = self._ik_fast(Tep)
            return res if res is not None else self._ik_solver.solve(Tep)  # None: Tep needs checking
        if kwargs.get("method") == "analytic":
            options = {k: v for k, v in kwargs.items() if k != "method"}
            unknown = sorted(set(options) - {"q0", "weights", "joint_limits", "tol", "free_joint"})
            if unknown:
                raise TypeError(
                    f"method='analytic' takes q0, weights, joint_limits, tol, free_joint; not {unknown}"
                )
            free = options.pop("free_joint", None)
            if free is not None:
                from symkin.runtime.free_joint import free_joint_solver, parse_free_joint

                j, values = parse_free_joint(free)
                return free_joint_solver(self.robot, j, self.backend).ik(Tep, values, **options)
            return self.analytic.ik(Tep, fkine=self.fkine, **options)
        c_loop = self.backend == "c" and self.n <= C_IK_MAX_JOINTS
        kwargs.setdefault("backend", "c" if c_loop else "numpy")
        if kwargs == {"backend": "c"} and c_loop:  # the defaults: keep the C solver for the next call
            from symkin.runtime.ik import default_c_solver

            self._ik_solver = solver = default_c_solver(self)
            self._ik_fast = solver.fast
            bound = solver.bind(MethodType(Kinematics.ik, self))
            if bound is not None:  # later calls of one target: one C call, no Python frame
                self.__dict__["ik"] = bound
            return solver.solve(Tep)
        return ik(self, Tep, **kwargs)

    # -- closed-form inverse kinematics (symkin.compiler.analytic_ik) -------------------------------------
    @cached_property
    def analytic(self) -> Any:
        """The closed-form solver of this robot on this backend (compiled on first use); raises
        NoAnalyticIKError naming what the arm lacks."""
        from symkin.runtime.analytic_ik import compile_analytic

        return compile_analytic(self.robot, self.backend)

    @property
    def has_analytic_ik(self) -> bool:
        """Whether symkin derives a closed-form IK for this arm (cached; see :meth:`ik_all`)."""
        from symkin.compiler.analytic_ik import analytic_refusal

        return analytic_refusal(self.robot, self.backend) is None

    def ik_all(
        self, T: Any, q0: Any = None, joint_limits: bool = True, weights: Any = None, free_joint: Any = None
    ) -> np.ndarray:
        """Every distinct closed-form solution of the pose ``T`` (base frame).

        ``T`` (4, 4) -> (k, n), ordered by ``sum_j weights_j (q_j - q0_j)^2`` when ``q0`` is given;
        ``T`` (N, 4, 4) -> (N, S, n) with NaN rows after each pose's solutions (S: the arm's
        maximum, 8 for a 6R arm). Revolute joints are wrapped by 2 pi into the joint limits where a
        shift allows; with ``joint_limits`` rows outside them are dropped. See
        :mod:`symkin.runtime.analytic_ik`. On the C backend later calls go straight to the compiled
        solver (the same signature, plus ``tol``): no Python frame per pose.

        ``free_joint=(j, values)`` (redundant arms): joint ``j``, the first or the last of the chain,
        takes each of ``values`` (a number or a 1-D array) and the other joints are solved in closed
        form; (N, 4, 4) -> (N, V * S, n). See :mod:`symkin.runtime.free_joint`.
        """
        if free_joint is not None:
            from symkin.runtime.free_joint import free_joint_solver, parse_free_joint

            j, values = parse_free_joint(free_joint)
            if values is None:
                raise ConfigurationError("ik_all needs the values of the free joint: free_joint=(j, values)")
            return free_joint_solver(self.robot, j, self.backend).ik_all(T, values, q0, joint_limits, weights)
        solver = self.analytic
        if self.backend == "c":
            self.__dict__["ik_all"] = solver.ik_all
        return solver.ik_all(T, q0, joint_limits, weights)
