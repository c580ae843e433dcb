"""Hand-written sphere models of the built-in arms: a handful of spheres per link that cover the
link's real shape conservatively (in the style of the sphere sets motion planners use), written
for symkin from each arm's published dimensions (link lengths of the kinematic models in
:mod:`symkin.model.robots`, outer diameters of the manufacturers' data sheets and drawings).

Every sphere is in the frame of its link (metres): ``base`` is the base frame, ``link<k+1>``
the k-th link frame of the chain (``robot.link_poses(q)[k]``, the frame right after the k-th
joint), ``ee`` the end-effector frame ``robot.fkine(q)``. ``disabled`` lists the link pairs that
touch at every configuration by construction (like the "Default"/"Always" pairs of MoveIt's
setup assistant): with them out, no sphere pair collides at the robot's named configurations.

The models are approximate: good for planning margins and self-collision checks, not for
contact or clearance below about a centimetre.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

from symkin.model.geometry import Geometry, Sphere

__all__ = ["builtin_geometry", "BUILTIN_GEOMETRY"]

_Row = tuple[str, float, float, float, float]  # link, x, y, z, radius


def _geometry(rows: Sequence[_Row], disabled: Sequence[tuple[str, str]], source: str) -> Geometry:
    return Geometry(tuple(Sphere((x, y, z), r, link) for link, x, y, z, r in rows), tuple(disabled), source)


def _line(link: str, a: Sequence[float], b: Sequence[float], count: int, r: float) -> list[_Row]:
    """``count`` spheres of radius ``r`` evenly from ``a`` to ``b`` (both ends included)."""
    if count == 1:
        return [(link, *(0.5 * (p + q) for p, q in zip(a, b)), r)]  # type: ignore[list-item]
    return [(link, *(p + i / (count - 1) * (q - p) for p, q in zip(a, b)), r) for i in range(count)]  # type: ignore[return-value]


# ---------------------------------------------------------------------------------------------
# Franka Emika Panda (symkin's ETS: link frames 0 and 1 at the shoulder, z = 0.333; frame 2 at
# z = 0.649; frame 3 at the elbow, x = 0.0825; frames 4 and 5 at the wrist, z = 1.033; frame 6 at
# the flange, 0.088 forward and 0.107 below the wrist, z pointing out of the flange; ee at the
# gripper's tool point, 0.1034 beyond the flange, turned -45 deg like the hand).


def _panda() -> Geometry:
    rows: list[_Row] = [
        # base (link 0): round foot of ~0.2 m with the connector housing at the back (-x)
        ("base", 0.0, 0.0, 0.06, 0.09),
        ("base", -0.09, 0.0, 0.05, 0.07),
        ("base", 0.0, 0.0, 0.14, 0.075),
        # link1: vertical column from the foot (z 0.14) up to the shoulder
        *_line("link1", (0.0, 0.0, -0.19), (0.0, 0.0, -0.04), 4, 0.075),
        ("link1", 0.0, 0.0, 0.0, 0.07),
        # link2: shoulder housing around joint 2 (along y), then up the upper arm
        ("link2", 0.0, 0.035, 0.0, 0.075),
        ("link2", 0.0, -0.035, 0.0, 0.075),
        ("link2", 0.0, 0.0, 0.08, 0.07),
        ("link2", 0.0, 0.0, 0.15, 0.065),
        # link3: rest of the upper arm, then the elbow housing around joint 4 at x = 0.0825
        *_line("link3", (0.0, 0.0, -0.15), (0.0, 0.0, -0.03), 3, 0.065),
        ("link3", 0.04, 0.0, 0.0, 0.065),
        ("link3", 0.0825, 0.03, 0.0, 0.065),
        ("link3", 0.0825, -0.03, 0.0, 0.065),
        # link4: elbow housing, then the knee up to the forearm's foot above joint 5's axis
        ("link4", 0.0, 0.03, 0.0, 0.07),
        ("link4", 0.0, -0.03, 0.0, 0.07),
        ("link4", -0.045, 0.0, 0.07, 0.065),
        ("link4", -0.0825, 0.0, 0.11, 0.065),
        # link5: forearm from its foot above the knee (z 0.78) to the wrist: slim and set back (-x) at
        # the bottom, where the hand folds in front of it
        *_line("link5", (-0.035, 0.0, -0.24), (-0.035, 0.0, -0.12), 3, 0.05),
        ("link5", 0.0, 0.0, -0.06, 0.06),
        ("link5", 0.0, 0.0, -0.005, 0.065),
        ("link5", 0.0, 0.0, 0.045, 0.06),
        # link6: wrist block from joint 6 (along y) to joint 7's housing at x = 0.088
        ("link6", 0.0, 0.0, 0.0, 0.065),
        ("link6", 0.044, 0.0, 0.01, 0.06),
        ("link6", 0.088, 0.0, 0.02, 0.06),
        # link7: joint 7 housing down to the flange (z = 0 here), with the flange's side bump
        ("link7", 0.0, 0.0, -0.075, 0.055),
        ("link7", 0.0, 0.0, -0.025, 0.055),
        ("link7", 0.04, 0.04, -0.05, 0.035),
        # ee: the Franka hand (0.2 m wide along its y, 0.06 m thick, from the flange to 0.066 m above
        # it) and the fingers
        *_line("ee", (0.0, -0.07, -0.07), (0.0, 0.07, -0.07), 4, 0.034),
        ("ee", 0.0, 0.0, -0.09, 0.04),
        ("ee", 0.0, 0.04, -0.03, 0.025),
        ("ee", 0.0, -0.04, -0.03, 0.025),
        ("ee", 0.0, 0.04, -0.008, 0.02),
        ("ee", 0.0, -0.04, -0.008, 0.02),
    ]
    return _geometry(
        rows,
        # the housings of joints 5 and 7 sit side by side; joint 6 turns one about the other
        [("link5", "link7")],
        "approximate sphere model written for symkin from the Franka Emika Panda's dimensions "
        "(kinematic offsets 0.333/0.316/0.0825/0.384/0.088/0.107 m, link diameters about 0.13-0.15 m, "
        "Franka Hand 0.2 x 0.066 m with fingers)",
    )


# ---------------------------------------------------------------------------------------------
# Universal Robots (standard DH: link frame k is DH frame k-1 turned by joint k; the upper arm
# runs along x of link frame 1 to a2 < 0 at the shoulder offset along that frame's z, the
# forearm along x of frame 2 at the net offset shoulder - elbow; wrist 1 is d4 along z of frame 3).


def _ur(
    name: str,
    d1: float,
    a2: float,
    a3: float,
    d4: float,
    d5: float,
    d6: float,
    shoulder: float,
    elbow: float,
    r_big: float,
    r_fore: float,
    r_wrist: float,
) -> Geometry:
    fo = shoulder - elbow  # forearm's offset along the joint axes
    n_up = max(3, round(abs(a2) / (1.3 * r_big)))
    n_fore = max(3, round(abs(a3) / (1.3 * r_fore)))
    rows: list[_Row] = [
        # base: the mounting foot, as wide as the shoulder joint
        ("base", 0.0, 0.0, 0.3 * d1, 0.9 * r_big),
        # link1 (shoulder): joint 1's housing up to joint 2, and joint 2's housing along -y
        ("link1", 0.0, 0.0, d1, r_big),
        ("link1", 0.0, -0.45 * shoulder, d1, r_big),
        # link2 (upper arm): joint 2's rotor housing, the tube, joint 3's housing
        ("link2", 0.0, 0.0, shoulder, r_big),
        *_line("link2", (a2 * 0.18, 0.0, shoulder), (a2 * 0.85, 0.0, shoulder), n_up, 0.85 * r_big),
        ("link2", a2, 0.0, shoulder, 0.95 * r_big),
        # link3 (forearm): the elbow housing, the tube, the end at wrist 1
        ("link3", 0.0, 0.0, fo, 0.95 * r_big),
        *_line("link3", (a3 * 0.2, 0.0, fo), (a3 * 0.87, 0.0, fo), n_fore, r_fore),
        # link4 (wrist 1): housing around joint 4 out to wrist 2
        ("link4", 0.0, 0.0, 0.45 * d4, r_wrist),
        ("link4", 0.0, 0.0, d4, r_wrist),
        # link5 (wrist 2)
        ("link5", 0.0, 0.0, 0.35 * d5, r_wrist),
        ("link5", 0.0, 0.0, d5, r_wrist),
        # link6 (wrist 3) and the tool flange on ee
        ("link6", 0.0, 0.0, 0.45 * d6, r_wrist),
        ("ee", 0.0, 0.0, -0.01, 0.85 * r_wrist),
    ]
    dims = "/".join(f"{round(abs(v) * 1000, 1):g}" for v in (d1, a2, a3, d4, d5, d6))
    return _geometry(
        rows,
        [],
        f"approximate sphere model written for symkin from the Universal Robots {name.upper()}'s "
        f"dimensions (DH d1/a2/a3/d4/d5/d6 {dims} mm, shoulder and elbow offsets "
        f"{round(shoulder * 1000, 2):g}/{round(elbow * 1000, 2):g} mm, joint housings "
        f"{round(2 * r_big * 1000):g} mm and wrists {round(2 * r_wrist * 1000):g} mm across)",
    )


# ---------------------------------------------------------------------------------------------
# KUKA LBR iiwa (standard DH with zero link offsets: frames 0 and 1 at the base and the
# shoulder, frames 2 and 3 at the shoulder and the elbow, frames 4 and 5 at the elbow and the
# wrist, frame 6 at the wrist; each link spans half the distance between two such points).


def _iiwa(name: str, h0: float, d1: float, d3: float, r: float) -> Geometry:
    d5 = 0.4  # elbow to wrist; the flange is 0.126 beyond the wrist
    half3, half5 = 0.525 * d3, 0.525 * d5  # where link 2 meets link 3 and link 4 meets link 5
    rows: list[_Row] = [
        # base (link 0): round foot of height h0 with the cable outlet at the back
        ("base", 0.0, 0.0, 0.5 * h0, 1.2 * r),
        ("base", -0.09, 0.0, 0.4 * h0, 0.85 * r),
        # link1: from the base to the shoulder
        *_line("link1", (0.0, 0.0, h0 + 0.3 * r), (0.0, 0.0, d1 - 0.2 * r), 3, r),
        # link2 (up is -y here): shoulder housing up to the half of the upper arm
        ("link2", 0.0, 0.0, 0.0, 1.1 * r),
        ("link2", 0.0, 0.0, 0.035, r),
        *_line("link2", (0.0, -0.45 * half3, 0.0), (0.0, -0.85 * half3, 0.0), 2, r),
        # link3 (up is +z): the other half up to the elbow
        *_line("link3", (0.0, 0.0, 1.1 * half3), (0.0, 0.0, d3 - 0.25 * r), 3, r),
        # link4 (up is +y here): elbow housing up to the half of the forearm
        ("link4", 0.0, 0.0, 0.0, 1.1 * r),
        ("link4", 0.0, 0.0, -0.035, r),
        *_line("link4", (0.0, 0.45 * half5, 0.0), (0.0, 0.85 * half5, 0.0), 2, r),
        # link5 (up is +z): the other half, up to where the wrist housing of link 6 takes over (the
        # slanted joint faces let the flange fold back by 120 deg: no sphere hugs the wrist)
        ("link5", 0.0, 0.0, 1.1 * half5, 0.95 * r),
        ("link5", 0.0, 0.0, d5 - 0.11, 0.95 * r),
        # link6 (up is -y here): the wrist housing
        ("link6", 0.0, 0.0, 0.0, r),
        ("link6", 0.0, 0.0, 0.03, 0.9 * r),
        ("link6", 0.0, -0.045, 0.0, 0.85 * r),
        # link7: the last joint's housing up to the flange, and the flange plate on ee
        ("link7", 0.0, 0.0, 0.085, 0.055),
        ("ee", 0.0, 0.0, -0.025, 0.05),
    ]
    return _geometry(
        rows,
        [],
        f"approximate sphere model written for symkin from the KUKA {name}'s dimensions (link lengths "
        f"{round(d1 * 1000):g}/{round(d3 * 1000):g}/400/126 mm, base height {round(h0 * 1000):g} mm, link "
        f"diameters about {round(2 * r * 1000):g} mm)",
    )


_MODELS: dict[str, Callable[[], Geometry]] = {
    "panda": _panda,
    "ur3": lambda: _ur(
        "ur3", 0.1519, -0.24365, -0.21325, 0.11235, 0.08535, 0.0819, 0.1198, 0.0925, 0.06, 0.042, 0.04
    ),  # fmt: skip
    "ur5": lambda: _ur(
        "ur5", 0.089159, -0.425, -0.39225, 0.10915, 0.09465, 0.0823, 0.13585, 0.1197, 0.075, 0.05, 0.047
    ),  # fmt: skip
    "ur10": lambda: _ur(
        "ur10", 0.1273, -0.612, -0.5723, 0.163941, 0.1157, 0.0922, 0.220941, 0.1719, 0.095, 0.065, 0.058
    ),  # fmt: skip
    "lbr_iiwa7": lambda: _iiwa("LBR iiwa 7 R800", 0.15, 0.34, 0.4, 0.075),
    "lbr_iiwa14": lambda: _iiwa("LBR iiwa 14 R820", 0.1575, 0.36, 0.42, 0.08),
}

#: Names of the built-in robots that have a sphere model.
BUILTIN_GEOMETRY: tuple[str, ...] = tuple(sorted(_MODELS))


def builtin_geometry(name: str) -> Geometry | None:
    """The hand-written sphere model of built-in robot ``name`` ("panda", "ur3", "ur5", "ur10",
    "lbr_iiwa7", "lbr_iiwa14"; case-insensitive, ``-`` and spaces read as ``_``), or None for a
    robot without one. Spheres are in the frames of the robot's links (module docstring), metres."""
    if not isinstance(name, str):
        return None
    key = "_".join(name.strip().lower().replace("-", " ").split())
    build = _MODELS.get(key)
    return build() if build is not None else None
