"""Lower kinematic functions to printed lines, shared by every backend's templates."""

from __future__ import annotations

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
    name: str
    shape: tuple[int, ...]
    size: int
    values: tuple[tuple[int, str], ...]  # (flat index, printed expression); empty when a loop writes it


@dataclass(frozen=True)
class PrintedHessian:
    """A Hessian output written by the loops of ``hessian_<frame>`` from the array ``jacobian``."""

    out: str
    jacobian: str
    frame: str  # "base" or "ee"


@dataclass(frozen=True)
class PrintedFunction:
    name: str
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


def _print(printer: CodePrinter, e: sp.Expr) -> str:
    d = depth(e)
    if d > MAX_PRINT_DEPTH:
        raise ValueError(f"expression nested {d} levels deep: too deep to print (limit {MAX_PRINT_DEPTH})")
    return printer.doprint(e)


def _size(shape: tuple[int, ...]) -> int:
    size = 1
    for d in shape:
        size *= d
    return size


def lower(f: KinFunction, printer: CodePrinter) -> PrintedFunction:
    """Print every intermediate and output of ``f``; inputs limited to the joints used."""
    code = f.code
    if f.delegate:
        return _lower_delegate(f)
    used: set[sp.Symbol] = set()
    for _, e in code.intermediates:
        used |= e.free_symbols
    for _, (_, exprs) in code.outputs.items():
        for e in exprs:
            used |= e.free_symbols
    inputs = tuple((str(s), j) for j, s in enumerate(code.inputs) if s in used)
    lines = tuple((str(s), _print(printer, e)) for s, e in code.intermediates)
    outs, scratch = [], []
    for name, (shape, exprs) in code.outputs.items():
        printed = PrintedOutput(
            name, shape, _size(shape), tuple((i, _print(printer, e)) for i, e in enumerate(exprs))
        )
        (scratch if name in code.scratch else outs).append(printed)
    hessians = []
    for h in code.hessians:
        n = len(h.order)
        outs.append(PrintedOutput(h.out, (n, 6, n), 6 * n * n, ()))
        hessians.append(PrintedHessian(h.out, h.jacobian, h.frame))
    return PrintedFunction(
        f.name,
        f.doc,
        str(code.counts),
        inputs,
        lines,
        tuple(outs),
        tuple(scratch),
        tuple(hessians),
        code.strategy,
    )


def _lower_delegate(f: KinFunction) -> PrintedFunction:
    """A function that calls ``f.delegate``: its outputs and the callee's others as local arrays."""
    code = f.code
    n = len(code.inputs)
    shapes = [(name, shape) for name, (shape, _) in code.outputs.items()]
    shapes += [(h.out, (n, 6, n)) for h in code.hessians]
    every = [PrintedOutput(name, shape, _size(shape), ()) for name, shape in shapes]
    outs = tuple(o for o in every if o.name not in code.scratch)
    return PrintedFunction(
        f.name,
        f.doc,
        str(code.counts),
        (),
        (),
        outs,
        tuple(o for o in every if o.name in code.scratch),
        (),
        code.strategy,
        delegate=f.delegate or "",
        delegate_outs=tuple(o.name for o in every),
        delegate_pick=tuple(i for i, o in enumerate(every) if o.name not in code.scratch),
    )
