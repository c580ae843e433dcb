"""DH import: ETS structure, exact constants, FK against the textbook DH matrices, table files."""

from __future__ import annotations

import math
from fractions import Fraction
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin import load_dh_file
from symkin.errors import RobotError
from symkin.model.dh import DHLink, angle_const, dh_table_args
from symkin.model.ets import Const
from symkin.model.robot import Robot
from symkin.model.robots import load


def dh_standard(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """The standard DH link matrix (Corke, Robotics, Vision and Control), written out."""
    ct, st_, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st_ * ca, st_ * sa, a * ct], [st_, ct * ca, -ct * sa, a * st_], [0, sa, ca, d], [0, 0, 0, 1]]
    )


def dh_modified(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
    """Craig's modified DH link matrix, written out."""
    ct, st_, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
    return np.array(
        [[ct, -st_, 0, a], [st_ * ca, ct * ca, -sa, -sa * d], [st_ * sa, ct * sa, ca, ca * d], [0, 0, 0, 1]]
    )


def fk_reference(rows: list[dict], q: np.ndarray, modified: bool) -> np.ndarray:
    T = np.eye(4)
    for row, qi in zip(rows, q):
        theta, d = row.get("theta", 0.0), row.get("d", 0.0)
        if row.get("prismatic"):
            d += qi + row.get("offset", 0.0)
        else:
            theta += qi + row.get("offset", 0.0)
        T = T @ (dh_modified if modified else dh_standard)(theta, d, row.get("a", 0.0), row.get("alpha", 0.0))
    return T


def test_standard_and_modified_link_order() -> None:
    link = DHLink(d=0.1, a=0.2, alpha="pi/2", offset="pi/6")
    assert str(Robot.from_dh([link]).ets) == "Rz(pi/6) Rz(q0) tz(0.1) tx(0.2) Rx(pi/2)"
    assert str(Robot.from_dh([link], modified=True).ets) == "tx(0.2) Rx(pi/2) Rz(pi/6) Rz(q0) tz(0.1)"
    p = DHLink(theta="-pi/2", a=0.0203, prismatic=True, offset=0.1)
    assert str(Robot.from_dh([p]).ets) == "Rz(-pi/2) tz(0.1) tz(q0) tx(0.0203)"


def test_zero_constants_are_dropped() -> None:
    assert str(Robot.from_dh([DHLink(), DHLink(a=1)]).ets) == "Rz(q0) Rz(q1) tx(1)"


@pytest.mark.parametrize(
    "value, text",
    [
        (math.pi / 2, "pi/2"),
        (-math.pi / 2, "-pi/2"),
        (math.pi, "pi"),
        (2 * math.pi / 3, "2*pi/3"),
        (math.pi / 12, "pi/12"),
        (0.0, "0"),
        (0.1, "0.1"),
        (1.0000001, "1.0000001"),
        (np.float64(math.pi / 4), "pi/4"),
        ("90deg", "pi/2"),
        (Fraction(1, 3), "1/3"),
        (2, "2"),
    ],
)
def test_angles_snap_to_exact_multiples_of_pi(value: object, text: str) -> None:
    assert str(angle_const(value)) == text


def test_float_lengths_stay_the_decimal_they_print_as() -> None:
    r = Robot.from_dh([DHLink(d=0.089159, a=np.float64(-0.425), alpha=math.pi / 2)])
    assert str(r.ets) == "Rz(q0) tz(0.089159) tx(-0.425) Rx(pi/2)"


dh_value = st.floats(-1.0, 1.0, allow_nan=False)
dh_angle = st.one_of(st.sampled_from([0.0, math.pi / 2, -math.pi / 2, math.pi]), st.floats(-3.0, 3.0))
dh_row = st.fixed_dictionaries(
    {"d": dh_value, "a": dh_value, "alpha": dh_angle, "offset": dh_angle, "prismatic": st.booleans()}
)


@settings(max_examples=40, deadline=None)
@given(rows=st.lists(dh_row, min_size=1, max_size=6), modified=st.booleans(), seed=st.integers(0, 2**16))
def test_fk_matches_the_textbook_dh_matrices(rows: list[dict], modified: bool, seed: int) -> None:
    for row in rows:
        if row["prismatic"]:
            row["theta"] = row.pop("alpha")  # a constant joint angle for prismatic rows
            row["alpha"] = 0.3
    r = Robot.from_dh([DHLink(**row) for row in rows], modified=modified)
    q = np.random.default_rng(seed).uniform(-2, 2, len(rows))
    np.testing.assert_allclose(r.fkine(q), fk_reference(rows, q, modified), atol=1e-12)


def test_base_tool_limits_names_and_configs() -> None:
    links = [
        {"d": 0.3, "alpha": "pi/2", "qlim": (-1, 1), "name": "shoulder"},
        {"type": "P", "qlim": (0, 0.5), "name": "slide"},
    ]
    r = Robot.from_dh(
        links, base="tz(1)", tool="tx(0.1)", configs={"qr": [0.5, 0.2]}, qd_max=[1, 2], name="arm"
    )
    assert str(r.ets) == "tz(1) Rz(q0) tz(0.3) Rx(pi/2) tz(q1) tx(0.1)"
    assert r.joint_names == ("shoulder", "slide")
    np.testing.assert_array_equal(r.qlim, [[-1, 0], [1, 0.5]])
    np.testing.assert_array_equal(r.qr, [0.5, 0.2])
    np.testing.assert_array_equal(r.qd_max, [1, 2])


@pytest.mark.parametrize(
    "links, kwargs, words",
    [
        ([DHLink(theta=0.3)], {}, ["DH link 0", "revolute", "offset="]),
        ([{"d": 1, "lenght": 2}], {}, ["DH link 0", "'lenght'", "valid keys", "alpha"]),
        ([{"type": "X"}], {}, ["DH link 0", "'X'", "'R'", "'P'"]),
        ([DHLink(), DHLink(d=float("nan"))], {}, ["DH link 1 d", "finite"]),
        ([DHLink(alpha="pi/")], {}, ["DH link 0 alpha", "invalid constant"]),
        ([DHLink(a=[1])], {}, ["DH link 0 a", "number"]),
        ([], {}, ["at least one link"]),
        ([DHLink()], {"base": "tz(q)"}, ["base", "constant", "tz(q0)"]),
        ([DHLink()], {"tool": "tz(0.1) foo(1)"}, ["tool", "unknown token 'foo(1)'"]),
        ([{"type": "R", "prismatic": True}], {}, ["contradicts"]),
    ],
)
def test_bad_dh_input_raises_an_actionable_robot_error(links: list, kwargs: dict, words: list[str]) -> None:
    with pytest.raises(RobotError) as info:
        Robot.from_dh(links, **kwargs)
    for w in words:
        assert w in str(info.value)


# ---------------------------------------------------------------------------------------------
# DH table files

STANFORD = """\
# symkin dh: standard
# name: stanford_file
# The Stanford arm: joint 3 prismatic
type  theta  d      a       alpha   qmin     qmax
R     -      0.412  0       -pi/2   -170deg  170deg
R     -      0.154  0       pi/2    -170deg  170deg
P     -pi/2  -      0.0203  0       0.3048   1.27
R     -      0      0       -pi/2   -170deg  170deg
R     -      0      0       pi/2    -90deg   90deg
R     -      0.263  0       0       -170deg  170deg    # the wrist
"""


def test_table_file_matches_the_builtin_stanford_arm(tmp_path: Path) -> None:
    f = tmp_path / "stanford.dh"
    f.write_text(STANFORD)
    r = load_dh_file(f)
    ref = load("stanford")
    assert r.name == "stanford_file"
    assert str(r.ets) == str(ref.ets)
    np.testing.assert_allclose(r.qlim, ref.qlim, atol=1e-15)
    Q = ref.random_q(10, seed=2)
    np.testing.assert_allclose(r.fkine(Q), ref.fkine(Q), atol=1e-12)


def test_table_with_modified_dh_header_comment_configs_and_speeds(tmp_path: Path) -> None:
    text = """
# symkin dh: modified
# config qr: 0 90deg
# qd_max: 1, 2
# type a alpha d
R 0 0 0.5
R 1 pi/2 0
"""
    f = tmp_path / "two_link.txt"
    f.write_text(text)
    r = load_dh_file(str(f))
    assert r.name == "two_link"
    assert str(r.ets) == "Rz(q0) tz(0.5) tx(1) Rx(pi/2) Rz(q1)"
    np.testing.assert_allclose(r.qr, [0, math.pi / 2])
    np.testing.assert_array_equal(r.qd_max, [1, 2])


def test_builtin_ur5_from_a_table_agrees() -> None:
    text = """# symkin dh: standard
type d a alpha
R 0.089159 0 pi/2
R 0 -0.425 0
R 0 -0.39225 0
R 0.10915 0 pi/2
R 0.09465 0 -pi/2
R 0.0823 0 0
"""
    r = _parse_dh_table(text, "ur5.dh")
    assert isinstance(r, Robot)
    Q = load("ur5").random_q(10, seed=3)
    np.testing.assert_allclose(r.fkine(Q), load("ur5").fkine(Q), atol=1e-12)


@pytest.mark.parametrize(
    "text, words",
    [
        ("type d\nR 0\n", ["t.dh:1", "# symkin dh: standard", "modified"]),
        ("# symkin dh: craig\ntype d\nR 0\n", ["t.dh:1", "'# symkin dh: craig'"]),
        ("# symkin dh: standard\ntype d lenght\nR 0 1\n", ["t.dh:2", "unknown column", "'lenght'", "alpha"]),
        ("# symkin dh: standard\nd a\n0 1\n", ["t.dh:2", "'type' column"]),
        ("# symkin dh: standard\ntype d a\nR 0 1\nR 0\n", ["t.dh:4", "2 cells", "3 columns"]),
        ("# symkin dh: standard\ntype d a\nR 0 1\nQ 0 1\n", ["t.dh:4", "'Q'", "R (revolute)"]),
        ("# symkin dh: standard\ntype alpha\nR pi/\n", ["t.dh:3", "'alpha'", "invalid constant"]),
        ("# symkin dh: standard\ntype qmin qmax\nR 1 -1\n", ["t.dh:3", "qmin 1 is greater than qmax -1"]),
        ("# symkin dh: standard\ntype qmin qmax\nR 1 -\n", ["t.dh:3", "both qmin and qmax"]),
        ("# symkin dh: standard\ntype d\n", ["no DH rows"]),
        ("# symkin dh: standard\n# config qr: 1 2 3\ntype d\nR 0\n", ["t.dh:2", "config qr", "1 values"]),
        ("# symkin dh: standard\ntype theta\nR 0.5\n", ["t.dh:3", "revolute", "offset column"]),
    ],
)
def test_bad_tables_name_the_file_line_and_the_fix(text: str, words: list[str]) -> None:
    with pytest.raises(RobotError) as info:
        _parse_dh_table(text, "t.dh")
    for w in words:
        assert w in str(info.value)


def test_missing_table_file_is_a_robot_error(tmp_path: Path) -> None:
    with pytest.raises(RobotError, match="cannot read DH table"):
        load_dh_file(tmp_path / "nope.dh")


def test_robot_from_dh_is_the_robot_classmethod() -> None:
    r = Robot.from_dh([DHLink(a=1), DHLink(a=1)], name="p2")
    assert str(r.ets) == str(load("planar2").ets) and r.name == "p2"
    assert angle_const(Const.of("pi/3")) == Const.pi_times(Fraction(1, 3))


def _parse_dh_table(text, filename="<dh table>"):
    return Robot(**dh_table_args(text, filename))
