"""Collision distances of the JAX and PyTorch backends (symkin.runtime.diff.collision) against the C
backend's generated collision kernel, their joint gradients against the C kernel's analytic ones
and against finite differences, and the penalty for a loss."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.geometry import Box, Capsule, Environment, Sphere
from tests.diff_libs import BACKENDS, lib

SCENE = Environment(
    spheres=(Sphere((0.45, 0.35, 0.25), 0.08),),
    capsules=(Capsule((0.4, -0.4, 0.0), (0.4, -0.4, 0.5), 0.05),),
    boxes=(Box((0.5, 0.0, -0.1), (0.5, 0.8, 0.05)),),
)


@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


@pytest.fixture(scope="module")
def c_kin(panda):
    return symkin.compile(panda, backend="c")


@pytest.fixture(scope="module")
def Q(panda):
    """One batch shape for every test: JAX compiles each query once per shape (seconds each)."""
    return panda.random_q(12, seed=0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_distances_and_gradients_match_the_c_kernel(panda, c_kin, Q, backend):
    L = lib(backend)
    kin = symkin.compile(panda, backend=backend)
    x = L.array(Q)
    assert kin.collision_pairs(SCENE) == c_kin.collision_pairs(SCENE)
    D = L.numpy(kin.distances(x, SCENE))
    np.testing.assert_allclose(D, c_kin.distances(Q, SCENE), rtol=0, atol=1e-12)
    np.testing.assert_allclose(L.numpy(kin.distances(x)), c_kin.distances(Q), rtol=0, atol=1e-12)
    D2, G = kin.distance_jacobians(x, SCENE)
    Dc, Gc = c_kin.distance_jacobians(Q, SCENE)
    np.testing.assert_allclose(L.numpy(D2), Dc, rtol=0, atol=1e-12)
    np.testing.assert_allclose(L.numpy(G), Gc, rtol=0, atol=1e-10)
    hit = np.asarray(L.numpy(kin.in_collision(x, SCENE)), dtype=bool)
    assert hit.tolist() == list(c_kin.in_collision(Q, SCENE))
    assert 0 < hit.sum() < len(Q)  # both kinds of configuration are checked


@pytest.mark.parametrize("backend", BACKENDS)
def test_distance_gradients_match_finite_differences(panda, Q, backend):
    """Central differences (h = 1e-6) of the backend's own distances; pairs whose closest points
    switch features within h (a kink: the difference quotient jumps) are rare and skipped by
    requiring the one-sided quotients to agree."""
    L = lib(backend)
    kin = symkin.compile(panda, backend=backend)
    _, G = kin.distance_jacobians(L.array(Q), SCENE)
    G = L.numpy(G)
    h = 1e-6
    checked = 0
    for j in range(panda.n):
        dq = np.zeros(panda.n)
        dq[j] = h
        d0, dp, dm = (L.numpy(kin.distances(L.array(Q + s * dq), SCENE)) for s in (0, 1, -1))
        fwd, back = (dp - d0) / h, (d0 - dm) / h
        smooth = np.abs(fwd - back) < 1e-4
        fd = (dp - dm) / (2 * h)
        np.testing.assert_allclose(G[..., j][smooth], fd[smooth], rtol=0, atol=1e-7)
        checked += smooth.sum()
    assert checked > 0.99 * G.size


@pytest.mark.parametrize("backend", BACKENDS)
def test_collision_cost_is_the_squared_margin_violation_and_differentiable(panda, c_kin, Q, backend):
    L = lib(backend)
    kin = symkin.compile(panda, backend=backend)
    margin = 0.05
    d = c_kin.distances(Q, SCENE)
    expected = (np.maximum(margin - d, 0.0) ** 2).sum(-1)
    cost = kin.collision_cost(L.array(Q), SCENE, margin=margin)
    np.testing.assert_allclose(L.numpy(cost), expected, rtol=1e-12, atol=1e-15)
    _, Gc = c_kin.distance_jacobians(Q, SCENE)
    grad_expected = np.einsum("bm,bmn->bn", -2 * np.maximum(margin - d, 0.0), Gc)
    if backend == "jax":
        fn = kin.collision().cost
        grad = L.mod.jit(L.mod.grad(lambda q: fn(q, SCENE, margin).sum()))(L.array(Q))
    else:
        q = L.array(Q).requires_grad_(True)
        kin.collision_cost(q, SCENE, margin=margin).sum().backward()
        grad = q.grad
    np.testing.assert_allclose(L.numpy(grad), grad_expected, rtol=0, atol=1e-10)
    assert np.abs(grad_expected).max() > 1e-3
