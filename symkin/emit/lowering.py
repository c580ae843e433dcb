"""Lower CSE'd kinematic functions to printed lines, shared by every backend's templates."""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp
from sympy.printing.codeprinter import CodePrinter

from symkin.symbolic.functions import KinFunction

__all__ = ["PrintedOutput", "PrintedFunction", "lower"]


@dataclass(frozen=True)
class PrintedOutput:
    name: str
    shape: tuple[int, ...]
    size: int
    values: tuple[tuple[int, str], ...]  # (flat index, printed expression)


@dataclass(frozen=True)
class PrintedFunction:
    name: str
    doc: str
    counts: str
    inputs: tuple[tuple[str, int], ...]  # (symbol name, joint index) actually used
    lines: tuple[tuple[str, str], ...]  # (temporary name, printed expression)
    outs: tuple[PrintedOutput, ...]


def lower(f: KinFunction, printer: CodePrinter) -> PrintedFunction:
    """Print every intermediate and output of ``f``; inputs limited to the joints used."""
    code = f.code
    used: set[sp.Symbol] = set()
    for _, e in code.intermediates:
        used |= e.free_symbols
    for _, (_, exprs) in code.outputs.items():
        for e in exprs:
            used |= e.free_symbols
    inputs = tuple((str(s), j) for j, s in enumerate(code.inputs) if s in used)
    lines = tuple((str(s), printer.doprint(e)) for s, e in code.intermediates)
    outs = []
    for name, (shape, exprs) in code.outputs.items():
        size = 1
        for d in shape:
            size *= d
        outs.append(
            PrintedOutput(name, shape, size, tuple((i, printer.doprint(e)) for i, e in enumerate(exprs)))
        )
    return PrintedFunction(f.name, f.doc, str(code.counts), inputs, lines, tuple(outs))
