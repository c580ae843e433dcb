"""One bounded memo of loaded kinematics for chains, trees and closed-form solvers: compiling the
same model again returns the same object, and the memo never holds more than LOADED_MAX objects."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import ParameterError, Tree
from symkin.runtime import memo
from tests.model.tree_urdfs import QUADRUPED


def test_chains_and_trees_share_one_memo(monkeypatch):
    monkeypatch.setattr(memo, "LOADED_MAX", 2)
    memo.clear()
    chain = symkin.compile("planar2", backend="numpy")
    tree_model = Tree.from_urdf(QUADRUPED, frames=["r_foot", "l_foot"])
    tree = symkin.compile(tree_model, backend="numpy")
    assert symkin.compile("planar2", backend="numpy") is chain  # memoised (and now most recent)
    assert symkin.compile(tree_model, backend="numpy") is tree
    symkin.compile("planar3", backend="numpy")  # a third object: the least recently used goes
    assert len(memo._LOADED) == 2
    assert symkin.compile("planar2", backend="numpy") is not chain
    memo.clear()


def test_memo_is_bypassed_without_cache():
    a = symkin.compile("planar2", backend="numpy")
    b = symkin.compile("planar2", backend="numpy", cache=False)
    assert a is not b
    q = np.array([0.3, -0.2])
    np.testing.assert_array_equal(a.fkine(q), b.fkine(q))


@pytest.mark.parametrize("backend", ["reference", "numpy"])
def test_a_bad_axes_is_the_same_error_on_a_chain_and_a_tree_frame(backend):
    tree_model = Tree.from_urdf(QUADRUPED, frames=["r_foot", "l_foot"])
    chain = symkin.load("planar2")
    if backend != "reference":
        tree_model, chain = symkin.compile(tree_model, backend), symkin.compile(chain, backend)
    q_tree, q_chain = np.zeros(tree_model.n), np.zeros(2)
    for call in (
        lambda: chain.manipulability(q_chain, axes="xyz"),
        lambda: chain.jacobm(q_chain, axes="xyz"),
        lambda: tree_model.manipulability(q_tree, "r_foot", axes="xyz"),
        lambda: tree_model.jacobm(q_tree, "r_foot", axes="xyz"),
    ):
        with pytest.raises(ParameterError, match="axes must be one of"):
            call()
