"""Built-in robots with published kinematic parameters, joint limits and named configurations.

Every robot has ``qz`` (all zeros); ``qr`` (a "ready" pose) and others where published. Each robot's
``source`` names the documents its numbers come from (manufacturer data sheets and specifications,
papers, Corke's Robotics Toolbox). ``load(name)`` returns a cached, immutable Robot.
"""

from __future__ import annotations

import difflib
import math
from collections.abc import Callable
from functools import cache, partial
from pathlib import Path

import numpy as np

from symkin.core.names import robot_key
from symkin.errors import UnknownRobotError
from symkin.model.dh import DHLink
from symkin.model.ets import ET, ETS
from symkin.model.robot import Robot

__all__ = ["load", "list_robots"]

_DEG = math.pi / 180
_PI = math.pi


def _deg(*values: float) -> list[float]:
    return [v * _DEG for v in values]


def _panda() -> Robot:
    # Haviland and Corke, Manipulator Differential Kinematics, Part 1 (2023), Fig. 1: E1..E15 with the
    # flipped joints E7 and E11, then the tool
    # point of the Franka hand: 0.1034 m along the flange z and -45 deg about it (as RTB's Panda ets()).
    ets = (
        "tz(0.333) Rz(q0) Ry(q1) tz(0.316) Rz(q2) tx(0.0825) Ry(-q3) tx(-0.0825) tz(0.384) Rz(q4) "
        "Ry(-q5) tx(0.088) Rx(pi) tz(0.107) Rz(q6) tz(0.1034) Rz(-pi/4)"
    )
    return Robot.from_ets(
        ets,
        name="panda",
        qlim=[
            [-2.8973, -1.7628, -2.8973, -3.0718, -2.8973, -0.0175, -2.8973],
            [2.8973, 1.7628, 2.8973, -0.0698, 2.8973, 3.7525, 2.8973],
        ],
        configs={"qr": [0, -0.3, 0, -2.2, 0, 2.0, _PI / 4]},
        joint_names=tuple(f"panda_joint{i}" for i in range(1, 8)),
        qd_max=[2.175, 2.175, 2.175, 2.175, 2.61, 2.61, 2.61],
        source=(
            "ETS of Fig. 1 of Haviland and Corke, 'Manipulator Differential Kinematics, Part 1' (2023), "
            "ending at the gripper tool point: flange tz(0.107) then tz(0.1034) Rz(-pi/4) as in Corke's "
            "Robotics Toolbox Panda ets() (the "
            "URDF's panda_hand frame lacks the 0.1034 m); joint and speed limits and qr from Franka Emika's "
            "robot and interface specifications / RTB"
        ),
    )


def _ur(
    name: str, d1: float, a2: float, a3: float, d4: float, d5: float, d6: float, qd_deg: list[float]
) -> Robot:
    alpha = ["pi/2", 0, 0, "pi/2", "-pi/2", 0]
    d = [d1, 0, 0, d4, d5, d6]
    a = [0, a2, a3, 0, 0, 0]
    links = [DHLink(d=d[j], a=a[j], alpha=alpha[j]) for j in range(6)]
    return Robot.from_dh(
        links,
        name=name,
        qlim=np.array([[-2 * _PI] * 6, [2 * _PI] * 6]),
        configs={"qr": _deg(180, 0, 0, 0, 90, 0)},
        joint_names=("shoulder_pan", "shoulder_lift", "elbow", "wrist_1", "wrist_2", "wrist_3"),
        qd_max=_deg(*qd_deg),
        source=(
            f"Universal Robots, 'DH parameters for calculations of kinematics and dynamics' "
            f"({name.upper()}, standard DH); joint range +-360 deg and joint speeds from the UR technical "
            "specifications; qr from Corke's Robotics Toolbox"
        ),
    )


#: The arguments of :func:`_ur` after the name: d1, a2, a3, d4, d5, d6 (m), joint speeds (deg/s).
_UR = {
    "ur3": (0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819, [180, 180, 180, 360, 360, 360]),
    "ur5": (0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823, [180] * 6),
    "ur10": (0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922, [120, 120, 180, 180, 180, 180]),
}


def _puma560() -> Robot:
    rows = [  # d, a, alpha, qlim (deg)
        (0, 0, "pi/2", (-160, 160)),
        (0, 0.4318, 0, (-45, 225)),
        (0.15005, 0.0203, "-pi/2", (-225, 45)),
        (0.4318, 0, "pi/2", (-110, 170)),
        (0, 0, "-pi/2", (-100, 100)),
        (0, 0, 0, (-266, 266)),
    ]
    links = [DHLink(d=d, a=a, alpha=al, qlim=tuple(_deg(*lim))) for d, a, al, lim in rows]
    return Robot.from_dh(
        links,
        name="puma560",
        configs={
            "qr": [0, _PI / 2, -_PI / 2, 0, 0, 0],
            "qs": [0, 0, -_PI / 2, 0, 0, 0],
            "qn": [0, _PI / 4, -_PI, 0, _PI / 4, 0],
        },
        source=(
            "Corke's Puma 560 model (standard DH, Corke & Armstrong-Helouvry 1994; joint limits from Wang "
            "& Chen 1991), as in the MATLAB Robotics Toolbox and 'Robotics, Vision and Control': the base "
            "frame is at the shoulder (RTB-python >= 1.0 adds the 26.45 in pedestal as d1). qr, qs, qn as "
            "in the toolbox, with qn's joint 3 written -pi (same pose as pi) to lie within its limits"
        ),
    )


