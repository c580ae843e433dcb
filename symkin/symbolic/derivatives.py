"""Partial derivatives of any order of a frame's pose, as straight-line code over the Jacobian columns.

The k-th order derivative tensor of a frame (roboticstoolbox-python's ``partial_fkine0(q, k)``
layout) is ``D[i_{k-1}, ..., i_1, :, i_0] = d^{k-1} J_{i_0} / dq_{i_1} ... dq_{i_{k-1}}``: shape
``(n,) * (k - 1) + (6, n)``, rows (v, omega) of the base-frame Jacobian J0; k = 1 is J0 itself and
k = 2 the Hessian ``H[i_1, :, i_0] = dJ_{i_0}/dq_{i_1}`` (Haviland and Corke, Manipulator
Differential Kinematics, Part 2, 2023, section "Higher-Order Derivatives"; Maximising
Manipulability During Resolved-Rate Motion Control, 2020, eq 20).

Part 2 obtains each order by the product rule on the previous one, every column a cross product of
columns of lower orders. Taken along one path (a chain, or a tree frame's path), with slots
``s_1 <= s_2 <= ...`` in path order, ``w_s`` the slot's signed axis (0 for a prismatic slot) and
``v_s`` its translational column, the rule closes into one nested cross product per sorted multiset
of slots:

- a vector that turns with the link after slot ``s`` (an axis ``w_s``, a column ``v_s``, and every
  cross product of such vectors, by the Jacobi identity) has ``d x / dq_b = w_b x x`` for every
  slot b at or before s;
- so the translational part, ``d^k p / dq_{s_1} ... dq_{s_k}`` (symmetric in all k indices), is
  ``V(s_1..s_k) = w_{s_1} x (w_{s_2} x ( ... x (w_{s_{k-1}} x v_{s_k})))``;
- and the angular part of column ``i_0`` is ``W(s_1..s_k) = w_{s_1} x ( ... x (w_{s_{k-1}} x
  w_{s_k}))`` when ``i_0`` is the last slot of the multiset (``s_k``), else 0 (the axis of a joint
  does not move with the joints after it). At k = 2 this is eq 20 of the MMC paper.

Every cross product is one value of the straight-line :class:`~symkin.symbolic.program.Program` the
frame's Jacobian came from, shared by every entry of every order that contains it: an order-k
tensor of an n-slot path costs ``C(n + k - 1, k)`` pairs of cross products, however many of its
``6 n^k`` entries repeat them. Mimic slots (``theta = m q_j + c``) are derived on the slot columns
and contracted onto the joints by the chain rule, each entry a sum over the slots of its joints
weighted by the product of their multipliers.

roboticstoolbox-python 1.5's ``partial_fkine0`` writes ``H[i_1, :, i_0] = w_{i_1} x J_{i_0}`` for
every pair of joints before it differentiates, which holds only where ``i_1 <= i_0``: its tensors
of order 3 and more agree with these (and with finite differences) on the entries whose indices
``i_{k-1} ... i_1, i_0`` are those of a product it expands correctly, and differ elsewhere (see
:func:`symkin.model.derivatives.rtb_valid`).
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import replace
from fractions import Fraction

import sympy as sp

from symkin.symbolic.cse import Tensor
from symkin.symbolic.program import Program, TreeProgram, _cross

__all__ = ["derivative_entries", "frame_columns", "extend_program", "MAX_ORDER"]

MAX_ORDER = 8  # orders above this are refused before any work (the tensor has 6 n^k entries)

Column = tuple[list[sp.Expr], list[sp.Expr]]  # (v, w): translational and angular part


def frame_columns(tp: TreeProgram, f: int) -> list[Column]:
    """The Jacobian columns (v, w) of the slots on frame ``f``'s path, base first: J0's own columns
    for a plain frame, the slot columns (before the multipliers) otherwise."""
    C = tp.C0[f]
    if C is None:
        J = tp.J0[f]
        return [(list(J[:3, j]), list(J[3:, j])) for j, _ in tp.paths[f]]
    return [(list(C[:3, s]), list(C[3:, s])) for s in range(C.shape[1])]


def extend_program(tp: TreeProgram) -> Program:
    """A program that continues ``tp``'s lines (same names, same value numbering)."""
    P = Program()
    for name, expr in tp.lines:
        P.lines.append((name, expr))
        P._names[expr] = name  # noqa: SLF001 - the program's own value table, rebuilt
    return P


