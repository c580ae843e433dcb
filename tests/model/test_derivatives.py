"""The numeric reference of the derivatives of any order (Part 2's product rule on J0's columns)
against central differences of J0 of order k - 1, on chains with revolute and prismatic joints,
link frames, trees and a mimic-joint tree; its layout against roboticstoolbox-python's
``partial_fkine0`` (compare extra); the errors for bad orders."""

from __future__ import annotations

import itertools

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import symkin
from symkin import ParameterError, Tree
from symkin.model.derivatives import MAX_ENTRIES, MAX_ORDER, derivative_shape, rtb_valid
from tests.conftest import assert_close
from tests.model.tree_urdfs import GRIPPER, QUADRUPED

# central differences of order k - 1 of J0: step and the tolerance they reach (truncation h^2,
# rounding eps / h^(k-1)), relative to max(1, |D|)
STEP = {1: 0.0, 2: 1e-5, 3: 1e-4, 4: 1e-3}
FD_TOL = {1: 1e-14, 2: 1e-8, 3: 2e-6, 4: 2e-5}


def central_differences(jacob0, q: np.ndarray, order: int, h: float | None = None) -> np.ndarray:
    """The order-``order`` derivative at one ``q`` by nested central differences of ``jacob0``
    (a batched function (N, n) -> (N, 6, n)): ``D[i_{k-1}, ..., i_1, :, i_0]`` is the mean over
    the 2^(k-1) sign patterns s of ``prod(s) J(q + h sum_m s_m e_{i_m})[:, i_0] / h^(k-1)`` / 2^(k-1)
    (order 1: J itself)."""
    n, m = q.shape[0], order - 1
    h = STEP[order] if h is None else h
    if m == 0:
        return jacob0(q[None])[0]
    dirs = list(itertools.product(range(n), repeat=m))  # (i_1, ..., i_m)
    signs = list(itertools.product((1.0, -1.0), repeat=m))
    Q = np.array([q + h * sum(s * np.eye(n)[i] for s, i in zip(sg, d)) for d in dirs for sg in signs])
    J = jacob0(Q).reshape(len(dirs), len(signs), 6, n)
    weights = np.array([np.prod(sg) for sg in signs]) / (2 * h) ** m
    D = np.einsum("dsrc,s->drc", J, weights)  # (dirs, 6, n), dirs as (i_1, ..., i_m)
    D = D.reshape((n,) * m + (6, n))
    return D.transpose(*range(m - 1, -1, -1), m, m + 1)  # (i_m, ..., i_1, 6, n)


CHAINS = ("planar3", "ur5", "panda", "stanford", "cobra600")


@pytest.mark.parametrize("name", CHAINS)
@pytest.mark.parametrize("order", (2, 3, 4))
def test_chain_derivatives_are_central_differences_of_the_jacobian(name, order):
    robot = symkin.load(name)
    for seed in (1, 2):
        q = robot.random_q(seed=seed)
        D = robot.derivative(q, order)
        assert D.shape == derivative_shape(order, robot.n)
        assert_close(D, central_differences(robot.jacob0, q, order), FD_TOL[order], f"{name} order {order}")


def test_orders_one_and_two_are_the_jacobian_and_the_hessian():
    panda = symkin.load("panda")
    Q = panda.random_q(4, seed=3)
    assert np.array_equal(panda.derivative(Q, 1), panda.jacob0(Q))
    assert np.array_equal(panda.derivative(Q, 2), panda.hessian0(Q))
    # Part 2's recursion from order 1 reproduces the Hessian written by eq 20 in its own layout
    from symkin.model.derivatives import chain_derivative

    assert_close(chain_derivative(panda.jacob0(Q), range(7), 2), panda.hessian0(Q), 1e-15, "H")


def test_batches_and_one_configuration_agree():
    robot = symkin.load("ur5")
    Q = robot.random_q(3, seed=4)
    D = robot.derivative(Q, 3)
    assert D.shape == (3, 6, 6, 6, 6)
    for i in range(3):
        assert np.array_equal(robot.derivative(Q[i], 3), D[i])
    assert robot.derivative(np.zeros((0, 6)), 4).shape == (0, 6, 6, 6, 6, 6)