def _lbr_iiwa(name: str, model: str, d1: float, d3: float, speeds: list[float]) -> Robot:
    d = [d1, 0, d3, 0, 0.4, 0, 0.126]
    alpha = ["-pi/2", "pi/2", "pi/2", "-pi/2", "-pi/2", "pi/2", 0]
    lim = [170, 120, 170, 120, 170, 120, 175]
    links = [DHLink(d=d[j], alpha=alpha[j], qlim=(-lim[j] * _DEG, lim[j] * _DEG)) for j in range(7)]
    mm = "/".join(f"{round(v * 1000)}" for v in (d1, d3, 0.4, 0.126))
    return Robot.from_dh(
        links,
        name=name,
        joint_names=tuple(f"A{i}" for i in range(1, 8)),
        qd_max=_deg(*speeds),
        source=(
            f"KUKA, 'LBR iiwa 7 R800, LBR iiwa 14 R820 Specifications' ({model}: link lengths {mm} mm, "
            "axis ranges +-170/120/170/120/170/120/175 deg and axis speeds), as standard DH with "
            "alternating +-pi/2 twists; zero pose is the arm straight up"
        ),
    )


#: The arguments of :func:`_lbr_iiwa` after the name: model, d1, d3 (m), joint speeds (deg/s).
_LBR_IIWA = {
    "lbr_iiwa7": ("LBR iiwa 7 R800", 0.34, 0.4, [98, 98, 100, 130, 140, 180, 180]),
    "lbr_iiwa14": ("LBR iiwa 14 R820", 0.36, 0.42, [85, 85, 100, 75, 130, 135, 135]),
}


#: Sawyer: the robot's joint value q_j against the angle theta_j of the DH table,
#: theta_j = SAWYER_SIGN_j q_j + SAWYER_OFFSET_j: every joint axis of the DH table then lies on the URDF's
#: (same line, same direction) at every q, and the tool point is within 0.75 mm of the URDF's right_hand.
SAWYER_SIGN = (1, 1, 1, -1, 1, 1, 1)
SAWYER_OFFSET = (0, "-pi/2", 0, "pi", 0, "pi", "pi/2")


def _sawyer() -> Robot:
    a = [0.081, 0, 0, 0, 0, 0, 0]
    d = [0.317, 0.1925, 0.4, 0.1685, 0.4, 0.1363, 0.13375]
    alpha = ["-pi/2"] * 6 + [0]
    links = [DHLink(d=d[j], a=a[j], alpha=alpha[j], offset=SAWYER_OFFSET[j]) for j in range(7)]
    dh = Robot.from_dh(links, name="sawyer")
    ets = ETS(
        tuple(ET(e.axis, joint=e.joint, flip=SAWYER_SIGN[e.joint] < 0) if e.is_joint else e for e in dh.ets)
    )
    return Robot(
        ets,
        name="sawyer",
        qlim=[
            [-3.0503, -3.8095, -3.0426, -3.0439, -2.9761, -2.9761, -4.7124],
            [3.0503, 2.2736, 3.0426, 3.0439, 2.9761, 2.9761, 4.7124],
        ],
        joint_names=tuple(f"right_j{i}" for i in range(7)),
        qd_max=[1.74, 1.328, 1.957, 1.957, 3.485, 3.485, 4.545],
        source=(
            "Rethink Robotics Sawyer: link lengths and twists of the standard DH table in Corke's Robotics "
            "Toolbox (after D. Layeghi, 'Dynamic and kinematic modelling of the Sawyer arm', 2017); joint "
            "values (zeros and directions), limits and speeds of Rethink's URDF (sawyer_description, "
            "sawyer_base.urdf.xacro): with theta the DH angles, theta_1 = q_1 - pi/2, theta_3 = pi - q_3, "
            "theta_5 = q_5 + pi, theta_6 = q_6 + pi/2, so every joint axis lies on the URDF's. The end "
            "effector is the DH table's last frame: 0.75 mm from the URDF's right_hand, turned 10 deg about z"
        ),
    )


def _planar(n: int) -> Robot:
    terms = " + ".join(f"l{k} c{''.join(str(i) for i in range(1, k + 1))}" for k in range(1, n + 1))
    return Robot.from_dh(
        [DHLink(a=1) for _ in range(n)],
        name=f"planar{n}",
        source=(
            f"planar {n}-link arm with unit links, the textbook example (Corke's Robotics Toolbox "
            f"mdl_planar{n}; Corke, 'Robotics, Vision and Control', 2017, chapter 7): x = {terms}"
        ),
    )


