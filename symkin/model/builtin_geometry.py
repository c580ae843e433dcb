"""The built-in arms' sphere models.

**Covering models** (Panda, UR3, UR5, UR10, LBR iiwa 14): spheres fitted by
:func:`symkin.geometry.mesh_fit.fit_builtin` to the arms' real collision meshes (the URDFs of
example-robot-data and rtb-data) so that every point of every mesh surface lies inside a sphere
of its link (exactly, not by sampling; the Panda's fingers over their whole travel), each sphere
reaching at most :data:`DEFAULT_EXCESS` (2 cm) out of the mesh. They are stored in
``builtin_spheres.json`` beside this module (``symkin geometry builtins --update`` regenerates it;
``--check`` compares it with a refit), with each link's figures and the disabled link pairs.

**Hand-written model** (LBR iiwa 7 R800, whose meshes no pip package ships): a handful of spheres
per link written for symkin from the arm's published dimensions (link lengths of the kinematic
model in :mod:`symkin.model.robots`, outer diameters of the data sheet); not measured against a
mesh.

Every sphere is in the frame of its link (metres): ``base`` is the base frame, ``link<k+1>``
the k-th link frame of the chain (``robot.link_poses(q)[k]``, the frame right after the k-th
joint), ``ee`` the end-effector frame ``robot.fkine(q)``. ``disabled`` lists the link pairs that
touch at every configuration by construction (like the "Default"/"Always" pairs of MoveIt's
setup assistant): with them out, no sphere pair collides at the robot's named configurations.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Sequence
from functools import cache
from pathlib import Path
from typing import Any

from symkin.core.names import robot_key
from symkin.model.geometry import Geometry, Sphere

__all__ = ["builtin_geometry", "BUILTIN_GEOMETRY", "COVERING", "DEFAULT_EXCESS", "stored_models", "STORE"]

#: The outward excess (m) the stored covering models are fitted for.
DEFAULT_EXCESS = 0.02

#: The stored covering models (``symkin geometry builtins --update`` writes it).
STORE = Path(__file__).with_name("builtin_spheres.json")

_Row = tuple[str, float, float, float, float]  # link, x, y, z, radius


def _geometry(rows: Sequence[_Row], disabled: Sequence[tuple[str, str]], source: str) -> Geometry:
    return Geometry(tuple(Sphere((x, y, z), r, link) for link, x, y, z, r in rows), tuple(disabled), source)


def _line(link: str, a: Sequence[float], b: Sequence[float], count: int, r: float) -> list[_Row]:
    """``count`` spheres of radius ``r`` evenly from ``a`` to ``b`` (both ends included)."""
    if count == 1:
        return [(link, *(0.5 * (p + q) for p, q in zip(a, b)), r)]  # type: ignore[list-item]
    return [(link, *(p + i / (count - 1) * (q - p) for p, q in zip(a, b)), r) for i in range(count)]  # type: ignore[return-value]


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


@cache
def stored_models() -> dict[str, Any]:
    """The contents of :data:`STORE`: ``{"max_excess": ..., "robots": {name: {"source",
    "disabled", "spheres": [[link, x, y, z, r], ...], "links": [per-link figures]}}}``."""
    return json.loads(STORE.read_text(encoding="utf-8"))


def _stored(name: str) -> Geometry | None:
    entry = stored_models().get("robots", {}).get(name) if STORE.is_file() else None
    if entry is None:  # only while the store is being written for the first time
        return None
    return _geometry(
        [tuple(row) for row in entry["spheres"]], [tuple(p) for p in entry["disabled"]], entry["source"]
    )


#: Names of the built-in robots whose model covers their real collision meshes.
COVERING: tuple[str, ...] = ("lbr_iiwa14", "panda", "ur10", "ur3", "ur5")

_MODELS: dict[str, Callable[[], Geometry | None]] = {
    **{name: (lambda name=name: _stored(name)) for name in COVERING},
    "lbr_iiwa7": lambda: _iiwa("LBR iiwa 7 R800", 0.15, 0.34, 0.4, 0.075),
}

#: Names of the built-in robots that have a sphere model.
BUILTIN_GEOMETRY: tuple[str, ...] = tuple(sorted(_MODELS))


def builtin_geometry(name: str) -> Geometry | None:
    """The sphere model of built-in robot ``name`` ("panda", "ur3", "ur5", "ur10",
    "lbr_iiwa14": covering their real meshes; "lbr_iiwa7": hand-written; case-insensitive, ``-``
    and spaces read as ``_``), or None for a robot without one. Spheres are in the frames of the
    robot's links (module docstring), metres."""
    if not isinstance(name, str):
        return None
    key = robot_key(name)
    build = _MODELS.get(key)
    return build() if build is not None else None
