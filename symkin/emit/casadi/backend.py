"""The CasADi backend: a generated Python module that builds ``casadi.Function`` objects (SX).

For optimisation users (``casadi.Opti``, NLPs, MPC), not the fast path: calling a CasADi
function from Python with NumPy arguments costs tens of microseconds.
"""

from __future__ import annotations

from typing import Any

from symkin.emit.templates import chain_tables, render_python_module

__all__ = ["render_casadi"]


def casadi_outs(outs: list) -> list[dict[str, Any]]:
    """The printed outputs as the CasADi templates write them: name, entries, and the rows and
    columns of the SX matrix (a 3-D output stacked)."""
    return [
        {"name": o.name, "vals": o.values, "rows": o.size // max(o.shape[-1], 1), "cols": o.shape[-1]}
        for o in outs
    ]


def render_casadi(robot: Any, functions: list, command: str) -> dict[str, str]:
    """The generated module ``symkin_<robot>_casadi.py``."""
    from symkin.emit.lowering import lower
    from symkin.emit.printers import CasADiPrinter

    printed = []
    for f in functions:
        p = lower(f, CasADiPrinter())
        printed.append(
            {
                "name": p.name,
                "inputs": p.inputs,
                "lines": p.lines,
                "outs": casadi_outs(p.outs),
                "scratch": casadi_outs(p.scratch),
                "hessians": p.hessians,
                "delegate": p.delegate,
                "delegate_pick": p.delegate_pick,
            }
        )
    return render_python_module(
        "casadi/module.py.j2",
        robot,
        functions,
        printed,
        command,
        "_casadi",
        chain=chain_tables(robot),
        hessian_frames=sorted({h.frame for f in printed for h in f["hessians"]}),
    )
