"""Lower kinematic functions to printed lines, shared by every backend's templates."""

from __future__ import annotations

import math
from dataclasses import dataclass

import sympy as sp
from sympy.printing.codeprinter import CodePrinter

from symkin.symbolic.cse import depth
from symkin.symbolic.functions import KinFunction

__all__ = ["PrintedOutput", "PrintedFunction", "PrintedHessian", "lower", "MAX_PRINT_DEPTH"]

# sympy's printers recurse once per nesting level; lines are split long before Python's limit.
MAX_PRINT_DEPTH = 200


@dataclass(frozen=True)
class PrintedOutput:
    """An output: its entries printed (``values``), and for a gathered one (see
    :class:`~symkin.symbolic.cse.CSEResult`) its ``distinct`` printed entries and the ``index``
    of each entry among them (else both empty)."""

    name: str
    shape: tuple[int, ...]
    size: int
    values: tuple[tuple[int, str], ...]  # (flat index, printed expression); empty when a loop writes it
    distinct: tuple[str, ...] = ()
    index: tuple[int, ...] = ()


@dataclass(frozen=True)
class PrintedHessian:
    """A Hessian output written by the loops of ``hessian_<frame>`` from the array ``jacobian``:
    per slot on the path its joint, its column in ``jacobian`` (rows of ``width`` entries) and its
    multiplier (``multipliers`` empty: each joint's one slot, multiplier 1)."""

    out: str
    jacobian: str
    frame: str  # "base" or "ee"
    joints: tuple[int, ...] = ()
    columns: tuple[int, ...] = ()
    multipliers: tuple[float, ...] = ()
    width: int = 0

    @property
    def args(self) -> str:
        """The tables as the Python templates' ``_hessian_<frame>(C, columns, joints, [mult])`` take them."""
        tables = [list(self.columns), list(self.joints)] + (
            [list(self.multipliers)] if self.multipliers else []
        )
        return ", ".join(map(repr, tables))


@dataclass(frozen=True)
class PrintedFunction:
    name: str
    kind: str
    frame: int | None
    doc: str
    counts: str
    inputs: tuple[tuple[str, int], ...]  # (symbol name, joint index) actually used
    lines: tuple[tuple[str, str], ...]  # (temporary name, printed expression)
    outs: tuple[PrintedOutput, ...]  # the results, in order
    scratch: tuple[PrintedOutput, ...] = ()  # local arrays written by lines, read by loops
    hessians: tuple[PrintedHessian, ...] = ()
    strategy: str = "expanded"
    delegate: str = ""  # the function this one calls instead of having code of its own
    delegate_outs: tuple[str, ...] = ()  # that function's outputs, in order
    delegate_pick: tuple[int, ...] = ()  # positions of this function's outputs among them
    order: int = 0  # a derivative<k> function's order k


def _print(printer: CodePrinter, e: sp.Expr) -> str:
    d = depth(e)
    if d > MAX_PRINT_DEPTH:
        raise ValueError(f"expression nested {d} levels deep: too deep to print (limit {MAX_PRINT_DEPTH})")
    return printer.doprint(e)


def _gathered(
    printer: CodePrinter, name: str, shape: tuple[int, ...], exprs: tuple[sp.Expr, ...]
) -> PrintedOutput:
    """A gathered output: each distinct entry printed once, in order of first use."""
    first: dict[sp.Expr, int] = {}
    index = tuple(first.setdefault(e, len(first)) for e in exprs)
    distinct = tuple(_print(printer, e) for e in first)
    values = tuple((i, distinct[k]) for i, k in enumerate(index))
    return PrintedOutput(name, shape, len(exprs), values, distinct, index)


def lower(f: KinFunction, printer: CodePrinter) -> PrintedFunction:
    """Print every intermediate and output of ``f``; inputs limited to the joints used. A function
    that calls ``f.delegate`` prints nothing: its outputs and the callee's others are local arrays."""
    code, n = f.code, len(f.code.inputs)
    own = not f.delegate
    used: set[sp.Symbol] = set()
    for e in [e for _, e in code.intermediates] + [e for _, exprs in code.outputs.values() for e in exprs]:
        used |= e.free_symbols if own else set()
    inputs = tuple((str(s), j) for j, s in enumerate(code.inputs) if s in used)
    lines = tuple((str(s), _print(printer, e)) for s, e in code.intermediates if own)
    every = [
        _gathered(printer, name, shape, exprs)
        if own and name in code.gathered
        else PrintedOutput(
            name, shape, math.prod(shape), tuple((i, _print(printer, e)) for i, e in enumerate(exprs) if own)
        )
        for name, (shape, exprs) in code.outputs.items()
    ]
    hessians = []
    for h in code.hessians:
        every.append(PrintedOutput(h.out, (n, 6, n), 6 * n * n, ()))
        if own:
            width = code.outputs[h.jacobian][0][-1]
            tables = (h.order, h.columns or h.order, h.multipliers or (), width)
            hessians.append(PrintedHessian(h.out, h.jacobian, h.frame, *tables))
    outs = tuple(o for o in every if o.name not in code.scratch)
    scratch = tuple(o for o in every if o.name in code.scratch)
    return PrintedFunction(
        f.name,
        f.kind,
        f.frame,
        f.doc,
        str(code.counts),
        inputs,
        lines,
        outs,
        scratch,
        tuple(hessians),
        code.strategy,
        delegate=f.delegate or "",
        delegate_outs=() if own else tuple(o.name for o in every),
        delegate_pick=() if own else tuple(i for i, o in enumerate(every) if o.name not in code.scratch),
        order=f.order,
    )
