"""URDF import: agreement with the DH/ETS built-ins, arbitrary axes against Rodrigues' formula,
exact constants, limits, and actionable errors."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from symkin.errors import RobotError, URDFError
from symkin.model.robot import Robot
from symkin.model.robots import load

HALF_PI = "1.570796326794897"


def joint(
    name: str,
    parent: str,
    child: str,
    kind: str = "revolute",
    xyz: str = "0 0 0",
    rpy: str = "0 0 0",
    axis: str | None = "0 0 1",
    limit: str = 'lower="-3" upper="3" velocity="2" effort="1"',
    extra: str = "",
) -> str:
    ax = f'<axis xyz="{axis}"/>' if axis is not None else ""
    lim = f"<limit {limit}/>" if limit else ""
    return (
        f'<joint name="{name}" type="{kind}"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/>{ax}{lim}{extra}</joint>'
    )


def urdf(links: list[str], joints: list[str], name: str = "test") -> str:
    body = "\n  ".join([f'<link name="{n}"/>' for n in links] + joints)
    return f'<?xml version="1.0"?>\n<robot name="{name}">\n  {body}\n</robot>\n'


# The UR5 written as a URDF from its published standard DH table (joint i's origin is link i-1's
# constant part tz(d) tx(a) Rx(alpha): xyz = (a, 0, d), rpy = (alpha, 0, 0)).
UR5 = urdf(
    ["base", "l1", "l2", "l3", "l4", "l5", "l6", "tool0"],
    [
        joint(
            "shoulder_pan",
            "base",
            "l1",
            limit='lower="-6.283185" upper="6.283185" velocity="3.14" effort="1"',
        ),
        joint("shoulder_lift", "l1", "l2", xyz="0 0 0.089159", rpy=f"{HALF_PI} 0 0"),
        joint("elbow", "l2", "l3", xyz="-0.425 0 0"),
        joint("wrist_1", "l3", "l4", xyz="-0.39225 0 0"),
        joint("wrist_2", "l4", "l5", xyz="0 0 0.10915", rpy=f"{HALF_PI} 0 0"),
        joint("wrist_3", "l5", "l6", xyz="0 0 0.09465", rpy=f"-{HALF_PI} 0 0", kind="continuous"),
        joint("tool0_fixed", "l6", "tool0", kind="fixed", xyz="0 0 0.0823", axis=None, limit=""),
    ],
    name="ur5_urdf",
)

# Franka Emika's panda_arm_hand URDF (franka_description), kinematic elements only.
PANDA_LINKS = [f"panda_link{i}" for i in range(9)] + ["panda_hand", "panda_leftfinger", "panda_rightfinger"]
PANDA = urdf(
    PANDA_LINKS,
    [
        joint(
            "panda_joint1",
            "panda_link0",
            "panda_link1",
            xyz="0 0 0.333",
            limit='effort="87" lower="-2.8973" upper="2.8973" velocity="2.1750"',
        ),
        joint(
            "panda_joint2",
            "panda_link1",
            "panda_link2",
            rpy=f"-{HALF_PI} 0 0",
            limit='effort="87" lower="-1.7628" upper="1.7628" velocity="2.1750"',
        ),
        joint(
            "panda_joint3",
            "panda_link2",
            "panda_link3",
            xyz="0 -0.316 0",
            rpy=f"{HALF_PI} 0 0",
            limit='effort="87" lower="-2.8973" upper="2.8973" velocity="2.1750"',
        ),
        joint(
            "panda_joint4",
            "panda_link3",
            "panda_link4",
            xyz="0.0825 0 0",
            rpy=f"{HALF_PI} 0 0",
            limit='effort="87" lower="-3.0718" upper="-0.0698" velocity="2.1750"',
        ),
        joint(
            "panda_joint5",
            "panda_link4",
            "panda_link5",
            xyz="-0.0825 0.384 0",
            rpy=f"-{HALF_PI} 0 0",
            limit='effort="12" lower="-2.8973" upper="2.8973" velocity="2.6100"',
        ),
        joint(
            "panda_joint6",
            "panda_link5",
            "panda_link6",
            rpy=f"{HALF_PI} 0 0",
            limit='effort="12" lower="-0.0175" upper="3.7525" velocity="2.6100"',
        ),
        joint(
            "panda_joint7",
            "panda_link6",
            "panda_link7",
            xyz="0.088 0 0",
            rpy=f"{HALF_PI} 0 0",
            limit='effort="12" lower="-2.8973" upper="2.8973" velocity="2.6100"',
        ),
        joint(
            "panda_joint8", "panda_link7", "panda_link8", kind="fixed", xyz="0 0 0.107", axis=None, limit=""
        ),
        joint(
            "panda_hand_joint",
            "panda_link8",
            "panda_hand",
            kind="fixed",
            rpy="0 0 -0.785398163397",
            axis=None,
            limit="",
        ),
        joint(
            "panda_finger_joint1",
            "panda_hand",
            "panda_leftfinger",
            kind="prismatic",
            xyz="0 0 0.0584",
            axis="0 1 0",
            limit='effort="20" lower="0.0" upper="0.04" velocity="0.2"',
        ),
        joint(
            "panda_finger_joint2",
            "panda_hand",
            "panda_rightfinger",
            kind="prismatic",
            xyz="0 0 0.0584",
            axis="0 -1 0",
            limit='effort="20" lower="0.0" upper="0.04" velocity="0.2"',
            extra='<mimic joint="panda_finger_joint1"/>',
        ),
    ],
    name="panda",
)


def test_ur5_urdf_gives_the_same_ets_and_fk_as_the_published_dh() -> None:
    r = Robot.from_urdf(UR5)
    ref = load("ur5")
    assert str(r.ets) == str(ref.ets)  # 1.570796326794897 snapped to pi/2; zero constants dropped
    Q = ref.random_q(20, seed=5)
    np.testing.assert_allclose(r.fkine(Q), ref.fkine(Q), atol=1e-12)
    assert r.name == "ur5_urdf"
    assert r.joint_names == ("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3")
    np.testing.assert_allclose(r.qlim[:, 5], [-math.pi, math.pi])  # continuous joint
    np.testing.assert_allclose(r.qlim[:, 0], [-6.283185, 6.283185])
    np.testing.assert_array_equal(r.qd_max, [3.14, 2, 2, 2, 2, 2])


def test_panda_urdf_to_the_hand_plus_the_tool_offset_is_the_builtin_panda() -> None:
    r = Robot.from_urdf(PANDA, end_link="panda_hand")
    ref = load("panda")
    tool = np.eye(4)
    tool[2, 3] = 0.1034  # the URDF ends at panda_hand; the built-in at the tool point 0.1034 m further
    Q = ref.random_q(20, seed=6)
    np.testing.assert_allclose(r.fkine(Q) @ tool, ref.fkine(Q), atol=1e-12)
    np.testing.assert_array_equal(r.qlim, ref.qlim)
    np.testing.assert_array_equal(r.qd_max, ref.qd_max)
    assert r.joint_names == ref.joint_names
    assert "Rz(-pi/4)" in str(r.ets)  # -0.785398163397 is within snap_tol of -pi/4


def test_panda_urdf_to_the_left_finger_includes_the_prismatic_finger() -> None:
    r = Robot.from_urdf(PANDA, end_link="panda_leftfinger")
    assert r.n == 8 and r.ets.structure == "RRRRRRRP"
    assert str(r.ets).endswith("tz(0.0584) ty(q7)")


def test_urdf_from_a_file_path(tmp_path: Path) -> None:
    f = tmp_path / "ur5.urdf"
    f.write_text(UR5)
    for arg in (f, str(f)):
        assert str(Robot.from_urdf(arg).ets) == str(load("ur5").ets)
    assert (
        str(Robot.from_urdf(f, end_link="l3").ets) == "Rz(q0) tz(0.089159) Rx(pi/2) Rz(q1) tx(-0.425) Rz(q2)"
    )


def test_sub_chain_between_named_links() -> None:
    r = Robot.from_urdf(UR5, base_link="l2", end_link="l5")
    assert str(r.ets) == "tx(-0.425) Rz(q0) tx(-0.39225) Rz(q1) tz(0.10915) Rx(pi/2) Rz(q2)"
    assert r.joint_names == ("elbow", "wrist_1", "wrist_2")


@pytest.mark.parametrize(
    "axis, text",
    [
        ("0 0 -1", "Rz(-q0)"),
        ("-1 0 0", "Rx(-q0)"),
        ("0 1 1", "Rx(pi/4) Ry(q0) Rx(-pi/4)"),
        ("1 1 0", "Rz(pi/4) Rx(q0) Rz(-pi/4)"),
        ("-1 0 1", "Ry(-pi/4) Rz(q0) Ry(pi/4)"),
        ("0 0.5 0.8660254037844386", "Rx(pi/3) Ry(q0) Rx(-pi/3)"),
        ("1e-12 0 1", "Rz(q0)"),
    ],
)
def test_axes_become_exact_ets(axis: str, text: str) -> None:
    r = Robot.from_urdf(urdf(["a", "b"], [joint("j", "a", "b", axis=axis)]))
    assert str(r.ets) == text


def rpy_matrix(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    Rx = np.array([[1, 0, 0], [0, cr, -sr], [0, sr, cr]])
    Ry = np.array([[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]])
    Rz = np.array([[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]])
    return Rz @ Ry @ Rx


def rodrigues(u: np.ndarray, q: float) -> np.ndarray:
    """Rotation by q about the unit vector u: I + sin q K + (1 - cos q) K^2."""
    K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
    return np.eye(3) + math.sin(q) * K + (1 - math.cos(q)) * K @ K


def urdf_fk(spec: list[tuple], q: np.ndarray) -> np.ndarray:
    """Independent URDF forward kinematics: origin (translation, then rpy), then the joint motion."""
    T, k = np.eye(4), 0
    for kind, xyz, rpy, axis in spec:
        A = np.eye(4)
        A[:3, :3], A[:3, 3] = rpy_matrix(*rpy), xyz
        T = T @ A
        if kind == "fixed":
            continue
        u = np.asarray(axis, dtype=float) / np.linalg.norm(axis)
        J = np.eye(4)
        if kind == "prismatic":
            J[:3, 3] = u * q[k]
        else:
            J[:3, :3] = rodrigues(u, q[k])
        T, k = T @ J, k + 1
    return T


def spec_urdf(spec: list[tuple]) -> str:
    links = [f"l{i}" for i in range(len(spec) + 1)]
    joints = [
        joint(
            f"j{i}",
            links[i],
            links[i + 1],
            kind=kind,
            xyz=" ".join(map(repr, xyz)),
            rpy=" ".join(map(repr, rpy)),
            axis=" ".join(map(str, axis)),
        )
        for i, (kind, xyz, rpy, axis) in enumerate(spec)
    ]
    return urdf(links, joints)


def test_arbitrary_unit_axis_matches_rodrigues() -> None:
    spec = [("revolute", (0.1, -0.2, 0.3), (0.4, -0.5, 0.6), (1, 2, 2))]
    r = Robot.from_urdf(spec_urdf(spec))
    assert "." not in str(r.ets).split("Rz(q0)")[1]  # the axis rotations are exact atan2 terms
    for q in np.linspace(-3, 3, 7):
        T = r.fkine([q])
        np.testing.assert_allclose(T, urdf_fk(spec, np.array([q])), atol=1e-12)
        np.testing.assert_allclose(
            T[:3, :3], rpy_matrix(0.4, -0.5, 0.6) @ rodrigues(np.array([1, 2, 2]) / 3, q), atol=1e-12
        )


axis_st = st.tuples(st.integers(-3, 3), st.integers(-3, 3), st.integers(-3, 3)).filter(lambda a: any(a))
num_st = st.floats(-1, 1, allow_nan=False).map(lambda x: round(x, 4))
angle_st = st.one_of(st.sampled_from([0.0, 1.5707963267948966, -3.141592653589793]), num_st)
joint_st = st.tuples(
    st.sampled_from(["revolute", "continuous", "prismatic", "fixed"]),
    st.tuples(num_st, num_st, num_st),
    st.tuples(angle_st, angle_st, angle_st),
    axis_st,
)


@settings(max_examples=40, deadline=None)
@given(spec=st.lists(joint_st, min_size=1, max_size=5), seed=st.integers(0, 2**16))
def test_random_chains_match_an_independent_urdf_fk(spec: list[tuple], seed: int) -> None:
    if all(k == "fixed" for k, *_ in spec):
        spec[0] = ("revolute", *spec[0][1:])
    r = Robot.from_urdf(spec_urdf(spec))
    q = np.random.default_rng(seed).uniform(-2, 2, r.n)
    np.testing.assert_allclose(r.fkine(q), urdf_fk(spec, q), atol=1e-12)


# ---------------------------------------------------------------------------------------------
# errors


def test_branching_tree_without_end_link_lists_the_leaves() -> None:
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(PANDA)
    msg = str(info.value)
    assert (
        "branches" in msg
        and "end_link" in msg
        and "'panda_leftfinger'" in msg
        and "'panda_rightfinger'" in msg
    )


def test_mimic_joint_on_the_chain_is_rejected() -> None:
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(PANDA, end_link="panda_rightfinger")
    msg = str(info.value)
    assert "'panda_finger_joint2'" in msg and "mimic" in msg and "'panda_finger_joint1'" in msg


def test_malformed_xml_reports_line_and_column() -> None:
    bad = '<robot name="x">\n  <link name="a"/>\n  <link name="b">\n</robot>\n'
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(bad)
    msg = str(info.value)
    assert "malformed XML" in msg and "line 4" in msg and "column" in msg


@pytest.mark.parametrize("kind", ["floating", "planar"])
def test_floating_and_planar_joints_are_rejected(kind: str) -> None:
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(urdf(["a", "b"], [joint("free", "a", "b", kind=kind)]))
    msg = str(info.value)
    assert "'free'" in msg and kind in msg and "revolute, continuous, prismatic and fixed" in msg


@pytest.mark.parametrize(
    "text, words",
    [
        (urdf(["a", "b"], [joint("j", "a", "b", kind="ball")]), ["'j'", "unknown type 'ball'", "'revolute'"]),
        (urdf(["a", "b"], [joint("j", "a", "bb")]), ["'j'", "'bb'", "not declared", "did you mean 'b'"]),
        (urdf(["a", "b"], [joint("j", "a", "b", xyz="0 nan 0")]), ["'j' origin xyz", "'nan'", "finite"]),
        (urdf(["a", "b"], [joint("j", "a", "b", rpy="0 0")]), ["'j' origin rpy", "3 numbers"]),
        (urdf(["a", "b"], [joint("j", "a", "b", xyz="0 x 0")]), ["'j' origin xyz", "'x'", "not a number"]),
        (urdf(["a", "b"], [joint("j", "a", "b", axis="0 0 0")]), ["'j'", "zero vector"]),
        (
            urdf(["a", "b"], [joint("j", "a", "b", limit='lower="1" upper="-1"')]),
            ["'j'", "lower 1.0 > upper -1.0"],
        ),
        (
            urdf(["a", "b"], [joint("j", "a", "b", kind="fixed")]),
            ["no revolute, continuous or prismatic joint"],
        ),
        (urdf(["a", "b", "c"], [joint("j", "a", "b"), joint("k", "c", "b")]), ["'b'", "two joints", "tree"]),
        ('<robot name="x"><link name="a"/></rbt>', ["malformed XML", "line 1"]),
        ('<model name="x"/>', ["<robot>", "<model>"]),
    ],
)
def test_bad_urdf_raises_an_actionable_error(text: str, words: list[str]) -> None:
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(text)
    for w in words:
        assert w in str(info.value)


def test_unknown_links_and_missing_paths_name_the_links() -> None:
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(UR5, end_link="tool")
    assert "end_link 'tool'" in str(info.value) and "'tool0'" in str(info.value)
    with pytest.raises(URDFError) as info:
        Robot.from_urdf(UR5, base_link="basee")
    assert "base_link 'basee'" in str(info.value) and "'base'" in str(info.value)
    with pytest.raises(URDFError) as info:  # end above base: URDF chains go from parent to child
        Robot.from_urdf(UR5, base_link="l4", end_link="l2")
    assert "no path" in str(info.value) and "'l4'" in str(info.value) and "'l2'" in str(info.value)
    with pytest.raises(URDFError) as info:  # two roots
        Robot.from_urdf(urdf(["a", "b", "c"], [joint("j", "a", "b")]))
    assert "root links" in str(info.value) and "base_link" in str(info.value)


def test_missing_file_is_a_urdf_error_and_a_robot_error(tmp_path: Path) -> None:
    with pytest.raises(RobotError, match="cannot read URDF file"):
        Robot.from_urdf(tmp_path / "missing.urdf")


# ---------------------------------------------------------------------------------------------
# xacro (issue 23, item 2): refused with the command that expands it, by both readers

XACRO_ARM = """<?xml version="1.0"?>
<robot name="arm" xmlns:xacro="http://www.ros.org/wiki/xacro">
  <xacro:property name="len" value="0.5"/>
  <xacro:macro name="segment" params="i parent">
    <link name="l${i}"/>
    <joint name="j${i}" type="revolute"><parent link="${parent}"/><child link="l${i}"/>
      <origin xyz="0 0 ${len}"/><axis xyz="0 0 1"/></joint>
  </xacro:macro>
  <link name="base"/><link name="l0"/>
  <joint name="j0" type="revolute"><parent link="base"/><child link="l0"/><axis xyz="0 0 1"/></joint>
  <xacro:segment i="1" parent="l0"/>
  <xacro:segment i="2" parent="l1"/>
