"""The partial derivatives of order k of a chain's pose, written step by step (``symkin derive ROBOT
--order k``): Markdown with LaTeX math, or LaTeX.

What Haviland and Corke's Part 2 (Manipulator Differential Kinematics, Part 2: Acceleration and
Advanced Applications, 2023, section "Higher-Order Derivatives") does for the third derivative and
leaves to the reader beyond: the product rule on the partitioned Hessian, order after order. The
text shows the tensor's layout, the rule, its closed form (one nested cross product of joint axes
per sorted multiset of joints, :mod:`symkin.symbolic.derivatives`), the Jacobian columns it starts
from (those of :func:`symkin.derive.chain.derive_steps`), the distinct columns of every order up
to k with their expressions while they stay short, the order-k tensor block by block for small
arms, and the checks: each order against the partial derivative of the previous one (symbolic, or
at random points to 30 digits when too large), and the whole tensor against the numeric reference
(:meth:`symkin.Robot.derivative`, Part 2's recursion) at random configurations.
"""

from __future__ import annotations

import itertools
import math
import random
from collections.abc import Sequence
from typing import Any

import mpmath
import numpy as np
import sympy as sp

from symkin.derive.chain import _check, _worst, derive_steps
from symkin.derive.common import (
    CHECK_TEXT,
    FORMATS,
    Printer,
    constants,
    latex_document,
    mp_function,
    ops_of,
    shared_context,
)
from symkin.emit.templates import render
from symkin.errors import SymkinError, check_choice
from symkin.model.derivatives import check_order
from symkin.model.robot import Robot

__all__ = ["higher_order_derivation", "LIST_MAX", "BLOCKS_MAX", "CHECK_BLOCKS_MAX", "EXPANDED_MAX_JOINTS"]

LIST_MAX = 40  # the distinct columns of an order are listed up to this many
BLOCKS_MAX = 9  # the order-k tensor is printed block by block up to this many 6 x n blocks
CHECK_BLOCKS_MAX = (
    64  # each order is checked against the derivative of the previous one up to this many blocks
)
SYMBOLIC_MAX_OPS = 120  # that check is symbolic when the Jacobian has at most this many operations
EXPANDED_MAX_JOINTS = 6  # longer chains are derived in the program form (named intermediates)

Vec = list[sp.Expr]


def _cross(a: Sequence[sp.Expr], b: Sequence[sp.Expr]) -> Vec:
    return [a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]]


class _Nested:
    """V(s) and W(s) of sorted multisets s of chain positions (module docstring of
    :mod:`symkin.symbolic.derivatives`) from the Jacobian columns, memoised."""

    def __init__(self, v: Sequence[Vec], w: Sequence[Vec], expand: bool) -> None:
        self.v, self.w, self.expand = v, w, expand
        self.memo: dict[tuple[int, ...], tuple[Vec, Vec]] = {}

    def __call__(self, s: tuple[int, ...]) -> tuple[Vec, Vec]:
        got = self.memo.get(s)
        if got is None:
            if len(s) == 1:
                got = (list(self.v[s[0]]), list(self.w[s[0]]))
            else:
                v, w = self(s[1:])
                wb = self.w[s[0]]
                tidy = sp.expand if self.expand else (lambda x: x)
                got = ([tidy(x) for x in _cross(wb, v)], [tidy(x) for x in _cross(wb, w)])
            self.memo[s] = got
        return got

    def column(self, i0: int, diffs: Sequence[int]) -> sp.Matrix:
        """The 6-vector D[..., :, i0] of derivative positions ``diffs``."""
        s = tuple(sorted((i0, *diffs)))
        v, w = self(s)
        return sp.Matrix([*v, *(w if i0 == s[-1] else [0, 0, 0])])


