"""Solver and controller parameters are validated, and a controller never reports "solved" with a
non-finite answer (issue 12, items 4, 7 and the IK/control side of 13)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin.errors import ConfigurationError, ParameterError, PoseError
from symkin.runtime.control import MMC, StepInfo, rrmc
from symkin.runtime.loop import servo
from symkin.runtime.servo import servo_velocity

NAN, INF = math.nan, math.inf
NU = np.array([0.05, -0.02, 0.03, 0.1, 0.0, -0.1])


@pytest.fixture(scope="module")
def cpanda(kin):  # the Panda's C kinematics (tests/runtime/conftest.py)
    return kin


@pytest.mark.parametrize(
    "kwargs",
    [
        {"dt": NAN},  # returned NaN qd with status "solved"
        {"dt": INF},
        {"dt": 0.0},
        {"dt": -0.01},
        {"xi": NAN},  # also NaN with "solved"
        {"xi": INF},
        {"xi": 0.0},
        {"lam": NAN},
        {"lam": -1.0},
        {"rho_i": NAN},
        {"rho_s": INF},
        {"rho_i": 0.1, "rho_s": 0.2},
        {"rho_i": [0.9, 0.9]},  # wrong length
        {"qd_max": NAN},
        {"qd_max": 0.0},
        {"qd_max": [1.0, 2.0]},
        {"qd_max": 1j},
        {"slack_weight": NAN},
        {"singular_tol": -1.0},
        {"axes": "xyz"},
        {"backend": "gpu"},
    ],
)
@pytest.mark.parametrize("backend", ["python", "auto"])
def test_mmc_rejects_invalid_parameters(panda, cpanda, kwargs, backend):
    kin = cpanda if backend == "auto" else panda
    kwargs = {"backend": backend, **kwargs}
    with pytest.raises(ParameterError):
        MMC(kin, joint_limits=True, **kwargs)


@pytest.mark.parametrize(
    "kwargs", [{"damping": NAN}, {"damping": INF}, {"damping": -0.1}, {"singular_tol": NAN}, {"qd_max": -1}]
)
@pytest.mark.parametrize("backend", ["python", "c"])
def test_rrmc_rejects_invalid_parameters(panda, cpanda, kwargs, backend):
    with pytest.raises(ParameterError):
        rrmc(cpanda if backend == "c" else panda, panda.qr, NU, **kwargs)


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_valid_edge_parameters_give_finite_steps(panda, cpanda, backend):
    kin = cpanda if backend == "auto" else panda
    for kwargs in ({"qd_max": INF}, {"dt": 1e-6}, {"xi": 1e-9}, {"rho_s": 0.0}, {"lam": 1e-12}):
        qd, info = MMC(kin, joint_limits=True, backend=backend, **kwargs).step(panda.qr, NU)
        assert np.isfinite(qd).all() and info.status in {"solved", "singular", "infeasible", "max_iter"}


class _NaNJacobian:
    """Kinematics whose Jacobian is NaN: no parameter check can catch this."""

    def __init__(self, robot):
        self.robot, self.n, self.qlim, self.qd_max = robot, robot.n, robot.qlim, None

    def jacob0(self, q):
        return np.full((6, self.n), np.nan)

    def jacob0_hessian0(self, q):
        return self.jacob0(q), np.zeros((self.n, 6, self.n))


def test_a_step_is_never_solved_with_non_finite_qd(panda):
    qd, info = MMC(_NaNJacobian(panda), backend="python").step(panda.qr, NU)
    assert np.isfinite(qd).all()
    assert not info.ok and info.status != "solved"
    assert isinstance(info, StepInfo)


@pytest.mark.parametrize("value", [2**32 + 1, 2**31, 0, -1, 1.5, True, "30", NAN])
@pytest.mark.parametrize("name", ["ilimit", "slimit"])
@pytest.mark.parametrize("solver", ["c", "numpy"])
def test_ik_iteration_limits_are_validated(cpanda, panda, name, value, solver):
    """2**32 + 1 was truncated to int32 and became 1."""
    with pytest.raises(ParameterError, match=name):
        cpanda.ik(panda.fkine(panda.qr), backend=solver, **{name: value})


def test_ik_limits_product_fits_the_c_counters(cpanda, panda):
    with pytest.raises(ParameterError, match="ilimit \\* slimit"):
        cpanda.ik(panda.fkine(panda.qr), ilimit=2**20, slimit=2**12)
    res = cpanda.ik(panda.fkine(panda.qr), ilimit=30.0, slimit=np.int64(5), seed=0)  # integral values
    assert res.success


@pytest.mark.parametrize(
    "kwargs",
    [
        {"tol": NAN},
        {"tol": 0.0},
        {"lam": NAN},
        {"lam": [0.1, 0.2]},
        {"we": [1, 1, 1, 1, 1, NAN]},
        {"method": "XX"},
    ],
)
@pytest.mark.parametrize("solver", ["c", "numpy"])
def test_ik_options_are_validated(cpanda, panda, kwargs, solver):
    with pytest.raises(ParameterError):
        cpanda.ik(panda.fkine(panda.qr), backend=solver, **kwargs)


@pytest.mark.parametrize("solver", ["c", "numpy"])
def test_ik_refuses_complex_targets_and_starts_on_both_solvers(cpanda, panda, solver):
    T = panda.fkine(panda.qr)
    with pytest.raises(PoseError, match="complex"):
        cpanda.ik(T + 0j, backend=solver)
    with pytest.raises(PoseError, match="complex"):
        cpanda.ik(np.stack([T, T]) + 0j, backend=solver)
    with pytest.raises(ConfigurationError, match="complex"):
        cpanda.ik(T, q0=panda.qr + 0j, backend=solver)
    big_endian = cpanda.ik(T.astype(">f8"), q0=panda.qr.astype(">f8"), backend=solver, seed=0)
    assert big_endian.success and np.abs(panda.fkine(big_endian.q) - T).max() < 1e-6


@pytest.mark.parametrize("backend", ["python", "auto"])
def test_mmc_inputs_are_checked_like_everywhere(panda, cpanda, backend):
    mmc = MMC(cpanda if backend == "auto" else panda, backend=backend)
    with pytest.raises(ConfigurationError, match="complex"):
        mmc.step(panda.qr + 0j, NU)
    with pytest.raises(ParameterError, match="nu"):
        mmc.step(panda.qr, NU + 0j)
    want, _ = mmc.step(panda.qr, NU)
    got, _ = mmc.step(panda.qr.astype(">f8"), NU.astype(">f8"))
    assert np.allclose(got, want, atol=1e-12)
    from fractions import Fraction

    got, _ = mmc.step(np.array([Fraction(x).limit_denominator(10**9) for x in panda.qr], dtype=object), NU)
    assert np.isfinite(got).all()


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"dt": INF}, "dt"),  # failed mid-run on the command line
        ({"dt": NAN}, "dt"),
        ({"max_steps": -1}, "max_steps"),
        ({"max_steps": 2.5}, "max_steps"),
        ({"controller": "pid"}, "controller"),
    ],
)
def test_servo_rejects_invalid_parameters(panda, kwargs, words):
    with pytest.raises(ParameterError, match=words):
        servo(panda, panda.qr, panda.fkine(panda.qz), **kwargs)


def test_servo_velocity_rejects_invalid_threshold_and_caps():
    e = np.full(6, 0.1)
    for kwargs in ({"threshold": NAN}, {"threshold": -1.0}, {"nu_max": NAN}, {"gain": 1j}):
        with pytest.raises(ParameterError):
            servo_velocity(e, **kwargs)


def test_ik_and_mmc_need_joints():
    robot = symkin.Robot.from_ets("tx(1)")  # a valid robot without joints
    with pytest.raises(ParameterError, match="at least one joint"):
        robot.ik(np.eye(4))  # raw ValueError from a reshape before
    with pytest.raises(ParameterError, match="at least one joint"):
        MMC(robot)
