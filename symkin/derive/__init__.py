"""Teaching derivations: the symbolic FK, Jacobian and Hessian of a chain, a tree or a closed-form
IK solution, written as Markdown or LaTeX (``symkin derive``).

The package itself is callable: ``symkin.derive(robot, ...)`` is
:func:`symkin.derive.chain.derivation`, before and after its submodules are imported (importing
``symkin.derive.chain`` binds this package as ``symkin.derive``, so the package is the function).
Nothing here imports sympy until it is used.
"""

from __future__ import annotations

import sys
import types
from typing import Any


class _CallablePackage(types.ModuleType):
    def __call__(self, *args: Any, **kwargs: Any) -> str:
        """``symkin.derive(robot, fmt="markdown", ...)``: see :func:`symkin.derive.chain.derivation`."""
        from symkin.derive.chain import derivation

        return derivation(*args, **kwargs)


sys.modules[__name__].__class__ = _CallablePackage
