"""``DiffKinematics.derivative``: the JAX/PyTorch derivatives of any order against the numeric
reference (Part 2's product rule on the model, :mod:`symkin.model.derivatives`), batched, on a tree's
frames, and the error for an order the module was not compiled with."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.errors import FrameError, ParameterError
from tests.diff_libs import BACKENDS, Lib
from tests.model.tree_urdfs import QUADRUPED


@pytest.mark.parametrize("backend", BACKENDS)
def test_derivatives_of_a_chain_match_the_numeric_reference(backend):
    lib = Lib(backend)
    robot = symkin.load("puma560")
    kin = symkin.compile(robot, backend=backend, derivatives=4)
    Q = robot.random_q(3, seed=2)
    for k in (1, 2, 3, 4):
        D = lib.numpy(kin.derivative(lib.array(Q), k))
        assert D.shape == (3, *(robot.n,) * (k - 1), 6, robot.n)
        ref = np.array([robot.derivative(q, k) for q in Q])
        assert np.abs(D - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max())
    with pytest.raises(ParameterError, match="derivatives=3"):
        symkin.compile(robot, backend=backend).derivative(lib.array(Q[0]), 3)
    with pytest.raises(ParameterError):
        kin.derivative(lib.array(Q[0]), 0)
    with pytest.raises(FrameError):
        kin.derivative(lib.array(Q[0]), 3, frame="no such frame")


@pytest.mark.parametrize("backend", BACKENDS)
def test_derivatives_of_a_tree_frame(backend):
    lib = Lib(backend)
    tree = symkin.Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, backend=backend, derivatives=3)
    q = tree.random_q(seed=4)
    for frame in tree.frames:
        D = lib.numpy(kin.derivative(lib.array(q), 3, frame=frame))
        ref = tree.derivative(q, 3, frame=frame)
        assert np.abs(D - ref).max() <= 1e-12 * max(1.0, np.abs(ref).max())