def _block(nested: _Nested, diffs: Sequence[int], n: int) -> sp.Matrix:
    """The 6 x n block D[i_{k-1}, ..., i_1] (``diffs`` = (i_1, ..., i_{k-1}), chain positions)."""
    return sp.Matrix.hstack(*[nested.column(i0, diffs) for i0 in range(n)])


def _sub(idx: Sequence[int]) -> str:
    sep = "" if max(idx) < 9 else ","
    return sep.join(str(i + 1) for i in idx)


def higher_order_derivation(
    robot: Robot | str, order: int, fmt: str = "markdown", symbolic_constants: bool = False
) -> str:
    """The derivation of the order-``order`` partial derivative of ``robot``'s pose (module
    docstring); ``order`` 2..8 (2: the Hessian, by the same rule)."""
    check_choice(fmt, FORMATS, "format")
    from symkin.model.resolve import robot_with_joints

    robot = robot_with_joints(robot, "nothing to derive")
    k = check_order(order, robot.n, robot.name)
    if k < 2:
        raise SymkinError("--order 1 is the Jacobian: its derivation is `symkin derive ROBOT` itself")
    form = "program" if robot.n > EXPANDED_MAX_JOINTS else "auto"
    D = derive_steps(robot, symbolic_constants=symbolic_constants, sections=("ets",), form=form)
    ets, n = robot.ets, robot.n
    path = [e.joint for e in ets if e.joint is not None]  # joint index at each chain position
    pos = {j: p for p, j in enumerate(path)}
    J = D.J0
    v = [list(J[:3, j]) for j in path]
    w = [list(J[3:, j]) for j in path]
    expanded = D.form == "expanded"
    nested = _Nested(v, w, expand=expanded)
    P = Printer(D.q, D.intermediates)
    C = constants(ets, bool(D.constants))
    ctx: dict[str, Any] = {**shared_context(D, P, C), "order": k, "expanded": expanded, "list_max": LIST_MAX}
    ctx["columns"] = [
        rf"J_{{v_{{{j + 1}}}}} = {P.matrix(sp.Matrix(v[pos[j]]))}, \quad "
        rf"\omega_{{{j + 1}}} = J_{{\omega_{{{j + 1}}}}} = {P.matrix(sp.Matrix(w[pos[j]]))}"
        for j in range(n)
    ]
    orders = []
    for m in range(2, k + 1):
        sets = list(itertools.combinations_with_replacement(range(n), m))
        listed = []
        if len(sets) <= LIST_MAX:
            for s in sets:
                vs, ws = nested(s)
                q = [path[p] for p in s]
                rest = _sub(q[1:])
                listed.append(
                    rf"\mathbf{{V}}_{{{_sub(q)}}} = \omega_{{{q[0] + 1}}} \times \mathbf{{V}}_{{{rest}}} = "
                    rf"{P.matrix(sp.Matrix(vs))}, \quad \mathbf{{W}}_{{{_sub(q)}}} = "
                    rf"\omega_{{{q[0] + 1}}} \times \mathbf{{W}}_{{{rest}}} = {P.matrix(sp.Matrix(ws))}"
                )
        else:
            for s in sets:
                nested(s)
        orders.append(
            {
                "m": m,
                "distinct": len(sets),
                "entries": 6 * n**m,
                "listed": listed,
                "count": math.comb(n + m - 1, m),
            }
        )
    ctx["orders"] = orders
    ctx["blocks"] = []
    if n ** (k - 1) <= BLOCKS_MAX:
        for diffs_rev in itertools.product(range(n), repeat=k - 1):  # joint indices i_{k-1}, ..., i_1
            diffs = [pos[j] for j in diffs_rev[::-1]]
            B = _block(nested, diffs, n)
            B = B[:, [pos[j] for j in range(n)]]  # columns by joint index
            name = ", ".join(str(j + 1) for j in diffs_rev)
            ctx["blocks"].append(rf"D^{{({k})}}_{{{name}}} = {P.matrix(B)}")
    ctx["derivative_check"] = _derivative_check(nested, D, k, n, path)
    ctx["reference_check"] = _reference_check(nested, D, robot, k, path)
    ctx["legend"] = P.legend()
    text = render("derive/higher_order.md.j2", **ctx, sections={"ets"})
    return latex_document(text) if fmt == "latex" else text


