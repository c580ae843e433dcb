"""Common-subexpression elimination as a stage of its own, with operation counts.

:func:`cse_outputs` takes named outputs (sympy matrices), runs one CSE across all of them and
returns the intermediate terms, the flattened outputs and an :class:`OpCounts` that the emitters
write into each generated file's header (so a diff shows when simplification got worse).
"""

from __future__ import annotations

import itertools
from collections.abc import Iterable, Mapping
from dataclasses import dataclass

import sympy as sp
from sympy.core.function import AppliedUndef

__all__ = ["OpCounts", "CSEResult", "count_ops", "cse_outputs", "floatify", "tree_size", "depth"]


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


def _postorder(roots: list[sp.Basic], skip: Mapping[sp.Basic, object] | None = None) -> list[sp.Basic]:
    """Every distinct node under ``roots``, children before parents (iterative: no recursion limit),
    without the nodes in ``skip`` and below them."""
    seen: set[sp.Basic] = set()
    done = skip if skip is not None else {}
    out: list[sp.Basic] = []
    for root in roots:
        if root in seen or root in done:
            continue
        stack: list[tuple[sp.Basic, bool]] = [(root, False)]
        while stack:
            e, expanded = stack.pop()
            if expanded:
                out.append(e)
                continue
            if e in seen:
                continue
            seen.add(e)
            stack.append((e, True))
            stack.extend((a, False) for a in e.args if a not in seen and a not in done)
    return out


def _own_ops(e: sp.Basic) -> tuple[OpCounts, tuple[sp.Basic, ...]]:
    """The operations of node ``e`` itself and the arguments that carry further operations."""
    if e.is_Atom:
        return OpCounts(), ()
    args = e.args
    if e.is_Add:
        return OpCounts(add=len(args) - 1), args
    if e.is_Mul:
        coeff, rest = e.as_coeff_mul()
        k = len(rest) - 1 + (0 if coeff in (1, -1) else 1)  # a negation folds into an add/sub
        return OpCounts(mul=max(k, 0)), rest
    if e.is_Pow:
        exp = e.exp
        if exp.is_Integer and abs(int(exp)) <= 4:
            return OpCounts(mul=abs(int(exp)) - 1 + (1 if exp < 0 else 0)), (e.base,)
        return OpCounts(other=1), (e.base,)
    if isinstance(e, (sp.sin, sp.cos)):
        return OpCounts(trig=1), args
    return OpCounts(other=1), args


def count_ops(expr: sp.Expr) -> OpCounts:
    """Count the operations of one expression as a C compiler would emit it (no sharing: a
    subexpression used twice counts twice). Memoised over the distinct subexpressions, so a
    deeply shared expression is counted in time linear in its distinct nodes."""
    memo: dict[sp.Basic, OpCounts] = {}
    for e in _postorder([expr]):
        own, args = _own_ops(e)
        for a in args:
            own = own + memo.get(a, OpCounts())
        memo[e] = own
    return memo[expr]


_PRECISE = "floatify: 30-digit values"  # the key of the numeric values kept in a shared memo


def floatify(expr: sp.Expr, memo: dict[sp.Basic, sp.Expr] | None = None) -> sp.Expr:
    """Replace irrational numeric subexpressions (sqrt(2)/2, cos(1/3)...) by 17-digit Floats.

    Rationals are kept: the printers write them as correctly rounded doubles. Each distinct
    subexpression is rebuilt once (``memo`` may be shared between calls), bottom-up without
    recursion, so shared subtrees stay shared. A numeric subexpression is evaluated to 30 digits
    from the 30-digit values of its arguments (each distinct one evaluated once), not by
    ``sympy.N`` of the whole, which evaluates shared subtrees again at every use.
    """
    memo = {} if memo is None else memo
    if expr in memo:
        return memo[expr]
    precise: dict[sp.Basic, sp.Float] = memo.setdefault(_PRECISE, {})  # type: ignore[call-overload]
    numeric: dict[sp.Basic, bool] = {}  # sympy's is_number recurses: computed bottom-up instead
    for e in _postorder([expr]):
        if e.is_Atom or not e.args:
            numeric[e] = bool(e.is_number)
        else:
            numeric[e] = all(numeric.get(a, False) for a in e.args) and not isinstance(e, AppliedUndef)
        if e in memo:
            continue
        if numeric[e]:
            if e.is_Rational:
                memo[e] = e
                continue
            if any(a in precise for a in e.args):
                precise[e] = sp.N(e.func(*(precise.get(a, a) for a in e.args)), 30)
            else:  # a leaf of the numeric subtree: pi, sqrt(2), cos(1/3)
                precise[e] = sp.N(e, 30)
            memo[e] = sp.Float(float(precise[e]), 17)
        elif e.is_Atom or not e.args:
            memo[e] = e
        else:
            args = tuple(memo[a] for a in e.args)
            same = all(a is b for a, b in zip(args, e.args))  # == would recurse on deep arguments
            memo[e] = e if same else e.func(*args, evaluate=False)
    return memo[expr]


def tree_size(exprs: list[sp.Expr], memo: dict[sp.Basic, int] | None = None) -> int:
    """The number of nodes of ``exprs`` written out as trees (what a printer emits without
    sharing), computed over the distinct subexpressions; ``memo`` (node -> size) may be shared
    between calls, so sizing a derivation stage by stage visits each distinct node once."""
    memo = {} if memo is None else memo
    for e in _postorder(list(exprs), skip=memo):
        memo[e] = 1 + sum(memo[a] for a in e.args)
    return sum(memo[e] for e in exprs)


