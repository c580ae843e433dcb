"""The one numeric reference kernel (symkin/model/numeric.py) for chains and trees, against
computations that do not use it: the literal product of the elementary transforms written out
here with NumPy (Part 1 eqs 1, 5, Fig. 2) and central differences of the poses."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from symkin import Robot, load
from symkin.model.ets import ETS
from symkin.model.tree import as_tree

FEW = settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
AXES = ("tx", "ty", "tz", "Rx", "Ry", "Rz")


def elementary(name: str, x: float) -> np.ndarray:
    """The 4x4 matrix of one elementary transform, written out independently of symkin."""
    T = np.eye(4)
    i = "xyz".index(name[1])
    if name[0] == "t":
        T[i, 3] = x
        return T
    c, s = math.cos(x), math.sin(x)
    j, k = (i + 1) % 3, (i + 2) % 3
    T[j, j], T[j, k], T[k, j], T[k, k] = c, -s, s, c
    return T


@st.composite
def chains(draw) -> tuple[list[tuple[str, float | None, int]], int]:
    """A random ETS as (axis name, constant or None for a joint, joint sign), and its joint count."""
    items, n = [], 0
    for _ in range(draw(st.integers(1, 12))):
        name = draw(st.sampled_from(AXES))
        if draw(st.booleans()):
            items.append((name, None, draw(st.sampled_from((1, -1)))))
            n += 1
        else:
            items.append((name, draw(st.floats(-2.0, 2.0, allow_nan=False)), 1))
    if n == 0:
        items.append(("Rz", None, 1))
        n = 1
    return items, n


def _text(items: list[tuple[str, float | None, int]]) -> str:
    out, j = [], 0
    for name, c, sign in items:
        if c is None:
            out.append(f"{name}({'-' if sign < 0 else ''}q{j})")
            j += 1
        else:
            out.append(f"{name}({c!r})")
    return " ".join(out)


def _literal(items: list[tuple[str, float | None, int]], q: np.ndarray) -> tuple[np.ndarray, list]:
    """End pose and the pose right after each joint, by the plain product."""
    T, links, j = np.eye(4), [], 0
    for name, c, sign in items:
        if c is None:
            T = T @ elementary(name, sign * q[j])
            links.append(T)
            j += 1
        else:
            T = T @ elementary(name, c)
    return T, links


def _robot_at(chain: tuple[list, int], seed: int) -> tuple[list, Robot, np.ndarray]:
    """The drawn chain's items, its Robot and a random configuration of it."""
    items, n = chain
    return items, Robot(ETS.parse(_text(items))), np.random.default_rng(seed).uniform(-3.0, 3.0, n)


@FEW
@given(chains(), st.integers(0, 2**32 - 1))
def test_a_chains_poses_are_the_literal_product_of_its_transforms(chain, seed):
    items, robot, q = _robot_at(chain, seed)
    T, links = _literal(items, q)
    np.testing.assert_allclose(robot.fkine(q), T, atol=1e-12)
    np.testing.assert_allclose(robot.link_poses(q), np.array(links), atol=1e-12)
    np.testing.assert_allclose(as_tree(robot).fkine(q), T, atol=1e-12)  # the same walk as a tree


def _fd_jacobian(fkine, q: np.ndarray, h: float = 1e-6) -> np.ndarray:
    """Base-frame Jacobian (rows v, omega) from central differences of the poses."""
    n = len(q)
    R = fkine(q)[:3, :3]
    J = np.empty((6, n))
    for i in range(n):
        dq = np.zeros(n)
        dq[i] = h
        Tp, Tm = fkine(q + dq), fkine(q - dq)
        J[:3, i] = (Tp[:3, 3] - Tm[:3, 3]) / (2 * h)
        W = (Tp[:3, :3] - Tm[:3, :3]) / (2 * h) @ R.T
        J[3:, i] = [W[2, 1], W[0, 2], W[1, 0]]
    return J


@FEW
@given(chains(), st.integers(0, 2**32 - 1))
def test_link_frame_jacobians_and_hessians_are_derivatives_of_the_poses(chain, seed):
    _, robot, q = _robot_at(chain, seed)
    n = robot.n
    for k in (None, *range(n)):
        J = robot.jacob0(q, k)
        np.testing.assert_allclose(J, _fd_jacobian(lambda x, k=k: robot.fkine(x, k), q), atol=1e-7)
        H, h = robot.hessian0(q, k), 1e-6
        fd = np.stack(
            [(robot.jacob0(q + h * e, k) - robot.jacob0(q - h * e, k)) / (2 * h) for e in np.eye(n)]
        )
        np.testing.assert_allclose(H, fd, atol=1e-7)


@pytest.mark.parametrize("name", ["panda", "ur5", "puma560"])
def test_a_batch_is_each_configuration_on_its_own(name):
    robot = load(name)
    Q = robot.random_q(5, seed=3)
    J, H = robot.jacob0_hessian0(Q)
    for i, q in enumerate(Q):
        Ji, Hi = robot.jacob0_hessian0(q)
        np.testing.assert_array_equal(J[i], Ji)
        np.testing.assert_array_equal(H[i], Hi)
