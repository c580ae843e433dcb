"""Pickles written by symkin 0.1.0 before the one-pipeline layout (commit 7c10cf0: compiled chains
on every backend, compiled trees, a Robot and a Tree; made once with that version's code and kept
in tests/data) load with today's code into working objects: the same kinematics as the numeric
reference, rebuilt from the compile cache."""

from __future__ import annotations

import pickle
from pathlib import Path

import numpy as np
import pytest

import symkin
from symkin import Robot, Tree

DATA = Path(__file__).resolve().parents[1] / "data" / "pickles_0.1.0_7c10cf0.pkl"
PICKLES = pickle.loads(DATA.read_bytes())  # a dict of the old pickles' bytes, by what they hold


def test_old_robot_and_tree_pickles_load():
    robot, tree = pickle.loads(PICKLES["robot"]), pickle.loads(PICKLES["tree"])
    assert isinstance(robot, Robot) and robot.fingerprint == symkin.load("planar3").fingerprint
    assert isinstance(tree, Tree) and tree.frames == ("r_foot", "l_foot")
    q = tree.random_q(3, seed=1)
    assert tree.fkine_all(q).shape == (3, 2, 4, 4)


@pytest.mark.parametrize("backend", ["numpy", "c", "casadi"])
def test_old_compiled_chain_pickles_load(backend):
    kin = pickle.loads(PICKLES[f"chain_{backend}"])
    assert isinstance(kin, symkin.Kinematics) and kin.backend == backend
    ref = symkin.load("planar3")
    q = ref.random_q(5, seed=2)
    np.testing.assert_allclose(kin.fkine(q), ref.fkine(q), atol=1e-12)
    np.testing.assert_allclose(kin.jacob0(q), ref.jacob0(q), atol=1e-12)


@pytest.mark.parametrize("backend", ["numpy", "c"])
def test_old_compiled_tree_pickles_load(backend):
    kin = pickle.loads(PICKLES[f"tree_{backend}"])
    assert isinstance(kin, symkin.Kinematics) and kin.backend == backend
    tree = kin.tree
    q = tree.random_q(5, seed=3)
    np.testing.assert_allclose(kin.fkine_all(q), tree.fkine_all(q), atol=1e-12)
    np.testing.assert_allclose(kin.jacob0(q, frame="l_foot"), tree.jacob0(q, "l_foot"), atol=1e-12)