def depth(expr: sp.Expr) -> int:
    """The nesting depth of ``expr`` (an atom has depth 0), without recursion."""
    memo: dict[sp.Basic, int] = {}
    for e in _postorder([expr]):
        memo[e] = 1 + max((memo[a] for a in e.args), default=-1)
    return memo[expr]


@dataclass(frozen=True, eq=False)
class CSEResult:
    """Straight-line code: ``intermediates`` (symbol, expr) in order, then the named outputs.

    ``outputs[name]`` is ``(shape, exprs)`` with the expressions flattened in row-major order.
    Outputs named in ``scratch`` are local arrays, not results (a Jacobian a Hessian loop reads);
    ``hessians`` are Hessian outputs written by loops after the straight-line part
    (:class:`symkin.symbolic.program.HessianLoop`). ``strategy`` says how the code was derived:
    ``"expanded"`` (one expression per output, then CSE) or ``"program"`` (a straight-line
    program of named link frames, :mod:`symkin.symbolic.program`).
    """

    intermediates: tuple[tuple[sp.Symbol, sp.Expr], ...]
    outputs: dict[str, tuple[tuple[int, ...], tuple[sp.Expr, ...]]]
    counts: OpCounts
    inputs: tuple[sp.Symbol, ...]
    scratch: tuple[str, ...] = ()
    hessians: tuple[HessianLoop, ...] = ()
    strategy: str = "expanded"


def _flat(
    outputs: Mapping[str, sp.Matrix | tuple[sp.Matrix, ...]], memo: dict[sp.Basic, sp.Expr]
) -> dict[str, tuple[tuple[int, ...], tuple[sp.Expr, ...]]]:
    """Each output (a matrix, or a tuple of equal-shape matrices for a 3-D array) as its shape and
    its entries (:func:`floatify`, sharing ``memo``) in row-major order."""
    flat = {}
    for name, value in outputs.items():
        mats = value if isinstance(value, tuple) else (value,)
        shape = (len(mats), *mats[0].shape) if isinstance(value, tuple) else mats[0].shape
        flat[name] = (tuple(shape), tuple(floatify(x, memo) for m in mats for x in m))
    return flat


def _total(exprs: Iterable[sp.Expr]) -> OpCounts:
    return sum((count_ops(e) for e in exprs), OpCounts())


def cse_outputs(
    outputs: Mapping[str, sp.Matrix | tuple[sp.Matrix, ...]],
    inputs: tuple[sp.Symbol, ...],
    prefix: str = "x",
) -> CSEResult:
    """One CSE over all ``outputs`` (a matrix, or a tuple of equal-shape matrices for a 3-D array)."""
    flat = _flat(outputs, {})
    entries = [e for _, exprs in flat.values() for e in exprs]
    repl, reduced = sp.cse(entries, symbols=sp.numbered_symbols(prefix), order="none", optimizations=None)
    rest = iter(reduced)
    out = {name: (shape, tuple(itertools.islice(rest, len(exprs)))) for name, (shape, exprs) in flat.items()}
    return CSEResult(tuple(repl), out, _total([e for _, e in repl] + reduced), tuple(inputs))


@dataclass(frozen=True)
class HessianLoop:
    """A Hessian (n, 6, n) written by loops from the Jacobian columns of the slots on one frame's path.

    With ``Jv_a, Jw_a`` the column of slot a (``Jw = 0`` for a prismatic slot), ``order`` the joint
    of each slot along the path (base first), ``columns`` the column of each slot in the array
    ``jacobian`` (default ``order``: the Jacobian (6, n) itself) and ``multipliers`` the slots'
    ``m`` of ``theta = m q_joint + c`` (default 1; then each joint's column is its one slot's):

    - base frame (``frame="base"``, eq 20 of Haviland and Corke, Maximising Manipulability During
      Resolved-Rate Motion Control, 2020): for b at or before a,
      ``dJ_a/dq_b = (Jw_b x Jv_a ; Jw_b x Jw_a)``; for b after a, ``(Jw_a x Jv_b ; 0)``;
    - end-effector frame (``frame="ee"``): for b after a,
      ``dJe_a/dq_b = (Jw_a x Jv_b - Jw_b x Jv_a ; Jw_a x Jw_b)``, and 0 for b at or before a
      (a joint does not move the end-effector-frame axes of the joints after it).

    Each block adds ``m_a m_b`` times into ``H[joint_b][:, joint_a]`` (the chain rule). ``out``
    names the Hessian output and ``jacobian`` the array of columns it reads.
    """

    out: str
    jacobian: str
    frame: str
    order: tuple[int, ...]
    columns: tuple[int, ...] | None = None
    multipliers: tuple[float, ...] | None = None

    @property
    def counts(self) -> OpCounts:
        """Operations the loops execute (a cross product: 6 mul, 3 add)."""
        n = len(self.order)
        pairs, strict = n * (n + 1) // 2, n * (n - 1) // 2
        if self.frame == "base":  # b after a reuses the block of (a, b)
            return OpCounts(mul=12 * pairs, add=6 * pairs)
        return OpCounts(mul=18 * strict, add=12 * strict)
