"""Pieces both closed-form IK body writers use (the NumPy/Python one and the C one): output
slots, CSE of a step's expressions, which names later steps read, and the cos/sin names of an
angle."""

from __future__ import annotations

from dataclasses import dataclass

import sympy as sp

from symkin.symbolic.analytic_ik import AnalyticIK
from symkin.symbolic.cse import floatify

__all__ = ["Out", "cse_lines", "used_later", "cs_names"]


@dataclass
class Out:
    lines: list[str]
    depth: int

    def emit(self, text: str) -> None:
        self.lines.append("    " * self.depth + text)


def cse_lines(exprs: list[sp.Expr], prefix: str) -> tuple[list[tuple[sp.Symbol, sp.Expr]], list[sp.Expr]]:
    flat = [floatify(e) for e in exprs]
    repl, reduced = sp.cse(flat, symbols=sp.numbered_symbols(prefix), order="none")
    return list(repl), list(reduced)


def used_later(plan: AnalyticIK) -> list[set[str]]:
    """Names of the symbols each step's successors use."""
    used: list[set[str]] = []
    acc: set[str] = set()
    for st in reversed(plan.steps):
        used.append(set(acc))
        for _, e in st.exprs:
            acc |= {str(s) for s in e.free_symbols}
    return used[::-1]


def cs_names(var: str) -> tuple[str, str]:
    suffix = var[1:] if var.startswith("q") else var
    return f"c{suffix}", f"s{suffix}"
