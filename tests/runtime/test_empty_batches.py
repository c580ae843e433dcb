"""Every batched entry point takes N = 0 configurations on every backend and gives empty results
of the batch's shape: the kinematics of a chain and of a tree (every method, every frame), the
derived quantities, and the collision queries (distances, their Jacobians, verdicts, points)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.model.geometry import Geometry, Sphere
from tests.model.tree_urdfs import GRIPPER

BACKENDS = ("c", "numpy", "casadi")
FRAMED = ("fkine", "jacob0", "jacobe", "fkine_jacob0", "hessian0", "hessiane", "jacob0_hessian0")
FRAMED += ("manipulability", "jacobm", "cond", "jacobs", "jacobb")
EVERY = ("fkine_all", "jacob0_all", "fkine_jacob0_all")
ENV = symkin.Environment(spheres=(Sphere((0.3, 0.0, 0.3), 0.1),))


def _shapes(x) -> list[tuple[int, ...]]:
    return [np.shape(a) for a in (x if isinstance(x, tuple) else (x,))]


def _models():
    robot = symkin.load("ur5")
    tree = symkin.Tree.from_urdf(GRIPPER)  # two frames, a mimic joint
    spheres = tuple(Sphere((0.0, 0.0, 0.05), 0.05, link) for link in tree.link_names)
    chain = robot.with_geometry(Geometry((Sphere((0, 0, 0), 0.05, "link3"), Sphere((0, 0, 0), 0.05, "ee"))))
    return chain, tree.with_geometry(Geometry(spheres))


@pytest.mark.parametrize("backend", BACKENDS)
def test_every_kinematics_method_takes_an_empty_batch(backend):
    for model in _models():
        kin = symkin.compile(model, backend)
        Q0, Q1 = np.zeros((0, model.n)), model.random_q(1, seed=1)
        frames = [None] if len(kin.frames) == 1 else list(kin.frames)
        calls = [(name, frame) for name in FRAMED for frame in frames] + [(name, None) for name in EVERY]
        if len(kin.frames) == 1:
            calls += [("link_poses", None), ("fkine", 2), ("jacob0", 2), ("hessian0", 2), ("jacobm", 2)]
        for name, frame in calls:
            f = getattr(kin, name)
            empty, one = (f(Q0), f(Q1)) if frame is None else (f(Q0, frame), f(Q1, frame))
            want = [(0, *s[1:]) for s in _shapes(one)]
            assert _shapes(empty) == want, (backend, model.name, name, frame)
        qd = np.zeros((0, model.n))
        assert kin.jacob0_dot(Q0, qd, frames[0]).shape == (0, 6, model.n)


@pytest.mark.parametrize("backend", ["c", "numpy"])
def test_every_collision_query_takes_an_empty_batch(backend):
    for model in _models():
        kin = symkin.compile(model, backend)
        Q0, Q1 = np.zeros((0, model.n)), model.random_q(1, seed=2)
        for env in (None, ENV):
            D1, J1 = kin.distance_jacobians(Q1, env)
            D0, J0 = kin.distance_jacobians(Q0, env)
            assert D0.shape == (0, D1.shape[1]) and J0.shape == (0, *J1.shape[1:]), (backend, model.name)
            assert kin.distances(Q0, env).shape == (0, D1.shape[1])
            verdicts = kin.in_collision(Q0, env)
            assert verdicts.shape == (0,) and verdicts.dtype == bool
        assert kin.collision_points(Q0).shape == (0, *kin.collision_points(Q1).shape[1:])
