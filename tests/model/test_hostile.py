"""Hostile robot descriptions end in a clear error (issue 12, items 5, 6, 9; issue 23, item 9):
long and deeply nested constants, values beyond the range of a double or of meaningful lengths and
angles, huge or tiny URDF axes, DOCTYPE/entities in URDF. These inputs took 13 s to minutes (regex
backtracking, a 10**999999999 integer, billion laughs) before the fixes; the tests assert the
errors, not a wall time (how long a parse takes belongs to no test)."""

from __future__ import annotations

import numpy as np
import pytest

import symkin
from symkin import ETS, Robot
from symkin.errors import ETSParseError, RobotError, URDFError
from symkin.model.dh import DHLink
from symkin.model.dh import dh_table_args as parse_dh_table
from symkin.model.ets import MAX_CONST_CHARS, Const


@pytest.mark.parametrize(
    "arg",
    [
        "1" * 1000,  # took 13-33 s (backtracking in the deg regex)
        "1" * 990 + "deg",
        "1" * 500 + " " * 400 + "x",
        "1." * 450,
        " " * 100_000 + "x",  # the joint pattern backtracked too (20 s)
        "-" + " " * 100_000 + "x",
        "1" * 5000,
    ],
)
def test_long_constants_are_refused_or_parsed_in_linear_time(arg):
    with pytest.raises(ETSParseError):
        ETS.parse(f"Rz(q) tx({arg})")
    assert ETS.parse("Rz(q) tx(-" + " " * 100_000 + "q)").n == 2  # a valid flipped joint


def test_constant_length_cap_and_exact_long_decimals():
    exact = "0.1000000000000000055511151231257827021181583404541015625"  # 0.1 as a double, exactly
    assert str(ETS.parse(f"tx({exact})")) == "tx(0.1)"
    with pytest.raises(ETSParseError, match="more than the 1000"):
        ETS.parse("tx(" + "0" * MAX_CONST_CHARS + "1)")


@pytest.mark.parametrize(
    ("arg", "why"),
    [
        ("-" * 3000 + "1", "more than"),  # raw RecursionError before
        ("-" * 990 + "1", ""),
        ("(" * 150 + "1" + ")" * 150, ""),
        ("1" + "+1" * 499, ""),
        ("1e308*10", "double"),  # raw OverflowError before
        ("9" * 400, "double"),
        ("9" * 400 + "*pi", "double"),
        ("atan2(" + "9" * 400 + ", 1)", "double"),
    ],
)
def test_deep_or_huge_constants_give_a_parse_error(arg, why):
    try:
        ets = ETS.parse(f"Rz(q) tx({arg})")
    except ETSParseError as exc:
        assert why in str(exc)
    else:  # accepted: then it is an ordinary, finite constant
        robot = Robot(ets)
        assert abs(robot.fkine([0.3])[0, 3]) < 1e300


def test_huge_joint_index_is_a_parse_error():
    for text in ("Rz(q" + "9" * 5000 + ")", "Rz(q99999999999)", "Rz(-q1234567890)"):
        with pytest.raises(ETSParseError):
            ETS.parse(text)


def test_in_range_constant_that_overflows_later_is_refused():
    assert ETS.parse("tx(1e308*10/100)").ets[0].const.value == pytest.approx(1e307)
    for value in (10**400, 2**1100):
        with pytest.raises(RobotError, match="range of a double"):
            Const.of(value)
        with pytest.raises(RobotError, match="range of a double"):
            symkin.Robot.from_dh([DHLink(d=value)])
    with pytest.raises(RobotError, match="range of a double"):
        symkin.Robot.from_dh([DHLink(d=1.5e308, offset=1.5e308, prismatic=True)])


def test_dh_table_cells_use_the_same_guards():
    head = "# symkin dh: standard\ntype d a alpha\n"
    with pytest.raises(RobotError, match=":3: column 'd'"):
        parse_dh_table(head + "R " + "1" * 1000 + " 0 0\n")
    with pytest.raises(RobotError, match="double"):
        parse_dh_table(head + "R 1e308*10 0 0\n")
    with pytest.raises(RobotError):
        parse_dh_table(head + "R " + "-" * 3000 + "1 0 0\n")


