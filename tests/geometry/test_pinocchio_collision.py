"""The compiled collision kernel against Pinocchio + coal on the same spheres and capsules (the
``compare`` extra; skipped without it): distances to 1e-9 and identical verdicts on 10 000 random
configurations, and on near-contact ones (obstacles 1e-7 m off a shape)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.geometry import Capsule, Environment, Geometry, Sphere

pytest.importorskip("pinocchio")
pytest.importorskip("coal")

from symkin.bench.collide import pinocchio_collision, random_spheres  # noqa: E402


def _with_capsules(robot):
    extra = (
        Capsule((0, 0, -0.05), (0.03, 0, 0.08), 0.04, "ee"),
        Capsule((0, 0.02, 0), (0, 0.12, 0.05), 0.05, "link3"),
        Capsule((0, -0.1, 0), (0, 0.0, 0.1), 0.05, "link5"),
    )
    g = Geometry((*robot.geometry.shapes, *extra), robot.geometry.disabled)
    # the link pairs the added capsules bring into contact at the ready pose stay unchecked (as the
    # touching pairs of the built-in models): without that a compact wrist collides everywhere
    touching = {
        (shapes[i].link, shapes[j].link)
        for shapes in [g.shapes]
        for k, (i, j) in enumerate(symkin.geometry.layout_of(robot.with_geometry(g)).self_pairs)
        if symkin.geometry.distances(robot.with_geometry(g), robot.qr)[k] < 0
    }
    return robot.with_geometry(g.with_disabled(touching))


@pytest.mark.parametrize("name", ["panda", "ur5"])
def test_verdicts_and_distances_match_pinocchio(name):
    robot = _with_capsules(symkin.load(name))
    kin = symkin.compile(robot, backend="c")
    env = random_spheres(10, seed=1)
    peer = pinocchio_collision(robot, env)
    Q = robot.random_q(10_000, seed=7)
    ours = kin.in_collision(Q, env)
    theirs = np.array([peer(q) for q in Q])
    assert (ours == theirs).all()
    assert 0.02 < ours.mean() < 0.98  # both verdicts occur
    few = Q[:300]
    D = kin.distances(few, env)
    P = np.array([peer.distances(q) for q in few])
    assert D.shape == P.shape
    assert np.abs(D - P).max() < 1e-9


def test_near_contact_verdicts_match_pinocchio():
    robot = _with_capsules(symkin.load("panda"))
    kin = symkin.compile(robot, backend="c")
    rng = np.random.default_rng(3)
    shapes = robot.geometry.shapes
    checked = 0
    for q in robot.random_q(10_000, seed=9):
        if checked > 100:
            break
        if kin.in_collision(q):
            continue
        X = kin.collision_points(q)
        i = int(rng.integers(len(shapes)))
        first = symkin.geometry.layout_of(robot).point_index[i]
        centre = X[first] if isinstance(shapes[i], Sphere) else 0.5 * (X[first] + X[first + 1])
        if isinstance(shapes[i], Capsule):
            continue
        u = rng.normal(size=3)
        u /= np.linalg.norm(u)
        for gap in (1e-7, -1e-7):
            env = Environment(spheres=(Sphere(centre + u * (shapes[i].radius + 0.05 + gap), 0.05),))
            peer = pinocchio_collision(robot, env)
            verdict = kin.in_collision(q, env)
            assert verdict == peer(q)
            d = kin.distances(q, env)
            k = len(kin.collision_pairs()) + i  # the obstacle against shape i
            assert abs(d[k] - gap) < 1e-12
            if (np.delete(d, k) > 1e-5).all():  # no other pair near or in contact
                assert verdict == (gap < 0)
                checked += 1
    assert checked > 100
