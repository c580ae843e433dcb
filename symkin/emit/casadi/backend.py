"""The CasADi backend: a generated Python module that builds ``casadi.Function`` objects (SX).

For optimisation users (``casadi.Opti``, NLPs, MPC), not the fast path: calling a CasADi
function from Python with NumPy arguments costs tens of microseconds.
"""

from __future__ import annotations

from typing import Any

from symkin.emit.templates import python_module

__all__ = ["render_casadi"]


def casadi_function(f: Any) -> dict[str, Any]:
    """Function ``f`` lowered for the CasADi templates (chains and trees): its inputs, lines,
    Hessians and delegate, and its outputs and scratch arrays as SX matrices (name, entries, rows,
    columns; a 3-D output stacked)."""
    from symkin.emit.lowering import lower
    from symkin.emit.printers import CasADiPrinter

    p = lower(f, CasADiPrinter())

    def table(outs: tuple) -> list[dict[str, Any]]:
        return [
            {"name": o.name, "vals": o.values, "rows": o.size // max(o.shape[-1], 1), "cols": o.shape[-1]}
            for o in outs
        ]

    return {
        "name": p.name,
        "inputs": p.inputs,
        "lines": p.lines,
        "outs": table(p.outs),
        "scratch": table(p.scratch),
        "hessians": p.hessians,
        "delegate": p.delegate,
        "delegate_pick": p.delegate_pick,
    }


def render_casadi(kernel: Any) -> dict[str, str]:
    """The generated module ``symkin_<code_name>_casadi.py`` of ``kernel``."""
    return python_module(
        "casadi/module.py.j2",
        kernel,
        [casadi_function(f) for f in kernel.functions],
        "_casadi",
    )