URDF = """<robot name="{name}"><link name="a"/><link name="b"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="{xyz}"/>
<axis xyz="0 0 1"/><limit lower="{lower}" upper="1" velocity="1"/></joint></robot>"""


def _urdf(name: str = "r", xyz: str = "0 0 0.1", lower: str = "-1") -> str:
    return URDF.format(name=name, xyz=xyz, lower=lower)


def test_urdf_with_doctype_or_entities_is_refused():
    entity = '<?xml version="1.0"?><!DOCTYPE robot [<!ENTITY x "evil">]>' + _urdf(name="&x;")
    with pytest.raises(URDFError, match="DOCTYPE"):
        Robot.from_urdf(entity)  # the entity used to become the robot's name
    laughs = (
        '<?xml version="1.0"?><!DOCTYPE lolz [<!ENTITY lol "lol">'
        + "".join(
            f'<!ENTITY lol{i} "{("&lol" + (str(i - 1) if i > 1 else "") + ";") * 10}">' for i in range(1, 10)
        )
        + "]>"
        + _urdf(name="&lol9;")
    )
    with pytest.raises(URDFError, match="DOCTYPE"):
        Robot.from_urdf(laughs)
    external = '<?xml version="1.0"?><!DOCTYPE robot SYSTEM "http://example.invalid/robot.dtd">' + _urdf()
    with pytest.raises(URDFError, match="DOCTYPE"):
        Robot.from_urdf(external)
    assert Robot.from_urdf('<?xml version="1.0"?><!-- <!DOCTYPE in a comment -->' + _urdf()).n == 1


@pytest.mark.parametrize(
    ("xyz", "lower", "words"),
    [
        ("1e400 0 0", "-1", "range of a double"),  # raw OverflowError before
        ("0 0 0", "-1e400", "range of a double"),
        ("1e999999999 0 0", "-1", "range of a double"),  # built a 10**999999999 integer
        ("0x10 0 0", "-1", "not a number"),
        ("1/3 0 0", "-1", "not a number"),
        ("1" * 2000 + " 0 0", "-1", "not a number"),
        ("nan 0 0", "-1", "finite"),
    ],
)
def test_urdf_numbers_are_checked(xyz, lower, words):
    with pytest.raises(URDFError, match=words):
        Robot.from_urdf(_urdf(xyz=xyz, lower=lower))


def test_urdf_tiny_numbers_and_files_that_are_not_utf8(tmp_path):
    assert Robot.from_urdf(_urdf(xyz="1e-999999999 0 0.1")).ets.n == 1  # below the smallest double: 0
    bad = tmp_path / "latin1.urdf"
    bad.write_bytes(_urdf(name="caf\xe9").encode("latin-1"))
    with pytest.raises(URDFError, match="not UTF-8"):
        Robot.from_urdf(bad)


def test_robot_attributes_are_validated_with_robot_errors():
    import numpy as np

    for kwargs in (
        {"qlim": [["a"], [1]]},
        {"qlim": [[1j], [1]]},
        {"configs": {"home": ["x"]}},
        {"configs": {"home": [1e300]}},  # compiled kinematics refuse |q| > 1e15
        {"qd_max": ["fast"]},
        {"joint_names": [1]},
    ):
        with pytest.raises(RobotError):
            Robot.from_ets("Rz(q)", **kwargs)
    with pytest.raises(RobotError, match="within"):
        Robot.from_poe(np.eye(4), [[0, 0, 1, 1e300, 0, 0]])  # raw OverflowError before
    with pytest.raises(RobotError, match="too large"):
        Robot.from_poe(np.eye(4), [[0, 0, 1, 10**400, 0, 0]])


def test_random_configurations_with_infinite_limits():
    import numpy as np

    robot = Robot.from_ets("Rz(q) tx(1) tz(q)", qlim=[[-np.inf, 0.5], [np.inf, np.inf]])
    Q = robot.random_q(500, seed=0)  # raised OverflowError ("Range exceeds valid bounds")
    assert np.isfinite(Q).all() and (Q[:, 0] >= -np.pi).all() and (Q[:, 0] <= np.pi).all()
    assert (Q[:, 1] >= 0.5).all() and (Q[:, 1] <= 2.5).all()
    assert robot.within_limits(Q).all()


