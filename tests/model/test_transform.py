"""Tool and base transforms: SE(3) matrices split into exact translations and rotations, every
accepted form, FK of the new robot against T_base @ fkine @ T_tool, and clear errors."""

from __future__ import annotations

import math

import numpy as np
import pytest

import symkin
from symkin.errors import RobotError
from symkin.model.ets import ETS
from symkin.model.transform import constant_ets, length_const, se3_ets, type_name


def rot(axis: str, a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    R = {"x": [[1, 0, 0], [0, c, -s], [0, s, c]], "y": [[c, 0, s], [0, 1, 0], [-s, 0, c]]}.get(
        axis, [[c, -s, 0], [s, c, 0], [0, 0, 1]]
    )
    T = np.eye(4)
    T[:3, :3] = R
    return T


def trans(x: float, y: float, z: float) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = [x, y, z]
    return T


def matrix_of(ets: list) -> np.ndarray:
    """The constant transform of a list of constant ETs, by the numeric reference."""
    return symkin.Robot(ETS(tuple(ets)) * ETS.parse("Rz(q0)")).fkine([0.0])


@pytest.mark.parametrize(
    "T, text",
    [
        (trans(0, 0, 0.333) @ rot("x", -math.pi / 2), "tz(0.333) Rx(-pi/2)"),
        (trans(0.0825, 0, 0) @ rot("x", math.pi / 2), "tx(0.0825) Rx(pi/2)"),
        (rot("z", -math.pi / 4), "Rz(-pi/4)"),
        (rot("y", 2 * math.pi / 3), "Ry(2*pi/3)"),  # one axis: one rotation, not three
        (
            trans(0.1, -0.2, 0.3) @ rot("z", math.pi / 2) @ rot("x", math.pi / 2),
            "tx(0.1) ty(-0.2) tz(0.3) Rz(pi/2) Rx(pi/2)",
        ),
        (np.eye(4), ""),
    ],
)
def test_float_matrices_become_exact_constants(T: np.ndarray, text: str) -> None:
    ets = se3_ets(T)
    assert str(ETS(tuple(ets))) == text
    np.testing.assert_allclose(matrix_of(ets), T, atol=1e-15)


def test_general_rotations_are_split_into_roll_pitch_yaw_and_reproduce_the_matrix() -> None:
    rng = np.random.default_rng(0)
    for _ in range(50):
        T = trans(*rng.uniform(-1, 1, 3)) @ rot("z", rng.uniform(-3, 3)) @ rot("y", rng.uniform(-1.5, 1.5))
        T = T @ rot("x", rng.uniform(-3, 3))
        ets = se3_ets(T)
        np.testing.assert_allclose(matrix_of(ets), T, atol=1e-14)
    # gimbal lock: pitch = pi/2 exactly
    T = trans(0, 0, 0.5) @ rot("z", 0.3) @ rot("y", math.pi / 2) @ rot("x", 0.2)
    np.testing.assert_allclose(matrix_of(se3_ets(T)), T, atol=1e-14)


def test_float_noise_snaps_but_real_values_stay() -> None:
    # products of floats leave noise: cos(pi/2) = 6e-17, 0.26 + 0.41183 = 0.6718299999999999
    assert str(length_const(0.6718299999999999)) == "0.67183"
    assert length_const(6.123233995736766e-17).is_zero
    assert str(length_const(0.123456789012345)) == "0.123456789012345"  # 15 digits are kept
    T = trans(0, -0.316, 6.1e-17) @ rot("x", math.pi / 2 + 3e-12)
    assert str(ETS(tuple(se3_ets(T)))) == "ty(-0.316) Rx(pi/2)"
    T = rot("x", 0.3)  # not near a multiple of pi/12: the float's exact decimal
    assert str(ETS(tuple(se3_ets(T)))) == "Rx(0.3)"


@pytest.mark.parametrize(
    "bad, match",
    [
        (np.eye(3), "4x4"),
        (np.diag([1.0, 1.0, 1.0, 2.0]), "bottom row"),
        (np.diag([1.0, 2.0, 1.0, 1.0]), "rotation"),
        (np.diag([1.0, 1.0, -1.0, 1.0]), "rotation"),  # a reflection
        (np.full((4, 4), np.nan), "NaN"),
    ],
)
def test_bad_matrices_are_refused(bad: np.ndarray, match: str) -> None:
    with pytest.raises(RobotError, match=match):
        se3_ets(bad, "tool")


def test_every_form_of_a_transform_gives_the_same_constants() -> None:
    T = trans(0, 0, 0.1) @ rot("x", math.pi / 2)
    forms = [
        "tz(0.1) Rx(pi/2)",
        "0 0 0.1 pi/2 0 0",
        "0 0 0.1 90deg 0 0",
        " ".join(repr(float(v)) for v in T.ravel()),
        T,
        T.tolist(),
        ETS.parse("tz(0.1) Rx(pi/2)"),
        list(ETS.parse("tz(0.1) Rx(pi/2)")),
    ]
    for f in forms:
        assert str(ETS(tuple(constant_ets(f, "tool")))) == "tz(0.1) Rx(pi/2)", f
    assert str(ETS(tuple(constant_ets("0.1 0.2 0.3", "tool")))) == "tx(0.1) ty(0.2) tz(0.3)"


def test_bad_forms_name_what_is_wrong() -> None:
    with pytest.raises(RobotError, match="constant, but contains the joint"):
        constant_ets("tz(0.1) Rz(q)", "tool")
    with pytest.raises(RobotError, match="got 4 numbers"):
        constant_ets("1 2 3 4", "tool")
    with pytest.raises(RobotError, match="tool: invalid constant"):
        constant_ets("0 0 zz", "tool")
    with pytest.raises(RobotError, match="not decimal.Decimal"):
        import decimal

        constant_ets(decimal.Decimal(1), "tool")


@pytest.mark.parametrize("name", ["ur5", "panda", "stanford"])
def test_with_tool_and_base_compose_with_fk(name: str) -> None:
    r = symkin.load(name)
    Tt = trans(0.01, -0.02, 0.15) @ rot("z", 0.4) @ rot("y", -0.7)
    Tb = trans(1.0, 0.5, 0.2) @ rot("z", math.pi / 2)
    new = r.with_tool(Tt).with_base(Tb)
    Q = r.random_q(10, seed=1)
    np.testing.assert_allclose(new.fkine(Q), Tb @ r.fkine(Q) @ Tt, atol=1e-13)
    # the Jacobian of the new robot against finite differences of its own FK (independent of r's)
    q, h = Q[0], 1e-6
    E = np.eye(r.n) * h
    dp = (new.fkine(q + E)[:, :3, 3] - new.fkine(q - E)[:, :3, 3]) / (2 * h)
    np.testing.assert_allclose(new.jacob0(q)[:3], dp.T, atol=1e-8)
    assert new.qlim is not r.qlim and np.array_equal(new.qlim, r.qlim)
    assert new.joint_names == r.joint_names and set(new.configs) == set(r.configs)
    assert "tool" in new.source and "base" in new.source
    assert r.with_tool(None) is r and r.with_tool(np.eye(4)) is r


def test_exact_tool_text_stays_exact_and_compiles() -> None:
    r = symkin.load("planar2").with_tool("tz(0.1) Rx(pi/2)")
    assert str(r.ets).endswith("tx(1) tz(0.1) Rx(pi/2)")
    kin = symkin.compile(r, backend="numpy")
    q = np.array([0.3, -0.5])
    np.testing.assert_allclose(
        kin.fkine(q), symkin.load("planar2").fkine(q) @ trans(0, 0, 0.1) @ rot("x", math.pi / 2), atol=1e-15
    )


def test_type_errors_name_the_full_type() -> None:
    assert type_name(np.eye(2)) == "numpy.ndarray" and type_name(3) == "int"
    with pytest.raises(RobotError, match="not numpy.ndarray"):
        symkin.Robot.from_ets(np.eye(4))  # type: ignore[arg-type]
    with pytest.raises(RobotError, match="ets must be a symkin.ETS, not list"):
        symkin.Robot([1, 2])  # type: ignore[arg-type]
