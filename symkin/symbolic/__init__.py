"""Symbolic kinematics (sympy): derivation, functions to emit, CSE.

The package itself is callable: ``symkin.symbolic(robot)`` returns the exact sympy expressions of
the pose, Jacobians and Hessians and the joint symbols (:func:`symkin.symbolic.expressions.symbolic`);
``symkin.symbolic.jacob0_analytical(robot, representation)`` the analytical Jacobian
(:mod:`symkin.symbolic.analytical`).
Nothing here imports sympy until it is used.
"""

from __future__ import annotations

import sys
import types
from typing import Any


class _CallablePackage(types.ModuleType):
    def __call__(self, robot: Any, form: str = "expanded") -> Any:
        """``symkin.symbolic(robot, form="expanded")``: see :func:`symkin.symbolic.expressions.symbolic`."""
        from symkin.symbolic.expressions import symbolic

        return symbolic(robot, form=form)


def jacob0_analytical(robot: Any, representation: str = "rpy/xyz") -> Any:
    """The analytical Jacobian as a sympy Matrix: see :func:`symkin.symbolic.analytical.jacob0_analytical`."""
    from symkin.symbolic.analytical import jacob0_analytical as _jacob0_analytical

    return _jacob0_analytical(robot, representation)


sys.modules[__name__].__class__ = _CallablePackage