def test_urdf_text_with_a_byte_order_mark_and_paths_with_nul():
    """Found by the fuzz suite: a BOM made XML text look like a path; a NUL in a path raised ValueError."""
    assert Robot.from_urdf("\ufeff" + _urdf()).n == 1
    with pytest.raises(URDFError, match="cannot read"):
        Robot.from_urdf("robot\x00.urdf")


# issue 23, item 9: numbers that are doubles but break the kinematics, in both URDF readers

TWO_JOINTS = """<robot name="r"><link name="a"/><link name="b"/><link name="c"/>
<joint name="j" type="revolute"><parent link="a"/><child link="b"/><origin xyz="{xyz}" rpy="{rpy}"/>
<axis xyz="{axis}"/><limit lower="-1" upper="1" velocity="1"/></joint>
<joint name="k" type="revolute"><parent link="b"/><child link="c"/><origin xyz="0 0.2 0.1"/>
<axis xyz="0 0 1"/>{mimic}<limit lower="-1" upper="1" velocity="1"/></joint></robot>"""


def _two(xyz="0 0 0.1", rpy="0 0 0", axis="0 0 1", mimic=""):
    return TWO_JOINTS.format(xyz=xyz, rpy=rpy, axis=axis, mimic=mimic)


@pytest.mark.parametrize(
    ("axis", "unit"),
    [
        ("1e200 0 0", "1 0 0"),  # raw OverflowError from the norm before
        ("0 -1e300 0", "0 -1 0"),
        ("3e200 4e200 0", "0.6 0.8 0"),
        ("1e200 2e200 2e200", "1 2 2"),
        ("1e-300 1e-300 1e-300", "1 1 1"),  # was "the zero vector"
        ("0 1e-320 -1e-320", "0 1 -1"),
    ],
)
def test_urdf_axes_of_any_double_size_are_directions(axis, unit):
    from symkin import Tree

    q = np.array([0.4, -0.7])
    want = Robot.from_urdf(_two(axis=unit))
    got = Robot.from_urdf(_two(axis=axis))
    np.testing.assert_allclose(got.fkine(q), want.fkine(q), atol=1e-12)
    tree = Tree.from_urdf(_two(axis=axis))
    np.testing.assert_allclose(tree.fkine(q, "c"), want.fkine(q), atol=1e-12)


@pytest.mark.parametrize(
    ("kwargs", "words"),
    [
        ({"xyz": "1e308 0 0"}, "joint 'j' origin xyz contains '1e308'"),  # two of them made inf poses
        ({"xyz": "0 -2e15 0"}, "joint 'j' origin xyz contains '-2e15'"),
        ({"rpy": "0 1e20 0"}, "joint 'j' origin rpy contains '1e20'"),  # no meaningful double angle
        ({"mimic": '<mimic joint="j" multiplier="1e308"/>'}, "joint 'k' mimic multiplier contains '1e308'"),
        ({"mimic": '<mimic joint="j" offset="-1e16"/>'}, "joint 'k' mimic offset contains '-1e16'"),
    ],
)
def test_urdf_lengths_angles_and_mimics_beyond_1e15_are_refused(kwargs, words):
    from symkin import Tree

    text = _two(**kwargs)
    readers = (Tree.from_urdf,) if "mimic" in kwargs else (Robot.from_urdf, Tree.from_urdf)
    for read in readers:
        with pytest.raises(URDFError, match="within \\+-1e15") as info:
            read(text)
        assert words in str(info.value)
    assert Robot.from_urdf(_two(xyz="1e15 0 -1e15", rpy="1e15 0 0")).n == 2  # the bound itself is fine


def test_composed_mimic_multipliers_stay_within_range():
    from symkin import Tree

    chain = _two(mimic='<mimic joint="j" multiplier="1e10"/>').replace(
        "</robot>",
        '<link name="d"/><joint name="l" type="revolute"><parent link="c"/><child link="d"/>'
        '<axis xyz="0 0 1"/><mimic joint="k" multiplier="1e10"/></joint></robot>',
    )
    with pytest.raises(URDFError, match="'l' follows l -> k -> j with the composed multiplier 1e\\+20"):
        Tree.from_urdf(chain)  # a raw OverflowError for 1e200 x 1e200 before
    assert Tree.from_urdf(chain.replace('multiplier="1e10"', 'multiplier="1e5"')).n == 1