def _cobra600() -> Robot:
    links = [
        DHLink(d=0.387, a=0.325, qlim=(-105 * _DEG, 105 * _DEG)),
        DHLink(a=0.275, alpha="pi", qlim=(-157.5 * _DEG, 157.5 * _DEG)),
        DHLink(prismatic=True, qlim=(0.0, 0.21)),
        DHLink(qlim=(-2 * _PI, 2 * _PI)),
    ]
    return Robot.from_dh(
        links,
        name="cobra600",
        joint_names=("J1", "J2", "J3", "J4"),
        configs={"qr": [_PI / 4, -_PI / 2, 0.1, 0]},
        source=(
            "Adept (Omron) Cobra s600 SCARA: standard DH of the Cobra600 model in Corke's Robotics Toolbox "
            "(base to joint 2 height 387 mm, inner link 325 mm, outer link 275 mm, joint 3 a quill moving "
            "down); joint ranges from Adept's Cobra s600 data sheet: J1 +-105 deg, J2 +-157.5 deg, J3 "
            "210 mm, J4 +-360 deg"
        ),
    )


def _gantry() -> Robot:
    return Robot.from_ets(
        "tx(q0) ty(q1) tz(q2)",
        name="gantry",
        qlim=[[0.0, 0.0, 0.0], [0.3, 0.25, 0.035]],
        joint_names=("X", "Y", "Z"),
        configs={"qr": [0.15, 0.125, 0.0175]},
        qd_max=[0.3, 0.3, 0.5 / 60],
        source=(
            "three-axis Cartesian gantry: the axis positions are the tool's x, y, z in the machine frame "
            "and the tool frame keeps the machine's orientation (the Kin_Gantry3 kinematics of the CODESYS "
            "SoftMotion library); travel 300 x 250 x 35 mm and speeds 18000, 18000 and 500 mm/min of "
            "IRNAS's open-hardware PreciseXY gantry (its README)"
        ),
    )


def _stanford() -> Robot:
    inch = 0.0254
    links = [
        DHLink(d=0.412, alpha="-pi/2", qlim=(-170 * _DEG, 170 * _DEG)),
        DHLink(d=0.154, alpha="pi/2", qlim=(-170 * _DEG, 170 * _DEG)),
        DHLink(theta="-pi/2", a=0.0203, prismatic=True, qlim=(12 * inch, 50 * inch)),
        DHLink(alpha="-pi/2", qlim=(-170 * _DEG, 170 * _DEG)),
        DHLink(alpha="pi/2", qlim=(-90 * _DEG, 90 * _DEG)),
        DHLink(d=0.263, qlim=(-170 * _DEG, 170 * _DEG)),
    ]
    return Robot.from_dh(
        links,
        name="stanford",
        source=(
            "Stanford arm, standard DH from Corke's Robotics Toolbox (Stanford AIM-177 Fig. 2.3; Paul 1981); "
            "joint 3 is prismatic, 12 to 50 inches"
        ),
    )


_BUILDERS: dict[str, Callable[[], Robot]] = {
    "panda": _panda,
    **{name: partial(_ur, name, *args) for name, args in _UR.items()},
    "puma560": _puma560,
    **{name: partial(_lbr_iiwa, name, *args) for name, args in _LBR_IIWA.items()},
    "sawyer": _sawyer,
    "planar2": lambda: _planar(2),
    "planar3": lambda: _planar(3),
    "stanford": _stanford,
    "cobra600": _cobra600,
    "gantry": _gantry,
}


def list_robots() -> list[str]:
    """Names of the built-in robots, sorted."""
    return sorted(_BUILDERS)


@cache
def _build(name: str) -> Robot:
    """The built-in robot ``name``, with its sphere model when it has one (:mod:`builtin_geometry`)."""
    from symkin.model.builtin_geometry import builtin_geometry

    robot = _BUILDERS[name]()
    geometry = builtin_geometry(name)
    return robot if geometry is None else robot.with_geometry(geometry)


def load(name: str) -> Robot:
    """A built-in robot by name (case-insensitive, ``-`` and spaces read as ``_``), e.g. ``load("panda")``."""
    if not isinstance(name, str):
        raise UnknownRobotError(
            f"a robot name must be a string, not {type(name).__name__}; available: {', '.join(list_robots())}"
        )
    key = robot_key(name)
    if key not in _BUILDERS:
        close = difflib.get_close_matches(key, list_robots(), n=3, cutoff=0.5)
        hint = f"; did you mean {' or '.join(repr(c) for c in close)}?" if close else ""
        raise UnknownRobotError(f"unknown robot {name!r}{hint} Available: {', '.join(list_robots())}")
    return _build(key)


def load_dh_file(path: str | Path) -> Robot:
    """A robot from a DH table file (format in :mod:`symkin.model.dh`)."""
    return Robot.from_dh_file(path)
