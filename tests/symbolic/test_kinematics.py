"""The symbolic derivation against the numeric O(n) reference and against finite differences."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

from symkin import Robot
from symkin.model.robots import list_robots, load
from symkin.runtime.kinematics import KIN_METHODS
from symkin.symbolic.cse import count_ops, cse_outputs
from symkin.symbolic.functions import kin_functions
from symkin.symbolic.kinematics import derive
from tests.conftest import assert_close


def _evaluate(sk, q):
    f = sp.lambdify(sk.q, [sk.T, sk.J0, sk.Je, *sk.H0, *sk.He], "numpy", cse=True)
    out = [np.array(x, dtype=float) for x in f(*q)]
    n = len(sk.q)
    return out[0], out[1], out[2], np.array(out[3 : 3 + n]), np.array(out[3 + n :])


def assert_expanded_matches_reference(sk, robot, q):
    """The expanded derivation ``sk`` at ``q``: T, J0, Je, H0, He against the numeric reference."""
    T, J0, Je, H0, He = _evaluate(sk, q)
    assert_close(T, robot.fkine(q), 1e-12, "T")
    assert_close(J0, robot.jacob0(q), 1e-12, "J0")
    assert_close(Je, robot.jacobe(q), 1e-12, "Je")
    assert_close(H0, robot.hessian0(q), 1e-10, "H0")
    assert_close(He, robot.hessiane(q), 1e-10, "He")


@pytest.mark.parametrize("name", list_robots())
def test_derivation_matches_numeric_reference(name):
    robot = load(name)
    sk = derive(robot)
    for seed in range(3):
        q = robot.random_q(seed=seed)
        assert_expanded_matches_reference(sk, robot, q)


def test_symbolic_jacobian_is_the_derivative_of_the_symbolic_pose():
    """Independent of the numeric reference: J0 columns equal d(position)/dq and vee(dR/dq R^T)."""
    robot = load("stanford")  # has a prismatic joint
    sk = derive(robot)
    p = sk.T[:3, 3]
    R = sk.T[:3, :3]
    q = robot.random_q(seed=4)
    subs = dict(zip(sk.q, q))
    for j, qj in enumerate(sk.q):
        dp = [float(sp.diff(x, qj).evalf(subs=subs)) for x in p]
        S = (sp.diff(R, qj) * R.T).evalf(subs=subs)
        w = [float(S[2, 1]), float(S[0, 2]), float(S[1, 0])]
        col = [float(x.evalf(subs=subs)) for x in sk.J0[:, j]]
        np.testing.assert_allclose(col, dp + w, atol=1e-12)


def test_quarter_turn_constants_are_exact_permutations():
    sk = derive(Robot.from_ets("Rx(pi/2) Rz(q0) Ry(-90deg) tx(1) Rz(pi) tz(q1)"))
    assert not any(isinstance(a, sp.Float) for a in sk.T.atoms(sp.Number))
    assert not sk.T.has(sp.pi)
    trig = {a for a in sk.T.atoms(sp.Function)}
    assert trig <= {sp.cos(sk.q[0]), sp.sin(sk.q[0])}


def test_parallel_joints_merge_into_summed_angles():
    """The textbook planar arm: x = l1 c1 + l2 c12 + l3 c123 comes out directly."""
    sk = derive(Robot.from_ets("Rz(q0) tx(1) Rz(q1) tx(2) Rz(q2) tx(3)"))
    q0, q1, q2 = sk.q
    x_expected = sp.cos(q0) + 2 * sp.cos(q0 + q1) + 3 * sp.cos(q0 + q1 + q2)
    assert sp.expand(sk.T[0, 3] - x_expected) == 0
    assert sk.T[0, 3] == x_expected  # structurally, not only after simplification


def test_operation_counts_stay_small():
    """Guards the construction (measured: Panda FK+J0+H0 525 ops, UR5 195 after one CSE)."""
    for name, limit in (("ur5", 260), ("panda", 620)):
        sk = derive(load(name))
        c = cse_outputs({"T": sk.T, "J": sk.J0, "H": sk.H0}, sk.q).counts
        assert c.total <= limit, f"{name}: {c}"
        assert c.trig <= 2 * load(name).n + 4


def test_count_ops_counts_plain_arithmetic():
    x, y = sp.symbols("x y")
    c = count_ops(x * y + sp.cos(x) * 2 + y**2)
    assert (c.mul, c.add, c.trig) == (3, 2, 1)


def test_every_function_is_emitted_with_counts():
    fs = kin_functions(load("planar2"))
    names = [f.name for f in fs]
    assert names == list(KIN_METHODS)  # what the compiled Kinematics binds
    assert all(f.code.counts.total > 0 for f in fs)
