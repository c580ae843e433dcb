"""The symbolic derivatives of any order (one nested cross product per sorted multiset of path
slots): at order 2 the generated hessian0 in its own layout, at orders 3 and 4 the numeric
reference; their size (distinct values and operations grow with the multisets, not with the
6 n^k entries); the functions the compiler gets."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin import Tree
from symkin.derive.common import mp_function
from symkin.model.derivatives import derivative_shape
from symkin.model.tree import as_tree
from symkin.symbolic.derivatives import derivative_entries, extend_program, frame_columns
from symkin.symbolic.functions import derivative_functions
from symkin.symbolic.kinematics import const_to_sympy, joint_symbols
from symkin.symbolic.program import derive_tree_program
from tests.conftest import assert_close
from tests.model.tree_urdfs import GRIPPER


def _tensor(model, frame: int, order: int, q: np.ndarray) -> np.ndarray:
    """The symbolic order-``order`` tensor of frame ``frame`` evaluated at ``q`` (mpmath)."""
    tree = as_tree(model)
    tp = derive_tree_program(tree, joint_symbols(tree.n), const_to_sympy, fold=True)
    P = extend_program(tp)
    D = derivative_entries(P, frame_columns(tp, frame), tp.paths[frame], tree.n, order)
    f = mp_function(P.lines, tp.q, list(D.entries))
    return np.array([float(x) for x in f(*map(float, q))]).reshape(D.shape)


@pytest.mark.parametrize("model", ["panda", "stanford", "gripper"])
def test_order_two_is_the_generated_hessian(model):
    m = Tree.from_urdf(GRIPPER) if model == "gripper" else symkin.load(model)
    kin = symkin.compile(m, "c")
    for f, frame in enumerate(as_tree(m).frames):
        q = m.random_q(seed=21)
        H = kin.hessian0(q, frame) if len(as_tree(m).frames) > 1 else kin.hessian0(q)
        assert_close(_tensor(m, f, 2, q), H, 1e-14, f"{model} {frame}")


@pytest.mark.parametrize("order", [3, 4])
def test_orders_three_and_four_are_the_reference(order):
    tree = Tree.from_urdf(GRIPPER)  # mimic slots: multipliers 2 and -1, a joint met twice on a path
    q = tree.random_q(seed=22)
    for f, frame in enumerate(tree.frames):
        assert_close(_tensor(tree, f, order, q), tree.derivative(q, order, frame), 1e-14, f"{frame} {order}")


def test_size_grows_with_the_multisets_not_the_entries():
    panda = symkin.load("panda")
    fns = {f.order: f for f in derivative_functions(panda, (3, 4))}
    for k, f in fns.items():
        shape, entries = f.code.outputs["D"]
        assert shape == derivative_shape(k, 7) and len(entries) == 6 * 7**k
        multisets = math.comb(7 + k - 1, k)
        # each distinct column at most 6 values (and their negations), plus 0
        assert len(set(entries)) <= 2 * 6 * multisets + 1
        assert f.code.gathered == ("D",)
    # one cross product (6 mul, 3 add) per new value at most: order 4 adds <= 2 * 6 * 210 crosses over order 3
    assert fns[4].code.counts.total - fns[3].code.counts.total <= 2 * 9 * math.comb(10, 4)


def test_functions_per_frame_and_order():
    tree = Tree.from_urdf(GRIPPER)
    fns = derivative_functions(tree, (3, 5))
    assert [(f.kind, f.frame, f.name) for f in fns] == [
        ("derivative3", 0, "derivative3_0"),
        ("derivative3", 1, "derivative3_1"),
        ("derivative5", 0, "derivative5_0"),
        ("derivative5", 1, "derivative5_1"),
    ]
    assert "(3, 3, 6, 3)" in fns[0].doc and "fa_tip2" in fns[0].doc
    assert "(3, 3, 3, 3, 6, 3)" in fns[2].doc
    with pytest.raises(ValueError, match="start at order 3"):
        derivative_functions(tree, (2,))
