"""Compiled kinematics offer cond, jacobs, jacobb and jacob0_dot on every backend, checked against
finite differences and the numeric reference; and a notebook view."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin.errors import ConfigurationError
from tests.conftest import assert_close

BACKENDS = ["c", "numpy", "casadi"]
H = 1e-6


@pytest.fixture(scope="module", params=BACKENDS)
def kin(request):  # noqa: ANN001, ANN201
    return symkin.compile("panda", backend=request.param)


def test_jacob0_dot_is_the_time_derivative_of_the_jacobian(kin) -> None:  # noqa: ANN001
    r = kin.robot
    rng = np.random.default_rng(0)
    for q in r.random_q(4, seed=1):
        qd = rng.uniform(-1, 1, r.n)
        fd = (kin.jacob0(q + H * qd) - kin.jacob0(q - H * qd)) / (2 * H)  # d/dt J(q + t qd) at t = 0
        Jd = kin.jacob0_dot(q, qd)
        assert Jd.shape == (6, r.n)
        assert_close(Jd, fd, 1e-8, f"{kin.backend} jacob0_dot vs finite differences")
        assert_close(Jd, r.jacob0_dot(q, qd), 1e-12, f"{kin.backend} jacob0_dot vs reference")
    Q, Qd = r.random_q(5, seed=2), rng.uniform(-1, 1, (5, r.n))
    batch = kin.jacob0_dot(Q, Qd)
    assert batch.shape == (5, 6, r.n)
    assert_close(batch, np.stack([kin.jacob0_dot(q, v) for q, v in zip(Q, Qd)]), 1e-14, "batch")
    with pytest.raises(ConfigurationError, match="qd"):
        kin.jacob0_dot(Q, Qd[:3])
    with pytest.raises(ConfigurationError, match="qd"):
        kin.jacob0_dot(Q[0], np.ones(3))


def test_reference_jacob0_dot_against_finite_differences() -> None:
    for name in ("ur5", "stanford", "cobra600"):
        r = symkin.load(name)
        q, qd = r.random_q(seed=3), np.linspace(-1, 1, r.n)
        fd = (r.jacob0(q + H * qd) - r.jacob0(q - H * qd)) / (2 * H)
        assert_close(r.jacob0_dot(q, qd), fd, 1e-8, name)


def test_space_and_body_jacobians(kin) -> None:  # noqa: ANN001
    r = kin.robot
    Q = r.random_q(4, seed=4)
    assert_close(kin.jacobs(Q), r.jacobs(Q), 1e-12, "jacobs")
    assert_close(kin.jacobb(Q), r.jacobb(Q), 1e-12, "jacobb")
    q = Q[0]
    assert_close(kin.jacobs(q), r.jacobs(q), 1e-12, "jacobs one")
    # independent: the body twist of a joint rate from finite differences, T^-1 dT/dq_j = [w; v]^
    T = r.fkine(q)
    for j in range(r.n):
        e = np.zeros(r.n)
        e[j] = H
        dT = (r.fkine(q + e) - r.fkine(q - e)) / (2 * H)
        S = np.linalg.inv(T) @ dT
        twist = [S[2, 1], S[0, 2], S[1, 0], *S[:3, 3]]
        assert_close(kin.jacobb(q)[:, j], twist, 1e-8, f"jacobb column {j}")
        Ss = dT @ np.linalg.inv(T)  # space twist
        assert_close(kin.jacobs(q)[:, j], [Ss[2, 1], Ss[0, 2], Ss[1, 0], *Ss[:3, 3]], 1e-8, f"jacobs {j}")


def test_condition_number(kin) -> None:  # noqa: ANN001
    r = kin.robot
    Q = r.random_q(4, seed=5)
    assert_close(kin.cond(Q), r.cond(Q), 1e-9, "cond batch")
    q = Q[0]
    s = np.linalg.svd(r.jacob0(q)[:3], compute_uv=False)
    assert kin.cond(q, axes="trans") == pytest.approx(s[0] / s[-1], rel=1e-9)
    assert isinstance(kin.cond(q), float)
    assert kin.cond(np.zeros(r.n)) > 1e6 or np.isinf(kin.cond(np.zeros(r.n)))  # singular at qz


def test_planar_arm_is_singular_when_straight() -> None:
    kin = symkin.compile("planar2", backend="numpy")
    assert np.isinf(kin.cond([0.0, 0.0], axes="trans"))  # 2 joints, 3 task rows


def test_notebook_view_of_compiled_kinematics(kin) -> None:  # noqa: ANN001
    md = kin._repr_markdown_()
    assert f"compiled for the **{kin.backend}** backend" in md
    assert "| q0 | panda\\_joint1 | revolute | Rz |" in md and "jacob0_dot" in md


def test_a_result_does_not_change_at_the_next_call(kin) -> None:  # noqa: ANN001
    """The CasADi backend evaluates into one shared buffer: what it returns must be a copy."""
    r = kin.robot
    q1, q2 = r.random_q(2, seed=6)
    T1, J1 = kin.fkine(q1), kin.jacob0(q1)
    kin.fkine(q2), kin.jacob0(q2)
    assert_close(T1, r.fkine(q1), 1e-12, "T kept")
    assert_close(J1, r.jacob0(q1), 1e-12, "J kept")


def test_named_configurations_as_on_the_robot(kin) -> None:  # noqa: ANN001
    """Issue 36 item 14: kin.qr, kin.qz and kin.configs on every backend, as the Robot has them (a
    ported ``robot.qr`` works on compiled kinematics); an unknown name lists the configurations."""
    import pickle

    r = kin.robot
    assert sorted(kin.configs) == sorted(r.configs) == ["qr", "qz"]
    for name in ("qr", "qz"):
        np.testing.assert_array_equal(getattr(kin, name), r.configs[name])
    assert_close(kin.fkine(kin.qr), r.fkine(r.qr), 1e-14, "fkine at qr")
    with pytest.raises(
        AttributeError, match=r"no attribute or configuration 'qready'; configurations: \['qr', 'qz'\]"
    ):
        kin.qready  # noqa: B018
    assert not hasattr(kin, "_private") and getattr(kin, "source", None) is None
    np.testing.assert_array_equal(pickle.loads(pickle.dumps(kin)).qr, r.qr)


def test_a_compiled_tree_has_its_configurations() -> None:
    from tests.model.tree_urdfs import QUADRUPED

    tree = symkin.Tree.from_urdf(QUADRUPED)
    kin = symkin.compile(tree, backend="numpy")
    assert sorted(kin.configs) == ["qz"]
    np.testing.assert_array_equal(kin.qz, np.zeros(tree.n))
