"""Compiled kinematics: the object :func:`symkin.compile` returns (no sympy here).

It has the numeric reference's methods and shapes (``fkine``, ``link_poses``, ``jacob0``,
``jacobe``, ``hessian0``, ``hessiane``, ``manipulability``, ``jacobm``) plus the fused
``fkine_jacob0`` and ``jacob0_hessian0`` used by IK and control. On the C backend the methods are
the extension module's functions themselves, so a call costs one C function call.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import cached_property
from pathlib import Path
from types import ModuleType
from typing import Any

import numpy as np

from symkin.model.robot import AXES_ROWS, Robot, as_batch, jacobm_of, manipulability_of
from symkin.runtime.ik import ik

__all__ = ["Kinematics", "KIN_METHODS"]

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


def _rows(axes: str) -> slice:
    try:
        return AXES_ROWS[axes]
    except KeyError:
        raise ValueError(f"axes must be one of {sorted(AXES_ROWS)}, not {axes!r}") from None


def _rebuild(robot: Robot, backend: str) -> Kinematics:
    """The kinematics of ``robot`` on ``backend`` (the unpickler of :class:`Kinematics`)."""
    from symkin.compile import compile as compile_robot

    return compile_robot(robot, backend=backend)


class Kinematics:
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

    def __init__(
        self,
        robot: Robot,
        backend: str,
        functions: dict[str, Callable[..., Any]],
        files: dict[str, str],
        path: Path | None = None,
        module: ModuleType | None = None,
    ) -> None:
        self.robot = robot
        self.backend = backend
        self.files = files
        self.path = path
        self.module = module
        for name in KIN_METHODS:
            setattr(self, name, functions[name])
        if "manipulability" in functions:
            self.manipulability = functions["manipulability"]
            self.jacobm = functions["jacobm"]

    @property
    def n(self) -> int:
        return self.robot.n

    @property
    def name(self) -> str:
        return self.robot.name

    @property
    def qlim(self) -> np.ndarray:
        return self.robot.qlim

    @property
    def qd_max(self) -> np.ndarray | None:
        return self.robot.qd_max

    def __repr__(self) -> str:
        return f"Kinematics(robot={self.robot.name!r}, n={self.n}, backend={self.backend!r})"

    def __reduce__(self) -> tuple[Any, tuple[Robot, str]]:
        """Pickle as (robot, backend): unpickling compiles again, which loads the generated code
        from the compile cache of the process that unpickles (a Dask worker, say) when it is there."""
        return (_rebuild, (self.robot, self.backend))

    def manipulability(self, q: Any, axes: str = "all") -> np.ndarray | float:  # type: ignore[no-redef]
        """Yoshikawa manipulability of the chosen rows of J0 (eq 52)."""
        rows = _rows(axes)
        Q, single = as_batch(q, self.n, self.name)
        J = self.jacob0(Q)
        m = manipulability_of(J[:, rows])
        return float(m[0]) if single else m

    def jacobm(self, q: Any, axes: str = "all") -> np.ndarray:  # type: ignore[no-redef]
        """Manipulability Jacobian (seed 001 eq 11), (n,) or (N, n)."""
        rows = _rows(axes)
        Q, single = as_batch(q, self.n, self.name)
        J, H = self.jacob0_hessian0(Q)
        Jm = jacobm_of(J[:, rows], H[:, :, rows])
        return Jm[0] if single else Jm

    @cached_property
    def c_fkjac(self) -> Any:
        """The C entry point ``fkine_jacob0(q, T, J)`` as a ctypes function (C backend only), for
        the C IK solver."""
        if self.backend != "c" or self.path is None:
            raise AttributeError("c_fkjac exists only on the C backend")
        from symkin.emit.c.backend import c_prefix
        from symkin.emit.c.build import load_library

        return getattr(load_library(self.path), f"{c_prefix(self.robot)}_fkine_jacob0")

    def ik(self, Tep: Any, **kwargs: Any) -> Any:
        """Numerical inverse kinematics (eqs 37-51); see :func:`symkin.runtime.ik.ik` for the options.

        On the C backend the whole solver loop runs in C on the generated kinematics; on the
        NumPy and CasADi backends the NumPy solver calls the generated functions.
        """
        c_loop = self.backend == "c" and self.n <= C_IK_MAX_JOINTS
        kwargs.setdefault("backend", "c" if c_loop else "numpy")
        return ik(self, Tep, **kwargs)