def _nested(
    P: Program, cols: Sequence[Column], memo: dict[tuple[int, ...], Column], s: tuple[int, ...]
) -> Column:
    """(V(s), W(s)) of the sorted slot multiset ``s`` (module docstring), memoised by suffix."""
    got = memo.get(s)
    if got is not None:
        return got
    if len(s) == 1:
        got = cols[s[0]]
    else:
        v, w = _nested(P, cols, memo, s[1:])
        wb = cols[s[0]][1]
        got = (_cross(P, wb, v), _cross(P, wb, w))
    memo[s] = got
    return got


def derivative_entries(
    P: Program, cols: Sequence[Column], paths: Sequence[tuple[int, Fraction]], n: int, order: int
) -> Tensor:
    """The order-``order`` derivative tensor of one frame, shape ``(n,) * (order - 1) + (6, n)``,
    each entry a value of ``P``.

    ``cols`` are the columns of the slots on the path (base first), ``paths`` the joint and
    multiplier of each slot; entries of joints off the path are 0."""
    if order < 1:
        raise ValueError(f"derivative order {order} < 1")
    memo: dict[tuple[int, ...], Column] = {}
    zero = [sp.Integer(0)] * 3
    by_joint: dict[int, list[tuple[int, Fraction]]] = {}
    for s, (j, m) in enumerate(paths):
        by_joint.setdefault(j, []).append((s, m))
    plain = all(len(v) == 1 and v[0][1] == 1 for v in by_joint.values())

    def slot_entry(column: int, diffs: tuple[int, ...]) -> list[sp.Expr]:
        key = tuple(sorted((column, *diffs)))
        v, w = _nested(P, cols, memo, key)
        return [*v, *(w if column == key[-1] else zero)]

    def joint_entry(j0: int, diffs: tuple[int, ...]) -> list[sp.Expr]:
        if plain:
            return slot_entry(by_joint[j0][0][0], tuple(by_joint[j][0][0] for j in diffs))
        total = [sp.Integer(0)] * 6
        for combo in itertools.product(by_joint[j0], *(by_joint[j] for j in diffs)):
            weight = sp.Integer(1)
            for _, m in combo:
                weight *= sp.Rational(m)
            e = slot_entry(combo[0][0], tuple(s for s, _ in combo[1:]))
            total = [t + weight * x for t, x in zip(total, e)]
        return P.vec(total)

    shape = (n,) * (order - 1) + (6, n)
    on = set(by_joint)
    blocks: dict[tuple[int, ...], list[list[sp.Expr]]] = {}  # (i_{k-1}..i_1) -> 6 x n block
    for diffs_rev in itertools.product(range(n), repeat=order - 1):  # i_{k-1}, ..., i_1: row-major
        block = [[sp.Integer(0)] * n for _ in range(6)]
        if set(diffs_rev) <= on:
            diffs = diffs_rev[::-1]  # i_1, ..., i_{k-1}
            for j0 in on:
                e = joint_entry(j0, diffs)
                for r in range(6):
                    block[r][j0] = e[r]
        blocks[diffs_rev] = block
    entries = [x for key in itertools.product(range(n), repeat=order - 1) for row in blocks[key] for x in row]
    return Tensor(shape, tuple(entries))


def with_lines(tp: TreeProgram, P: Program) -> TreeProgram:
    """``tp`` with the lines of ``P`` (which continued it, :func:`extend_program`)."""
    return replace(tp, lines=tuple(P.lines))