</robot>
"""


def _readers():
    from symkin.model.tree import Tree

    return (Robot.from_urdf, Tree.from_urdf)


@pytest.mark.parametrize(
    ("text", "found"),
    [
        (XACRO_ARM, "<xacro:property>"),  # read as XML, it was a 1-joint robot: the macros were dropped
        (XACRO_ARM.replace(' xmlns:xacro="http://www.ros.org/wiki/xacro"', ""), "<xacro:property>"),
        (XACRO_ARM.replace("xacro:", "x:").replace("xmlns:xacro", "xmlns:x"), "<x:property>"),  # any prefix
        (XACRO_ARM.replace("xmlns:xacro", "xmlns"), "default namespace is xacro's"),
        (urdf(["a", "b"], [joint("j", "a", "b", xyz="0 0 ${len}")]), "'0 0 ${len}' in attribute 'xyz'"),
        (urdf(["a", "b"], [joint("j", "a", "b", extra='<x xacro:if="1"/>')]), "xacro:if"),
        (urdf(["a", "$(arg b)"], [joint("j", "a", "$(arg b)")]), "$(arg b)"),
    ],
)
def test_xacro_text_is_refused_with_how_to_expand_it(text: str, found: str) -> None:
    for read in _readers():
        with pytest.raises(URDFError) as info:
            read(text)
        msg = str(info.value)
        assert "xacro, not plain URDF" in msg and found in msg, msg
        assert "`xacro file.urdf.xacro > file.urdf`" in msg


def test_an_expanded_urdf_that_keeps_the_xacro_declaration_is_read() -> None:
    """xacro's output keeps the namespace declaration of its input (example-robot-data's baxter.urdf
    does): with no xacro element, attribute or substitution left, it is plain URDF."""
    text = urdf(["a", "b"], [joint("j", "a", "b", xyz="0 0 0.5")]).replace(
        "<robot ", '<robot xmlns:xacro="http://www.ros.org/wiki/xacro" ', 1
    )
    assert 'xmlns:xacro="http://www.ros.org/wiki/xacro"' in text
    for read in _readers():
        model = read(text)
        assert model.n == 1
        assert np.allclose(model.fkine(np.zeros(1))[:3, 3], [0, 0, 0.5])


def test_xacro_files_are_refused_by_content_and_name(tmp_path: Path) -> None:
    from symkin.cli.main import main

    macro = tmp_path / "arm.urdf.xacro"
    macro.write_text(XACRO_ARM)
    plain = tmp_path / "plain.xacro"  # no macro in it, but a .xacro file is read expanded
    plain.write_text(urdf(["a", "b"], [joint("j", "a", "b")]))
    for read in _readers():
        with pytest.raises(URDFError, match=r"`xacro arm\.urdf\.xacro > arm\.urdf`"):
            read(macro)
        with pytest.raises(URDFError, match=r"name ends in \.xacro.*`xacro plain\.xacro > plain\.urdf`"):
            read(plain)
    spaced = tmp_path / "my arm.URDF.xacro"
    spaced.write_text(XACRO_ARM)
    with pytest.raises(URDFError, match=r"`xacro 'my arm\.URDF\.xacro' > 'my arm\.URDF'`"):
        Robot.from_urdf(spaced)
    assert main(["list-frames", str(macro)]) == 2  # the CLI reads .xacro as URDF, so it says the same
    assert main(["compile", str(macro), "--backend", "numpy"]) == 2


def test_plain_urdf_with_dollars_in_text_and_other_namespaces_is_read() -> None:
    text = urdf(["a", "b"], [joint("j", "a", "b", extra="<plugin>price: $5</plugin>")]).replace(
        "<robot ", '<robot xmlns:gz="http://gazebosim.org/schema" '
    )
    assert Robot.from_urdf(text).n == 1
