"""Structure detection for the closed-form IK: exact axes, float tolerance, clear refusals."""

from __future__ import annotations

from fractions import Fraction

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


def test_constant_and_mirror_tests_need_no_expansion():
    """is_constant and the C body's mirror test decide at random points (then, exactly, by
    expanding only what passes): a coefficient of an arm with general axes would expand to
    thousands of terms."""
    import sympy as sp

    from symkin.emit.analytic_ik import _sign_under
    from symkin.symbolic.ik_geometry import is_constant, value_at

    c, s, r = sp.symbols("c0 s0 r11", real=True)
    assert is_constant((c + s) ** 2 - c**2 - s**2 - 2 * c * s + sp.Rational(3, 2))
    assert not is_constant(c**2 + s**2)  # 1 on the circle only: c and s are independent symbols here
    assert is_constant(sp.cos(sp.Rational(3, 10)) * 2)
    assert abs(value_at(sp.sqrt(2) * c - s, {c: 1, s: Fraction(1, 2)}) - (2**0.5 - 0.5)) < 1e-15
    assert _sign_under(-r * s, {c: -c, s: -s}) == -1
    assert _sign_under(c * s + r, {c: -c, s: -s}) == 1
    assert _sign_under(c + s, {c: -c}) is None
    big = sp.Float("0.3", 50) * c * s - sp.Float("0.3", 50) * s * c + r
    assert _sign_under(big, {c: -c, s: -s}) == 1


def test_geometry_after_a_folded_run_is_numeric_to_50_digits():
    """A run of rotations between joints (two turns about the next joint's axis) folds to 50-digit
    numbers: the structure tests still see the UR arm's parallel axes."""
    import sympy as sp

    from symkin.symbolic.ik_geometry import fold_ik

    ur5 = str(load("ur5").ets).replace("Rz(q2)", "Rz(0.3) tx(0.01) Rz(0.2) Rz(q2)")
    g = geometry(fold_ik(snap(Robot.from_ets(ur5, name="u").ets)))
    assert any(x.has(sp.Float) for v in g.h for x in v)
    assert classify(g).kind == "three_parallel"
