"""Partial derivatives of any order of a frame's pose, numerically (NumPy): the reference.

The order-k derivative of a frame (roboticstoolbox-python's ``partial_fkine0(q, k)`` layout) is

    D[i_{k-1}, ..., i_1, :, i_0] = d^{k-1} J_{i_0} / dq_{i_1} ... dq_{i_{k-1}},

shape ``(n,) * (k - 1) + (6, n)``, rows (v, omega) of the base-frame Jacobian J0 (batched: a
leading (N,) axis). Order 1 is J0 itself, order 2 the Hessian ``H[i_1, :, i_0]`` (Haviland and
Corke, Manipulator Differential Kinematics, Part 2: Acceleration and Advanced Applications, 2023,
section "Higher-Order Derivatives"; Maximising Manipulability During Resolved-Rate Motion
Control, 2020, eq 20).

:func:`path_derivative` is Part 2's recursion: the product rule on the previous orders, each
column of the Hessian a cross product ``H_{i_0 i_1} = (w_{i_1} x Jv_{i_0} ; w_{i_1} x w_{i_0})``,
so every higher derivative of it a sum over the ways of sharing the further indices between the
two factors (Leibniz's rule, ``2^{k-2}`` products of lower orders). That product holds where
joint ``i_1`` comes at or before joint ``i_0`` along the path; elsewhere the translational part
is the entry with ``i_0`` and ``i_1`` swapped (it is ``d^k p``, symmetric in all k indices) and
the angular part 0 (an axis does not move with the joints after it). roboticstoolbox-python 1.5
applies the product to every pair, so its ``partial_fkine0(q, k)``, k >= 3, agrees with these
derivatives only on the entries :func:`rtb_valid` marks.

The generated code takes another route (one nested cross product per sorted multiset of joints,
:mod:`symkin.symbolic.derivatives`); finite differences of J0 are the third.
"""

from __future__ import annotations

import itertools
import operator
from collections.abc import Sequence
from typing import Any

import numpy as np

from symkin.errors import ParameterError
from symkin.model.kinematics import cross

__all__ = [
    "MAX_ORDER",
    "MAX_ENTRIES",
    "check_order",
    "derivative_shape",
    "derivative_kind",
    "derivative_doc",
    "path_derivative",
    "chain_derivative",
    "to_rtb_layout",
    "rtb_valid",
]

MAX_ORDER = 8
MAX_ENTRIES = 4_000_000  # entries 6 n^k of one configuration's tensor (32 MB of float64)


def derivative_kind(order: int) -> str:
    """The kind of the order-``order`` derivative functions: ``derivative3``, ``derivative4``..."""
    return f"derivative{order}"


def derivative_doc(order: int, n: int | str = "n", frame: str = "the end effector") -> str:
    """What the order-``order`` derivative of ``frame`` is, for docstrings (``n`` joints)."""
    shape = ", ".join([str(n)] * (order - 1) + ["6", str(n)])
    diffs = [f"i{j}" for j in range(order - 1, 0, -1)]
    if order > 3:
        diffs = [diffs[0], "...", diffs[-1]]
    by = " ".join("..." if i == "..." else f"dq_{i}" for i in diffs[::-1])
    return (
        f"Order-{order} partial derivative of the pose of {frame}, ({shape}): D[{', '.join(diffs)}, :, i0] "
        f"= d^{order - 1} J0[:, i0] / {by}, rows (v, omega) (Haviland and Corke, Manipulator Differential "
        "Kinematics, Part 2, 2023; roboticstoolbox-python's partial_fkine0 layout)."
    )


def derivative_shape(order: int, n: int) -> tuple[int, ...]:
    """The shape of one configuration's order-``order`` derivative: ``(n,) * (order - 1) + (6, n)``."""
    return (n,) * (order - 1) + (6, n)


def check_order(order: Any, n: int, name: str = "robot") -> int:
    """``order`` as an int in 1..:data:`MAX_ORDER` whose tensor of ``6 n^order`` entries stays
    within :data:`MAX_ENTRIES`; ParameterError naming the order otherwise."""
    if isinstance(order, (bool, np.bool_)):
        raise ParameterError(f"order must be an integer >= 1, not {order!r}")
    try:
        k = operator.index(order)
    except TypeError:
        raise ParameterError(f"order must be an integer >= 1, not {type(order).__name__} {order!r}") from None
    if not 1 <= k <= MAX_ORDER:
        raise ParameterError(f"order must be 1..{MAX_ORDER} (1: jacob0, 2: hessian0), not {k}")
    if 6 * n**k > MAX_ENTRIES:
        raise ParameterError(
            f"the order-{k} derivative of {name} ({n} joints) has 6 * {n}^{k} = {6 * n**k:,} entries per "
            f"configuration, more than {MAX_ENTRIES:,}: ask for a lower order"
        )
    return k


def _place(T: np.ndarray, positions: Sequence[int], k: int) -> np.ndarray:
    """``T`` (N, s, ..., s, c) with one index axis per entry of ``positions`` (grid positions
    0..k-1) as an array broadcastable over the grid (N, s or 1 per position, c)."""
    order = np.argsort(positions)
    T = T.transpose(0, *(1 + order), T.ndim - 1)
    s = T.shape[1] if T.ndim > 2 else 1
    shape = [T.shape[0]] + [s if p in positions else 1 for p in range(k)] + [T.shape[-1]]
    return T.reshape(shape)


