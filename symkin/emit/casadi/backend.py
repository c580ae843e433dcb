"""The CasADi backend: a generated Python module that builds ``casadi.Function`` objects (SX).

For optimisation users (``casadi.Opti``, NLPs, MPC), not the fast path: calling a CasADi
function from Python with NumPy arguments costs tens of microseconds.
"""

from __future__ import annotations

from typing import Any

from symkin.emit.templates import python_module

__all__ = ["render_casadi"]


def render_casadi(kernel: Any) -> dict[str, str]:
    """The generated module ``symkin_<code_name>_casadi.py`` of ``kernel``: its functions lowered
    (:func:`symkin.emit.lowering.lower`) and printed for CasADi SX (a 3-D output stacked into rows)."""
    from symkin.emit.lowering import lower
    from symkin.emit.printers import CasADiPrinter

    return python_module(
        "casadi/module.py.j2",
        kernel,
        [lower(f, CasADiPrinter()) for f in kernel.functions],
        "_casadi",
    )
