"""Every backend against the numeric reference, on every built-in robot and on random ETS robots."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import symkin
from symkin import ETS, Robot
from symkin.errors import ConfigurationError
from symkin.model.ets import ET, Axis, Const
from symkin.model.robots import list_robots, load
from tests.conftest import assert_close

TOL = {
    "fkine": 1e-12,
    "link_poses": 1e-12,
    "jacob0": 1e-12,
    "jacobe": 1e-12,
    "hessian0": 1e-10,
    "hessiane": 1e-10,
}


def check_against_reference(kin, robot: Robot, seed: int = 0, batch: int = 20) -> None:
    rng = np.random.default_rng(seed)
    q = robot.random_q(seed=rng)
    Q = robot.random_q(batch, seed=rng)
    for name, tol in TOL.items():
        f, ref = getattr(kin, name), getattr(robot, name)
        assert_close(f(q), ref(q), tol, f"{kin.backend} {robot.name} {name} single")
        assert_close(f(Q), ref(Q), tol, f"{kin.backend} {robot.name} {name} batch")
    T, J = kin.fkine_jacob0(Q)
    assert_close(T, robot.fkine(Q), 1e-12, "fkine_jacob0 T")
    assert_close(J, robot.jacob0(Q), 1e-12, "fkine_jacob0 J")
    J, H = kin.jacob0_hessian0(q)
    assert_close(H, robot.hessian0(q), 1e-10, "jacob0_hessian0 H")
    # m = sqrt(det(J J^T)) amplifies rounding near singularities (sqrt of ~1e-17 is ~3e-9), so
    # compare m^2 = det(J J^T), and the manipulability Jacobian only where J is well conditioned.
    for ax in ("all", "trans", "rot"):
        m_ref = robot.manipulability(Q, axes=ax)
        assert_close(kin.manipulability(Q, axes=ax) ** 2, m_ref**2, 1e-12, f"manipulability^2 {ax}")
        assert abs(kin.manipulability(q, axes=ax) ** 2 - robot.manipulability(q, axes=ax) ** 2) < 1e-12
        ok = robot.cond(Q, axes=ax) < 100  # cond(J J^T) < 1e4: rounding stays below 1e-11
        if ok.any():
            assert_close(kin.jacobm(Q[ok], axes=ax), robot.jacobm(Q[ok], axes=ax), 1e-10, f"jacobm {ax}")


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
@pytest.mark.parametrize("name", list_robots())
def test_backend_matches_reference_on_builtin_robot(backend, name):
    robot = load(name)
    kin = symkin.compile(robot, backend=backend)
    assert kin.backend == backend and kin.n == robot.n
    check_against_reference(kin, robot)


AXES = list(Axis)


@st.composite
def random_robots(draw):
    """ETS robots with revolute, prismatic and flipped joints and arbitrary constant rotations."""
    n = draw(st.integers(1, 7))
    ets: list[ET] = []
    for j in range(n):
        for _ in range(draw(st.integers(0, 3))):
            axis = draw(st.sampled_from(AXES))
            if axis.is_rotation:
                c = draw(
                    st.one_of(
                        st.integers(-4, 4).map(lambda k: Const.pi_times(k) if k else Const.of(0.3)),
                        st.floats(-3.0, 3.0, allow_nan=False).map(Const.of),
                    )
                )
            else:
                c = Const.of(draw(st.floats(-1.0, 1.0, allow_nan=False)))
            ets.append(ET(axis, const=c))
        ets.append(ET(draw(st.sampled_from(AXES)), joint=j, flip=draw(st.booleans())))
    if draw(st.booleans()):
        ets.append(ET(Axis.tz, const=Const.of(0.1)))
    return Robot(ETS(tuple(ets)), name="random")


@settings(max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(robot=random_robots(), seed=st.integers(0, 2**16))
def test_numpy_backend_on_random_robots(robot, seed):
    check_against_reference(symkin.compile(robot, backend="numpy"), robot, seed, batch=5)


@settings(max_examples=4, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(robot=random_robots(), seed=st.integers(0, 2**16))
def test_c_and_casadi_backends_on_random_robots(robot, seed):
    for backend in ("c", "casadi"):
        check_against_reference(symkin.compile(robot, backend=backend), robot, seed, batch=5)


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_bad_q_gets_the_reference_error(backend):
    kin = symkin.compile(load("planar3"), backend=backend)
    with pytest.raises(ConfigurationError, match=r"shape \(3,\) or \(N, 3\)"):
        kin.fkine([0.1, 0.2])
    with pytest.raises(ConfigurationError, match="must be finite"):
        kin.jacob0([0.1, np.nan, 0.2])
    with pytest.raises(ConfigurationError, match="must be finite"):
        kin.hessian0(np.array([[0.1, 0.2, 0.3], [0.1, np.inf, 0.2]]))
    with pytest.raises(ConfigurationError):
        kin.fkine("abc")


@pytest.mark.parametrize("backend", ["c", "numpy", "casadi"])
def test_one_configuration_gets_new_writeable_arrays_and_finite_checks(backend):
    # the single-configuration paths (NumPy: struct-filled np.empty arrays) must still return a
    # fresh, writeable float64 array per call, and reject NaN and inf in an ndarray q, also in a
    # joint the output does not depend on (jacob0 and the UR5's last joint)
    robot = load("ur5")
    kin = symkin.compile(robot, backend=backend)
    q = robot.random_q(seed=3)
    shapes = {
        "fkine": (4, 4),
        "link_poses": (6, 4, 4),
        "jacob0": (6, 6),
        "jacobe": (6, 6),
        "hessian0": (6, 6, 6),
    }
    for name, shape in shapes.items():
        a, b = getattr(kin, name)(q), getattr(kin, name)(q)
        assert a.shape == shape and a.dtype == np.float64 and a.flags.writeable and a.flags.c_contiguous
        assert not np.shares_memory(a, b)
        a[...] = 0.0
        assert_close(b, getattr(robot, name)(q), 1e-10, f"{backend} {name} after writing to another result")
    T, J = kin.fkine_jacob0(q)
    assert T.flags.writeable and J.flags.writeable and not np.shares_memory(T, J)
    for bad in (np.nan, np.inf, -np.inf):
        qb = q.copy()
        qb[5] = bad
        for name in ("fkine", "jacob0"):
            with pytest.raises(ConfigurationError, match="must be finite"):
                getattr(kin, name)(qb)


def test_c_backend_accepts_any_array_like():
    robot = load("ur5")
    kin = symkin.compile(robot, backend="c")
    q = robot.random_q(seed=1)
    for variant in (
        q.tolist(),
        tuple(q),
        q.astype(np.float32),
        q.astype(np.float32).astype(float),
        q[::-1][::-1],
    ):
        assert_close(kin.fkine(variant), robot.fkine(np.asarray(variant, dtype=float)), 1e-12)
    Q = robot.random_q(4, seed=2)
    assert_close(kin.jacob0(Q[:, ::1].T.copy().T), robot.jacob0(Q), 1e-12)  # non-contiguous input
    assert kin.fkine(np.zeros((0, 6))).shape == (0, 4, 4)


def test_casadi_functions_are_named_and_serialisable(tmp_path):
    import casadi as ca

    robot = load("panda")
    kin = symkin.compile(robot, backend="casadi")
    f = kin.functions["jacob0"]
    assert f.name_in() == ["q"] and f.name_out() == ["J"]
    path = tmp_path / "jacob0.casadi"
    f.save(str(path))
    g = ca.Function.load(str(path))
    q = robot.random_q(seed=3)
    assert_close(np.array(g(q)), robot.jacob0(q), 1e-12)
    m = kin.functions["manipulability_all"]
    assert abs(float(m(q)) - robot.manipulability(q)) < 1e-12
