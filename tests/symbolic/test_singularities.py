"""symkin.symbolic.singularities: the factored determinant against the compiled Jacobian."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import symkin
from symkin.errors import SymkinError
from symkin.symbolic.singularities import singular_factors
from tests.conftest import assert_close


def _compiled_det(name: str, rows: tuple[int, ...], Q: np.ndarray) -> np.ndarray:
    kin = symkin.compile(symkin.load(name), backend="numpy")
    return np.linalg.det(kin.jacob0(Q)[:, list(rows), :])


@pytest.mark.parametrize("name", ["ur5", "puma560", "stanford", "planar2", "planar3", "cobra600"])
def test_factored_determinant_equals_det_of_the_compiled_jacobian(name: str) -> None:
    A = singular_factors(name)
    assert A.method == "det(J)" and A.determinant is not None
    robot = symkin.load(name)
    Q = robot.random_q(6, seed=3)
    f = sp.lambdify(A.q, A.determinant, "numpy")
    got = np.array([float(f(*q)) for q in Q])
    assert_close(got, _compiled_det(name, A.rows, Q), 1e-9, f"{name}: det J")
    # the product of the factors really is the determinant: each factor vanishes somewhere J is singular
    assert A.factors and all(f.joints for f in A.factors)


def test_ur5_has_the_elbow_wrist_and_shoulder_factors() -> None:
    A = singular_factors("ur5")
    q = A.q
    simple = {(f.kind, f.joints) for f in A.factors if f.kind != "general"}
    assert simple == {("sin", (2,)), ("sin", (4,))}  # sin q3 and sin q5 (1-based)
    (shoulder,) = [f for f in A.factors if f.kind == "general"]
    assert shoulder.joints == (1, 2, 3)
    # a2 cos q2 + a3 cos(q2 + q3) + d5 sin(q2 + q3 + q4) (1-based) up to a constant factor
    a2, a3, d5 = sp.Rational(-425, 1000), sp.Rational(-39225, 100000), sp.Rational(9465, 100000)
    expected = a2 * sp.cos(q[1]) + a3 * sp.cos(q[1] + q[2]) + d5 * sp.sin(q[1] + q[2] + q[3])
    Q = symkin.load("ur5").random_q(5, seed=1)
    ratio = [float((shoulder.expr / expected).subs(dict(zip(q, x)))) for x in Q]
    assert np.ptp(ratio) < 1e-9 * abs(ratio[0]) and abs(ratio[0]) > 1e-6


def test_prismatic_joint_length_is_a_factor() -> None:
    A = singular_factors("stanford")
    (length,) = [f for f in A.factors if f.joints == (2,)]
    assert length.expr == A.q[2] and length.multiplicity == 2


def test_planar_two_link_uses_the_position_rows() -> None:
    A = singular_factors("planar2")
    assert A.axes == "trans" and A.rows == (0, 1)
    assert [(f.kind, f.joints) for f in A.factors] == [("sin", (1,))]


def test_redundant_and_short_jacobians_use_the_minors() -> None:
    # planar 3R, position only: 2 x 3, three 2 x 2 minors l1 l2 s2, l1 l3 s23, l2 l3 s3: no common factor
    A = singular_factors("planar3", axes="trans")
    assert A.method == "det(J J^T)" and A.minors == 3 and A.factors == () and A.determinant is None
    # planar 2R, all rows: 3 x 2 (vx, vy, wz), the minor (vy, wz) is cos q1: never all zero at once
    B = singular_factors("planar2", axes="all")
    assert B.method == "det(J^T J)" and B.factors == ()


def test_too_large_minors_are_reported_not_factored() -> None:
    A = singular_factors("ur5", max_terms=3)
    assert A.unfactored == 1 and A.factors == () and A.determinant is None


def test_bad_input() -> None:
    with pytest.raises(SymkinError, match="auto, all, trans, rot"):
        singular_factors("ur5", axes="xyz")
    with pytest.raises(SymkinError, match="no joints"):
        singular_factors(symkin.Robot.from_ets("tx(1)"))
