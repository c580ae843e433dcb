"""Structure detection for the closed-form IK: exact axes, float tolerance, clear refusals."""

from __future__ import annotations

import pytest

from symkin import DHLink, Robot, load
from symkin.errors import NoAnalyticIKError
from symkin.symbolic.analytic_ik import derive_analytic
from symkin.symbolic.ik_geometry import classify, geometry, snap


@pytest.mark.parametrize(
    ("name", "kind", "position", "S"),
    [
        ("ur3", "three_parallel", "", 8),
        ("ur5", "three_parallel", "", 8),
        ("ur10", "three_parallel", "", 8),
        ("puma560", "spherical_wrist", "parallel23", 8),
        ("stanford", "spherical_wrist", "intersect12", 8),
        ("planar2", "planar2", "", 2),
        ("planar3", "planar3", "", 2),
    ],
)
def test_builtin_structures(name, kind, position, S):
    plan = derive_analytic(load(name))
    assert (plan.structure.kind, plan.structure.position, plan.max_solutions) == (kind, position, S)


@pytest.mark.parametrize("name", ["panda", "lbr_iiwa7", "sawyer"])
def test_redundant_arms_refused(name):
    with pytest.raises(NoAnalyticIKError, match="numerical IK"):
        derive_analytic(load(name))


def test_general_6r_refused_naming_what_it_lacks():
    links = [DHLink(d=0.3, a=0.1, alpha="pi/3") for _ in range(6)]
    with pytest.raises(NoAnalyticIKError, match="neither a spherical wrist"):
        derive_analytic(Robot.from_dh(links, name="skew6"))


def _ur5_like(alpha1: float, alpha2: float) -> Robot:
    alpha = [alpha1, alpha2, 0, alpha1, -alpha1, 0]
    d = [0.089159, 0, 0, 0.10915, 0.09465, 0.0823]
    a = [0, -0.425, -0.39225, 0, 0, 0]
    return Robot.from_dh([DHLink(d=d[j], a=a[j], alpha=alpha[j]) for j in range(6)], name="ur5f")


def test_floating_point_twists_within_the_tolerance_are_snapped():
    robot = _ur5_like(1.5707963267948966, 1e-12)  # pi/2 as a float; a twist of 1e-12 rad is 0
    plan = derive_analytic(robot)
    assert plan.structure.kind == "three_parallel"
    assert all(x in (-1, 0, 1) for h in plan.geometry.h for x in h)  # exact axes after snapping


def test_a_twist_beyond_the_tolerance_breaks_the_structure():
    with pytest.raises(NoAnalyticIKError, match="neither a spherical wrist"):
        derive_analytic(_ur5_like(1.5707963267948966, 1e-4))  # axes 2 and 3 no longer parallel


def test_exact_geometry_of_the_puma():
    g = geometry(snap(load("puma560").ets))
    s = classify(g)
    assert tuple(float(x) for x in s.wrist) == (0.4521, -0.15005, 0.4318)
    assert g.h[1] == g.h[2]  # parallel shoulder and elbow axes, exactly


def test_ets_and_dh_sources_agree():
    ets = "Rz(q) tz(0.5) Ry(q) tz(0.4) Ry(q) tz(0.3) Rz(q) Ry(q) Rz(q) tz(0.1)"
    plan = derive_analytic(Robot.from_ets(ets, name="e"))
    assert plan.structure.kind == "spherical_wrist"


def test_reversed_chain_is_the_inverse_and_solves_a_spherical_shoulder():
    """reverse() reads the chain from the tool: applied twice it gives the chain back, and a 6-joint
    arm whose first three axes meet (the Panda without q7) is solved on the reversed chain."""
    import numpy as np
    import sympy as sp

    from symkin.runtime.free_joint import sub_robot
    from symkin.symbolic.ik_geometry import reverse

    g = geometry(snap(load("puma560").ets))
    back = reverse(reverse(g))
    assert back.joint == g.joint and back.revolute == g.revolute
    assert all(sp.simplify(a - b) == 0 for u, v in zip(back.h + back.p, g.h + g.p) for a, b in zip(u, v))
    assert sp.simplify(back.M - g.M) == sp.zeros(4, 4)
    sub = sub_robot(load("panda"), 6)[0]
    with pytest.raises(NoAnalyticIKError):
        classify(geometry(snap(sub.ets)))
    plan = derive_analytic(sub)
    assert plan.structure.reversed and plan.structure.kind == "spherical_wrist" and plan.max_solutions == 8
    # the reversed chain's pose at q is the inverse of the arm's (the geometry the steps are built on)
    q = np.array([0.3, -0.5, 0.8, -1.9, 0.4, 1.2])
    T = sub.fkine(q)
    r = plan.geometry
    Tr = np.eye(4)
    for k, j in enumerate(r.joint):
        h = np.array([float(x) for x in r.h[k]])
        p = np.array([float(x) for x in r.p[k]])
        K = np.array([[0, -h[2], h[1]], [h[2], 0, -h[0]], [-h[1], h[0], 0]])
        R = np.eye(3) + np.sin(q[j]) * K + (1 - np.cos(q[j])) * K @ K
        G = np.eye(4)
        G[:3, :3], G[:3, 3] = R, p - R @ p
        Tr = Tr @ G
    Tr = Tr @ np.array(r.M.evalf(), dtype=float)
    np.testing.assert_allclose(Tr, np.linalg.inv(T), atol=1e-12)