def _next_order(lower: list[np.ndarray], k: int) -> np.ndarray:
    """The slot tensor of order k (N, s^k, 6), indices (i_0, i_1, ..., i_{k-1}), from those of
    orders 1..k-1 (``lower[m - 1]``, same layout): Leibniz's rule on the cross product of the
    Hessian for i_1 at or before i_0, then the symmetry of the translational part and the zero
    angular part for i_1 after i_0 (module docstring)."""
    outer = list(range(2, k))
    total: np.ndarray | None = None
    for r in range(len(outer) + 1):
        for first in itertools.combinations(outer, r):
            rest = [p for p in outer if p not in first]
            w = _place(lower[r][..., 3:], (1, *first), k)  # d^r w_{i_1} / dq_first
            x = _place(lower[k - 2 - r], (0, *rest), k)  # d^(k-2-r) J_{i_0} / dq_rest
            term = np.concatenate((cross(w, x[..., :3]), cross(w, x[..., 3:])), axis=-1)
            total = term if total is None else total + term
    assert total is not None
    s = total.shape[1]
    at_or_before = (np.arange(s)[None, :] <= np.arange(s)[:, None]).reshape((1, s, s) + (1,) * (k - 1))
    v = np.where(at_or_before, total[..., :3], np.swapaxes(total[..., :3], 1, 2))
    w = np.where(at_or_before, total[..., 3:], 0.0)
    return np.concatenate((v, w), axis=-1)


def to_rtb_layout(T: np.ndarray) -> np.ndarray:
    """(N, i_0, i_1, ..., i_{k-1}, 6) -> (N, i_{k-1}, ..., i_1, 6, i_0)."""
    k = T.ndim - 2
    return T.transpose(0, *range(k, 1, -1), k + 1, 1)


def path_derivative(Jv: np.ndarray, Jw: np.ndarray, A: np.ndarray, order: int) -> np.ndarray:
    """The order-``order`` derivative (N, n, ..., 6, n) of a frame from the geometric columns Jv,
    Jw (N, s, 3) of the s joint slots on its path (base first; Jw = 0 for a prismatic slot),
    contracted onto the joints by ``A`` (s, n): slot i moves joint j by ``A[i, j]``."""
    tensors = [np.concatenate((Jv, Jw), axis=-1)]  # order 1: (N, i_0, 6)
    for k in range(2, order + 1):
        tensors.append(_next_order(tensors, k))
    T = tensors[-1]
    letters = "abcdefghij"[:order]
    spec = "N" + letters + "r," + ",".join(f"{c}{c.upper()}" for c in letters)
    T = np.einsum(spec + "->N" + letters.upper() + "r", T, *([A] * order), optimize=True)
    return to_rtb_layout(T)


def chain_derivative(J: np.ndarray, order_of: Sequence[int], order: int) -> np.ndarray:
    """The order-``order`` derivative (N, n, ..., 6, n) of a frame of a serial chain from its J0
    (N, 6, n): ``order_of[k]`` is the joint met k-th from the base (columns of joints after the
    frame are 0)."""
    o = list(order_of)
    A = np.zeros((len(o), J.shape[-1]))
    A[range(len(o)), o] = 1.0
    return path_derivative(np.swapaxes(J[:, :3, o], 1, 2), np.swapaxes(J[:, 3:, o], 1, 2), A, order)


def rtb_valid(order: int, n: int, path: Sequence[int] | None = None) -> np.ndarray:
    """Where roboticstoolbox-python 1.5's ``partial_fkine0(q, order)`` is the derivative: a boolean
    mask of shape ``(n,) * (order - 1) + (6, n)``.

    Its recursion forms column ``(i_0, i_1, ..., i_{m-1})`` of order m from the Hessian's cross
    product ``w_{i_1} x J_{i_0}`` and from columns of lower orders, as if the product held for
    every pair: a column is right when ``i_1`` comes at or before ``i_0`` along the path
    (``path``: the joints base first; default 0..n-1) and the lower-order columns it reads are
    right, ``(i_1, i_2..)`` (angular rows) and ``(i_0, ...)`` of the indices after i_1 it shares
    out (module docstring)."""
    rank = {j: r for r, j in enumerate(range(n) if path is None else path)}
    memo: dict[tuple[int, ...], bool] = {}

    def valid(idx: tuple[int, ...]) -> bool:  # (i_0, i_1, ..., i_{m-1})
        if len(idx) <= 2:
            return True
        if idx in memo:
            return memo[idx]
        a, b, outer = idx[0], idx[1], idx[2:]
        ok = rank.get(b, n) <= rank.get(a, -1)
        for r in range(len(outer) + 1):
            for first in itertools.combinations(range(len(outer)), r):
                rest = [outer[p] for p in range(len(outer)) if p not in first]
                ok = ok and valid((b, *(outer[p] for p in first))) and valid((a, *rest))
        memo[idx] = ok
        return ok

    mask = np.zeros(derivative_shape(order, n), dtype=bool)
    for idx in itertools.product(range(n), repeat=order):
        mask[idx[:0:-1] + (slice(None), idx[0])] = valid(idx)
    return mask