def test_link_frames_of_a_chain():
    panda = symkin.load("panda")
    q = panda.random_q(seed=5)
    for k in (2, 5):
        D = panda.derivative(q, 3, frame=k)
        J = lambda Q, k=k: panda.jacob0(Q, k)  # noqa: E731
        assert_close(D, central_differences(J, q, 3), FD_TOL[3], f"link {k}")
        assert not D[..., k + 1 :].any() and not D[k + 1 :].any()  # joints after the frame


@pytest.mark.parametrize("urdf", [QUADRUPED, GRIPPER], ids=["quadruped", "gripper"])
def test_tree_frames_and_mimic_joints(urdf):
    tree = Tree.from_urdf(urdf)
    for frame in tree.frames:
        q = tree.random_q(seed=6)
        for order in (3, 4):
            D = tree.derivative(q, order, frame)
            J = lambda Q, f=frame: tree.jacob0(Q, f)  # noqa: E731
            assert_close(D, central_differences(J, q, order), FD_TOL[order], f"{frame} order {order}")


def test_a_chain_and_its_tree_agree():
    panda = symkin.load("panda")
    Q = panda.random_q(3, seed=7)
    assert_close(Tree.from_robot(panda).derivative(Q, 4), panda.derivative(Q, 4), 1e-15, "tree of the Panda")


@settings(max_examples=15, deadline=None)
@given(st.integers(0, 2**31 - 1), st.integers(2, 4))
def test_translational_part_is_symmetric_and_angular_part_vanishes_after_the_column(seed, order):
    """d^k p is symmetric in all k indices; d^(k-1) w_{i0} is 0 unless every derivative index
    comes before i0 along the chain (an axis does not move with later joints)."""
    robot = symkin.load("panda")
    D = robot.derivative(robot.random_q(seed=seed), order)
    V = np.moveaxis(D[..., :3, :], -2, 0)  # (3, i_{k-1}, ..., i_1, i_0)
    for perm in itertools.permutations(range(1, order + 1)):
        assert np.allclose(V, V.transpose(0, *perm), atol=1e-13)
    W = D[..., 3:, :]
    for idx in itertools.product(range(7), repeat=order):  # (i_{k-1}, ..., i_1, i_0)
        w = W[idx[:-1] + (slice(None), idx[-1])]
        if max(idx[:-1]) > idx[-1]:
            assert not w.any()  # written as 0
        elif max(idx[:-1]) == idx[-1]:
            assert np.abs(w).max() <= 1e-15  # w_a x w_a and its derivatives: 0 up to rounding


def test_bad_orders_are_refused():
    robot = symkin.load("ur5")
    q = robot.qz
    for bad in (0, -1, MAX_ORDER + 1):
        with pytest.raises(ParameterError, match="order must be 1"):
            robot.derivative(q, bad)
    for bad in (True, 2.0, "3", None):
        with pytest.raises(ParameterError, match="order must be an integer"):
            robot.derivative(q, bad)
    big = symkin.load("planar3").__class__.from_ets(" ".join(f"Rz(q{j}) tx(0.1)" for j in range(20)))
    with pytest.raises(ParameterError, match=f"more than {MAX_ENTRIES:,}"):
        big.derivative(np.zeros(20), 5)


def test_against_roboticstoolbox_partial_fkine0():
    """roboticstoolbox-python 1.5's partial_fkine0(q, k) has the same layout; it equals the
    derivative where its recursion's cross product holds (rtb_valid) and differs elsewhere."""
    rtb = pytest.importorskip("roboticstoolbox")
    panda = symkin.load("panda")
    ets = rtb.models.Panda().ets()
    for seed in (1, 2):
        q = panda.random_q(seed=seed)
        assert_close(ets.hessian0(q), panda.derivative(q, 2), 1e-14, "order 2")
        for order in (3, 4):
            D, R = panda.derivative(q, order), ets.partial_fkine0(q, order)
            assert R.shape == D.shape
            mask = rtb_valid(order, 7)
            assert_close(R[mask], D[mask], 1e-14, f"order {order} where RTB's recursion holds")
            assert np.abs(R - D)[~mask].max() > 0.1  # and not elsewhere: the documented difference