def _derivative_check(nested: _Nested, D: Any, k: int, n: int, path: Sequence[int]) -> str:
    """Each order m = 2..k against the partial derivative of order m - 1 (expanded form, up to
    :data:`CHECK_BLOCKS_MAX` blocks of order k)."""
    if D.form != "expanded":
        return "not done in the program form (the columns are named intermediates)"
    if n ** (k - 1) > CHECK_BLOCKS_MAX:
        return f"not done: {n ** (k - 1)} blocks of order {k} (more than {CHECK_BLOCKS_MAX})"
    symbols = list(D.q) + list(D.constants)
    symbolic = sum(ops_of(x) for x in D.J0) <= SYMBOLIC_MAX_OPS
    results, differences = [], []
    for m in range(2, k + 1):
        for diffs in itertools.product(range(n), repeat=m - 1):  # chain positions i_1, ..., i_{m-1}
            lower = (
                _block(nested, diffs[:-1], n)
                if m > 2
                else sp.Matrix.hstack(*[sp.Matrix([*nested.v[i], *nested.w[i]]) for i in range(n)])
            )
            block, derivative = _block(nested, diffs, n), lower.diff(D.q[path[diffs[-1]]])
            if symbolic:
                results.append(_check(block, derivative, symbols))
            else:
                differences += list(block - derivative)
    if differences:  # at 3 random points to 30 digits, all at once
        f = mp_function((), symbols, differences)
        rng = random.Random(1)
        with mpmath.workdps(30):
            for _ in range(3):
                values = f(*[mpmath.mpf(rng.randint(100, 2000)) / 1000 for _ in symbols])
                results.append("failed" if max(abs(x) for x in values) > mpmath.mpf(10) ** -20 else "numeric")
    worst = _worst(results)
    if worst == "failed":
        raise SymkinError(f"derivation of {D.robot.name!r}: an order is not the derivative of the one below")
    return (
        f"every block of orders 2..{k} is the partial derivative of a block of the order below: "
        f"{CHECK_TEXT[worst]}"
    )


def _reference_check(nested: _Nested, D: Any, robot: Robot, k: int, path: Sequence[int]) -> str:
    """The order-k tensor evaluated at 3 random configurations (30 digits) against the numeric
    reference :meth:`symkin.Robot.derivative`."""
    n = robot.n
    sets = sorted(s for s in nested.memo if len(s) == k)
    exprs = [D.numeric(x) for s in sets for x in (*nested(s)[0], *nested(s)[1])]
    f = mp_function([(s, D.numeric(e)) for s, e in D.intermediates], D.q, exprs)
    Q = robot.random_q(3, seed=1)
    worst = 0.0
    for q in Q:
        with mpmath.workdps(30):
            values = [float(x) for x in f(*[mpmath.mpf(float(x)) for x in q])]
        table = {s: values[6 * i : 6 * i + 6] for i, s in enumerate(sets)}
        T = np.zeros((n,) * (k - 1) + (6, n))
        for idx in itertools.product(range(n), repeat=k):  # chain positions (i_0, i_1, ..., i_{k-1})
            s = tuple(sorted(idx))
            col = table[s][:3] + (table[s][3:] if idx[0] == s[-1] else [0.0] * 3)
            joints = [path[p] for p in idx]
            T[tuple(joints[:0:-1]) + (slice(None), joints[0])] = col
        worst = max(worst, float(np.abs(T - robot.derivative(q, k)).max()))
    return (
        f"the tensor at 3 random configurations against symkin's numeric reference (Part 2's recursion, "
        f"`Robot.derivative`): largest difference {worst:.1e}"
    )
