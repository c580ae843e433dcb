"""symkin.symbolic.jacob0_analytical: the sympy analytical Jacobian against the compiled numeric one."""

from __future__ import annotations

import numpy as np
import pytest
import sympy as sp

import symkin
from symkin.errors import SymkinError
from symkin.model.differential import REPRESENTATIONS
from tests.conftest import assert_close


@pytest.mark.parametrize("name", ["ur5", "panda"])
@pytest.mark.parametrize("representation", REPRESENTATIONS)
def test_symbolic_analytical_jacobian_matches_the_compiled_one(name: str, representation: str) -> None:
    robot = symkin.load(name)
    Ja = symkin.symbolic.jacob0_analytical(robot, representation)
    q = symkin.symbolic(robot).q
    assert Ja.shape == (6, robot.n) and Ja.free_symbols <= set(q)
    f = sp.lambdify(q, Ja, "numpy", cse=True)  # the exp form of the Panda written out is ~185,000 ops
    kin = symkin.compile(robot, backend="numpy")
    for x in robot.random_q(4, seed=5):
        assert_close(
            np.array(f(*x), dtype=float), kin.jacob0_analytical(x, representation), 1e-9, representation
        )


def test_rates_times_angular_velocity_are_finite_differences_of_the_angles() -> None:
    # independent of the runtime: d gamma/dt from the symbolic J_a against differences of the rpy angles
    robot = symkin.load("ur5")
    Ja = symkin.symbolic.jacob0_analytical(robot, "rpy/zyx")
    q = symkin.symbolic(robot).q
    f = sp.lambdify(q, Ja, "numpy")

    def rpy(x):  # R = Rz(yaw) Ry(pitch) Rx(roll)
        R = robot.fkine(x)[:3, :3]
        return np.array([np.arctan2(R[2, 1], R[2, 2]), -np.arcsin(R[2, 0]), np.arctan2(R[1, 0], R[0, 0])])

    x, qd, h = robot.random_q(seed=9), np.linspace(0.3, -0.2, 6), 1e-6
    fd = (rpy(x + h * qd) - rpy(x - h * qd)) / (2 * h)
    assert_close(np.array(f(*x), dtype=float)[3:] @ qd, fd, 1e-6, "d gamma/dt")


def test_unknown_representation() -> None:
    with pytest.raises(SymkinError, match="rpy/xyz"):
        symkin.symbolic.jacob0_analytical("planar2", "quaternion")
