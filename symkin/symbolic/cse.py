"""Common-subexpression elimination as a stage of its own, with operation counts.

:func:`cse_outputs` takes named outputs (sympy matrices), runs one CSE across all of them and
returns the intermediate terms, the flattened outputs and an :class:`OpCounts` that the emitters
write into each generated file's header (so a diff shows when simplification got worse).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import sympy as sp

__all__ = ["OpCounts", "CSEResult", "count_ops", "cse_outputs", "floatify"]


@dataclass(frozen=True)
class OpCounts:
    """Arithmetic in straight-line code: multiplications (incl. divisions), additions, trig calls."""

    mul: int = 0
    add: int = 0
    trig: int = 0
    other: int = 0

    @property
    def total(self) -> int:
        return self.mul + self.add + self.trig + self.other

    def __add__(self, o: OpCounts) -> OpCounts:
        return OpCounts(self.mul + o.mul, self.add + o.add, self.trig + o.trig, self.other + o.other)

    def __str__(self) -> str:
        return f"{self.total} ops ({self.mul} mul, {self.add} add, {self.trig} trig, {self.other} other)"


def count_ops(expr: sp.Expr) -> OpCounts:
    """Count the operations of one expression as a C compiler would emit them (no sharing)."""
    mul = add = trig = other = 0
    stack = [expr]
    while stack:
        e = stack.pop()
        if e.is_Atom:
            continue
        args = e.args
        if e.is_Add:
            add += len(args) - 1
        elif e.is_Mul:
            coeff, rest = e.as_coeff_mul()
            k = len(rest) - 1 + (0 if coeff in (1, -1) else 1)
            mul += max(k, 0)
            if coeff == -1 and len(rest) >= 1:
                add += 0  # a negation folds into the surrounding add/sub
            args = rest
        elif e.is_Pow:
            exp = e.exp
            if exp.is_Integer and abs(int(exp)) <= 4:
                mul += abs(int(exp)) - 1 + (1 if exp < 0 else 0)
            else:
                other += 1
            args = (e.base,)
        elif isinstance(e, (sp.sin, sp.cos)):
            trig += 1
        else:
            other += 1
        stack.extend(args)
    return OpCounts(mul, add, trig, other)


def floatify(expr: sp.Expr) -> sp.Expr:
    """Replace irrational numeric subexpressions (sqrt(2)/2, cos(1/3)...) by 17-digit Floats.

    Rationals are kept: the printers write them as correctly rounded doubles.
    """
    if expr.is_number:
        if expr.is_Rational:
            return expr
        return sp.Float(float(sp.N(expr, 30)), 17)
    if expr.is_Atom:
        return expr
    return expr.func(*(floatify(a) for a in expr.args), evaluate=False)


@dataclass(frozen=True, eq=False)
class CSEResult:
    """Straight-line code: ``intermediates`` (symbol, expr) in order, then the named outputs.

    ``outputs[name]`` is ``(shape, exprs)`` with the expressions flattened in row-major order.
    """

    intermediates: tuple[tuple[sp.Symbol, sp.Expr], ...]
    outputs: dict[str, tuple[tuple[int, ...], tuple[sp.Expr, ...]]]
    counts: OpCounts
    inputs: tuple[sp.Symbol, ...]


def cse_outputs(
    outputs: Mapping[str, sp.Matrix | tuple[sp.Matrix, ...]],
    inputs: tuple[sp.Symbol, ...],
    prefix: str = "x",
) -> CSEResult:
    """One CSE over all ``outputs`` (a matrix, or a tuple of equal-shape matrices for a 3-D array)."""
    flat: list[sp.Expr] = []
    shapes: dict[str, tuple[tuple[int, ...], int, int]] = {}
    for name, value in outputs.items():
        mats = value if isinstance(value, tuple) else (value,)
        shape = mats[0].shape if not isinstance(value, tuple) else (len(mats), *mats[0].shape)
        start = len(flat)
        for m in mats:
            flat.extend(floatify(x) for x in m)
        shapes[name] = (tuple(shape), start, len(flat))
    symbols = sp.numbered_symbols(prefix)
    repl, reduced = sp.cse(flat, symbols=symbols, order="none", optimizations=None)
    counts = OpCounts()
    for _, e in repl:
        counts = counts + count_ops(e)
    for e in reduced:
        counts = counts + count_ops(e)
    out = {name: (shape, tuple(reduced[a:b])) for name, (shape, a, b) in shapes.items()}
    return CSEResult(tuple(repl), out, counts, tuple(inputs))
