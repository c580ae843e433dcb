"""The CasADi distances (``kin.collision_function``): the same values and derivatives as the
reference, and obstacle constraints in a ``casadi.Opti`` IK problem solved with IPOPT."""

from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

import symkin
from symkin import Box, Capsule, Environment, Geometry, Sphere
from symkin.errors import GeometryError

ENV = Environment(
    spheres=(Sphere((0.45, 0.1, 0.5), 0.1),),
    capsules=(Capsule((0.3, -0.4, 0.0), (0.3, -0.3, 0.8), 0.05),),
    boxes=(Box((0.4, 0.0, -0.1), (0.6, 0.8, 0.05), rotation=[[0.8, -0.6, 0], [0.6, 0.8, 0], [0, 0, 1]]),),
)


@pytest.fixture(scope="module")
def panda():
    return symkin.load("panda")


def test_values_and_jacobians_match_the_reference(panda):
    kin = symkin.compile(panda, backend="numpy")
    f = kin.collision_function(ENV)
    assert f is kin.collision_function(ENV)  # built once per environment
    x = ca.SX.sym("q", 7)
    jac = ca.Function("dd_dq", [x], [ca.jacobian(f(x), x)])
    for q in panda.random_q(20, seed=3):
        d, J = kin.distance_jacobians(q, ENV)
        assert np.abs(np.array(f(q)).ravel() - d).max() < 1e-12
        Jc = np.array(jac(q))
        assert np.isfinite(Jc).all()
        assert np.abs(Jc - J)[d > 1e-4].max() < 1e-10


def test_capsules_and_trees(panda):
    arm = panda.with_geometry(
        Geometry(
            (*panda.geometry.shapes, Capsule((0, 0, 0), (0, 0.1, 0.05), 0.04, "link3")),
            panda.geometry.disabled,
        )
    )
    kin = symkin.compile(symkin.Tree.from_robot(arm), backend="numpy")
    env = Environment(spheres=ENV.spheres, capsules=ENV.capsules)
    f = kin.collision_function(env)
    Q = panda.random_q(20, seed=4)
    assert np.abs(np.array([np.array(f(q)).ravel() for q in Q]) - kin.distances(Q, env)).max() < 1e-12
    with pytest.raises(GeometryError, match="capsule against a box"):
        kin.collision_function(ENV)


def test_ik_nlp_with_an_obstacle_constraint(panda):
    """IK as an NLP; an obstacle placed on the elbow of the unconstrained solution: with the
    distance constraints the solution reaches the same pose and keeps 2 cm away."""
    kin = symkin.compile(panda, backend="casadi")
    q_goal = panda.qr.copy()
    q_goal[0] += 0.5
    T_goal = kin.fkine(q_goal)

    def solve(dist: ca.Function | None, n_self: int = 0) -> np.ndarray:
        opti = ca.Opti()
        q = opti.variable(7)
        T = kin.functions["fkine"](q)
        opti.minimize(ca.sumsqr(T[:3, :3] - T_goal[:3, :3]) + 1e-4 * ca.sumsqr(q - panda.qr))
        opti.subject_to(T[:3, 3] == T_goal[:3, 3])
        opti.subject_to(opti.bounded(panda.qlim[0], q, panda.qlim[1]))
        if dist is not None:
            opti.subject_to(dist(q)[n_self:] >= 0.02)
        opti.set_initial(q, panda.qr)
        opti.solver("ipopt", {"ipopt.print_level": 0, "print_time": 0, "ipopt.sb": "yes"})
        return np.array(opti.solve().value(q)).ravel()

    free = solve(None)
    assert np.linalg.norm(kin.fkine(free)[:3, 3] - T_goal[:3, 3]) < 1e-6
    elbow = next(i for i, s in enumerate(panda.geometry.shapes) if s.link == "link4")
    centre = kin.collision_points(free)[symkin.geometry.layout_of(panda).point_index[elbow]]
    env = Environment(spheres=(Sphere(centre, 0.05),))
    n_self = len(kin.collision_pairs(env)) - len(panda.geometry.shapes)
    assert kin.distances(free, env)[n_self:].min() < 0  # the unconstrained elbow is in the ball
    q = solve(kin.collision_function(env), n_self)
    assert kin.distances(q, env)[n_self:].min() >= 0.02 - 1e-6
    assert np.linalg.norm(kin.fkine(q)[:3, 3] - T_goal[:3, 3]) < 1e-6
    assert np.abs(kin.fkine(q)[:3, :3] - T_goal[:3, :3]).max() < 0.05  # the hand keeps its orientation
