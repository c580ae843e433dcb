"""Property-based fuzzing of the importers (issue 12): ETS text, DH tables and URDF documents give
a correct robot or a SymkinError, nothing else. "Correct" is checked against independent
computations: the ETS text round trip, and the DH and URDF transform products written out here
with NumPy. Example counts are bounded so the whole fuzz suite stays within seconds."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from symkin import ETS, Robot
from symkin.errors import SymkinError
from symkin.model.dh import DHLink, dh_table_args

FUZZ = settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
FEW = settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])


# -- ETS text ---------------------------------------------------------------------------------
PIECES = [
    "tx(", "ty(", "tz(", "Rx(", "Ry(", "Rz(", ")", "(", "q", "q0", "q1", "q7", "-q", "-", "+", "*", "/",
    "⊕", " ", "pi", "deg", "°", "0", "1", "9", ".", "e", "e-", "1e308", "1e-400", "0.5", "90", "atan2(",
    "sqrt(", ",", "x", "ä", "\n", "9" * 40, "-" * 50, "(" * 30, ")" * 30,
]  # fmt: skip


def _same_ets(a: ETS, b: ETS) -> bool:
    return str(a) == str(b) and a.n == b.n


@FUZZ
@given(st.lists(st.sampled_from(PIECES), max_size=30).map("".join) | st.text(max_size=80))
def test_ets_text_parses_or_raises_a_symkin_error(text):
    try:
        ets = ETS.parse(text)
    except SymkinError:
        return
    assert _same_ets(ETS.parse(str(ets)), ets)  # the text form round-trips
    for e in ets:
        assert e.is_joint or math.isfinite(e.const.value)
    robot = Robot(ets)
    q = np.linspace(-1.0, 1.0, robot.n)
    T = robot.fkine(q)
    assert T.shape == (4, 4)


@st.composite
def _constant_text(draw) -> tuple[str, float]:
    """A constant in one of the text forms, and its value computed independently."""
    kind = draw(st.sampled_from(["float", "deg", "pi", "int", "sum"]))
    if kind == "float":
        x = draw(st.floats(-1e6, 1e6, allow_nan=False))
        return repr(x), x
    if kind == "deg":
        d = draw(st.integers(-720, 720))
        return f"{d}deg", math.radians(d)
    if kind == "pi":
        k, m = draw(st.integers(-8, 8)), draw(st.integers(1, 12))
        return f"{k}*pi/{m}", k * math.pi / m
    if kind == "int":
        i = draw(st.integers(-(10**12), 10**12))
        return str(i), float(i)
    a, b = draw(st.floats(-10, 10, allow_nan=False)), draw(st.integers(-4, 4))
    return f"{a!r} + {b}*pi", a + b * math.pi


@FUZZ
@given(
    st.lists(st.tuples(st.sampled_from(["tx", "ty", "tz", "Rx", "Ry", "Rz"]), _constant_text()), max_size=6)
)
def test_ets_constants_have_the_value_they_were_written_with(items):
    text = " ".join(["Rz(q)", *(f"{a}({c})" for a, (c, _) in items)])
    ets = ETS.parse(text)
    for e, (_, (_, value)) in zip(ets.ets[1:], items):
        assert math.isclose(e.const.value, value, rel_tol=1e-12, abs_tol=1e-12)


# -- DH tables --------------------------------------------------------------------------------
def _rx(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[1, 0, 0, 0], [0, c, -s, 0], [0, s, c, 0], [0, 0, 0, 1.0]])


def _rz(a: float) -> np.ndarray:
    c, s = math.cos(a), math.sin(a)
    return np.array([[c, -s, 0, 0], [s, c, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1.0]])


def _trans(x: float = 0.0, y: float = 0.0, z: float = 0.0) -> np.ndarray:
    T = np.eye(4)
    T[:3, 3] = (x, y, z)
    return T


_NUM = st.floats(-2.0, 2.0, allow_nan=False, allow_infinity=False)


@FEW
@given(
    rows=st.lists(st.tuples(_NUM, _NUM, _NUM, _NUM, st.booleans()), min_size=1, max_size=6),
    modified=st.booleans(),
    seed=st.integers(0, 2**16),
)
def test_dh_robot_matches_the_dh_product(rows, modified, seed):
    """Standard: Rz(theta) Tz(d) Tx(a) Rx(alpha); modified: Tx(a) Rx(alpha) Rz(theta) Tz(d)."""
    links = [DHLink(d=d, a=a, alpha=al, offset=off, prismatic=p) for d, a, al, off, p in rows]
    robot = Robot.from_dh(links, modified=modified)
    q = np.random.default_rng(seed).uniform(-1, 1, len(rows))
    T = np.eye(4)
    for (d, a, al, off, p), qj in zip(rows, q):
        theta, dd = (off, d + off + qj) if p else (qj + off, d)
        if p:
            theta = 0.0
        link = [_rz(theta), _trans(z=dd), _trans(x=a), _rx(al)]
        T = T @ (link[2] @ link[3] @ link[0] @ link[1] if modified else link[0] @ link[1] @ link[2] @ link[3])
    assert np.abs(robot.fkine(q) - T).max() < 1e-9


CELLS = [
    "0", "0.1", "-0.5", "pi/2", "90deg", "-", "R", "P", "x", "1e308", "1e308*10", "nan", "inf", "1" * 300,
    "-" * 40 + "1", "(" * 40, "atan2(1,0)", "q", "1/0", "ä", "#", "1e-400",
]  # fmt: skip


@FUZZ
@given(
    header=st.lists(st.sampled_from(["type", "d", "a", "alpha", "offset", "qmin", "qmax", "name", "bad"]),
                    min_size=1, max_size=6),
    rows=st.lists(st.lists(st.sampled_from(CELLS), min_size=1, max_size=7), max_size=4),
    first=st.sampled_from(["# symkin dh: standard", "# symkin dh: modified", "# symkin dh: other", "x"]),
)  # fmt: skip
def test_dh_table_text_parses_or_raises_a_symkin_error(header, rows, first):
    text = "\n".join([first, " ".join(header), *(" ".join(r) for r in rows)])
    try:
        robot = Robot(**dh_table_args(text))
    except SymkinError:
        return
    assert np.isfinite(robot.fkine(np.zeros(robot.n))).all()


# -- URDF documents ---------------------------------------------------------------------------
def _rpy(r: float, p: float, y: float) -> np.ndarray:
    cr, sr, cp, sp, cy, sy = math.cos(r), math.sin(r), math.cos(p), math.sin(p), math.cos(y), math.sin(y)
    R = np.array(
        [
            [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
            [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
            [-sp, cp * sr, cp * cr],
        ]
    )
    T = np.eye(4)
    T[:3, :3] = R
    return T


def _axis_motion(kind: str, u: np.ndarray, q: float) -> np.ndarray:
    T = np.eye(4)
    if kind == "prismatic":
        T[:3, 3] = u * q
    elif kind in ("revolute", "continuous"):
        K = np.array([[0, -u[2], u[1]], [u[2], 0, -u[0]], [-u[1], u[0], 0]])
        T[:3, :3] = np.eye(3) + math.sin(q) * K + (1 - math.cos(q)) * K @ K  # Rodrigues
    return T


_VAL = st.floats(-1.5, 1.5, allow_nan=False).map(lambda x: repr(round(x, 6)))
_AXIS = st.sampled_from(
    ["0 0 1", "1 0 0", "0 -1 0", "0.6 0.8 0", "0 0.6 -0.8", "0.48 0.6 0.64", "1 1 1", "-2 0 1"]
)


@st.composite
def _chain(draw):
    n = draw(st.integers(1, 5))
    joints = []
    for j in range(n):
        kind = draw(st.sampled_from(["revolute", "continuous", "prismatic", "fixed"]))
        xyz = " ".join(draw(st.tuples(_VAL, _VAL, _VAL)))
        rpy = " ".join(draw(st.tuples(_VAL, _VAL, _VAL)))
        joints.append((f"j{j}", kind, xyz, rpy, draw(_AXIS)))
    return joints


def _urdf(joints, name: str = "fuzz") -> str:
    links = "".join(f'<link name="l{i}"/>' for i in range(len(joints) + 1))
    body = "".join(
        f'<joint name="{nm}" type="{kind}"><parent link="l{i}"/><child link="l{i + 1}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/>'
        f'<limit lower="-3" upper="3" velocity="1"/></joint>'
        for i, (nm, kind, xyz, rpy, axis) in enumerate(joints)
    )
    return f'<robot name="{name}">{links}{body}</robot>'


@FEW
@given(joints=_chain(), seed=st.integers(0, 2**16))
def test_urdf_robot_matches_the_urdf_transform_product(joints, seed):
    """0T_e = prod(Trans(xyz) RPY(rpy) Motion(axis, q)) over the chain (URDF spec), written out here."""
    moving = [j for j in joints if j[1] != "fixed"]
    assume(moving)
    robot = Robot.from_urdf(_urdf(joints))
    assert robot.n == len(moving)
    q = np.random.default_rng(seed).uniform(-1, 1, robot.n)
    T, k = np.eye(4), 0
    for _, kind, xyz, rpy, axis in joints:
        T = T @ _trans(*map(float, xyz.split())) @ _rpy(*map(float, rpy.split()))
        if kind != "fixed":
            u = np.array(list(map(float, axis.split())))
            T = T @ _axis_motion(kind, u / np.linalg.norm(u), q[k])
            k += 1
    assert np.abs(robot.fkine(q) - T).max() < 1e-9


HOSTILE = [
    ("<robot", "<!DOCTYPE robot [<!ENTITY e 'x'>]><robot"),
    ('type="revolute"', 'type="floating"'),
    ('type="prismatic"', 'type="bogus"'),
    ('<parent link="l0"/>', '<parent link="nowhere"/>'),
    ('xyz="0 0 1"', 'xyz="0 0 0"'),
    ('lower="-3"', 'lower="1e400"'),
    ('lower="-3"', 'lower="5"'),
    ('velocity="1"', 'velocity="-1"'),
    ('velocity="1"', 'velocity="nan"'),
    ("<origin ", "<origin xyz='1 2' "),
    ("</robot>", ""),
    ('name="j0"', 'name="j1"'),
    ("<link ", "<lnk "),
    ('"fuzz"', '"\x00"'),
    ('"fuzz"', '"&amp;&lt;"'),
    ("<robot", "\ufeff<robot"),
]


@FUZZ
@given(joints=_chain(), edits=st.lists(st.sampled_from(HOSTILE), max_size=3))
def test_mangled_urdf_gives_a_robot_or_a_symkin_error(joints, edits):
    text = _urdf(joints)
    for old, new in edits:
        text = text.replace(old, new, 1)
    try:
        robot = Robot.from_urdf(text)
    except SymkinError:
        return
    assert np.isfinite(robot.fkine(np.zeros(robot.n))).all()
