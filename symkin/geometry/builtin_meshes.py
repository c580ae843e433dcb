"""Where the built-in arms' real collision meshes come from, and how they sit on symkin's links.

Each :class:`MeshSource` names a URDF shipped by a pip package (the ``meshes`` extra:
example-robot-data for the Panda and the UR3/UR5/UR10, rtb-data, which roboticstoolbox-python
installs, for the LBR iiwa 14 R820), the URDF link each joint of the built-in robot moves, and the
pose of the URDF's base in the robot's base frame (the ROS-Industrial UR base_link is turned by pi
about z against the controller's base frame, which the UR DH parameters use).

:func:`source_frames` measures, for each link of the built-in robot, the constant pose of the URDF
link frame in symkin's link frame, from the two forward kinematics (symkin's numeric ETS and the
URDF read by :meth:`symkin.Tree.from_urdf`) at the zero configuration, and checks it at random
configurations within the limits: the rotations must agree to 1e-9, and the positions to within
``2 * sum(e_j)`` over the joints j before the link, ``e_j`` the distance between joint j's axis
lines in the two models (rotations by one angle about two parallel axes ``e`` apart move a point
to places at most ``2 e`` apart). That bound is returned per link, and the covering spheres of the
link grow by it: 0 for the Panda and the UR arms (their URDFs and symkin's models agree to
rounding); 0.87 mm on the iiwa's link 2 and 1.74 mm on links 3 to 7 (the URDF puts the axes of
joints 2 and 3 0.436 mm off KUKA's published kinematics, and joint 4's back).
"""

from __future__ import annotations

import importlib.metadata
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from symkin.errors import GeometryError, MissingExtraError
from symkin.model.ets import Axis
from symkin.model.kinematics import et_matrix

__all__ = ["MeshSource", "MESH_SOURCES", "locate", "source_frames"]

_INSTALL = 'pip install "symkin[meshes]"'
_ERD = "cmeel.prefix/share/example-robot-data"
_UR_LINKS = (
    "shoulder_link",
    "upper_arm_link",
    "forearm_link",
    "wrist_1_link",
    "wrist_2_link",
    "wrist_3_link",
)


@dataclass(frozen=True)
class MeshSource:
    """A built-in robot's collision meshes: the URDF at ``urdf`` inside the pip distribution
    ``distribution``, ``packages`` (package:// name -> folder inside the distribution), ``links``
    (the URDF link moved by each joint of the robot, in order) and ``base_yaw`` (the URDF base
    frame is the robot's base frame turned by this angle about z, rad); ``ee_links``: URDF links
    (rigid with the last link) whose meshes go on symkin's ``ee`` link, the same body as the last
    link but its own name, so that link pairs map one to one onto the URDF's (the Panda's fingers:
    its SRDF leaves the hand against link 5 unchecked, the fingers checked)."""

    robot: str
    distribution: str
    urdf: str
    links: tuple[str, ...]
    packages: tuple[tuple[str, str], ...] = ()
    base_yaw: float = 0.0
    ee_links: tuple[str, ...] = ()

    @property
    def label(self) -> str:
        return f"{self.distribution}'s {Path(self.urdf).name}"


MESH_SOURCES: dict[str, MeshSource] = {
    "panda": MeshSource(
        "panda", "example-robot-data", f"{_ERD}/robots/panda_description/urdf/panda.urdf",
        tuple(f"panda_link{i}" for i in range(1, 8)), ee_links=("panda_leftfinger", "panda_rightfinger"),
    ),
    **{
        name: MeshSource(name, "example-robot-data", f"{_ERD}/robots/ur_description/urdf/{name}_robot.urdf",
                         _UR_LINKS, base_yaw=math.pi)
        for name in ("ur3", "ur5", "ur10")
    },
    "lbr_iiwa14": MeshSource(
        "lbr_iiwa14", "rtb-data", "rtbdata/xacro/kuka_description/kuka_lbr_iiwa/urdf/lbr_iiwa_14_r820.urdf",
        tuple(f"link_{i}" for i in range(1, 8)),
        packages=(("kuka_lbr_iiwa_support", "rtbdata/xacro/kuka_description/kuka_lbr_iiwa"),),
    ),
}  # fmt: skip


def locate(source: MeshSource) -> tuple[Path, dict[str, Path]]:
    """The URDF file of ``source`` and its package folders (MissingExtraError when the
    distribution is not installed)."""
    try:
        dist = importlib.metadata.distribution(source.distribution)
    except importlib.metadata.PackageNotFoundError:
        raise MissingExtraError(
            f"the collision meshes of {source.robot} come from {source.distribution}: {_INSTALL}"
        ) from None
    path = Path(str(dist.locate_file(source.urdf))).resolve()
    if not path.is_file():
        raise MissingExtraError(f"{source.distribution} has no {source.urdf}; reinstall it: {_INSTALL}")
    packages = {name: Path(str(dist.locate_file(folder))).resolve() for name, folder in source.packages}
    return path, packages


def on_ee(robot, placements: dict, source: MeshSource) -> dict:
    """``placements`` with the URDF links of ``source.ee_links`` moved from the last link's frame
    to the end-effector frame ``ee`` (the same body: a constant transform)."""
    from symkin.geometry.meshes import Placement

    if not source.ee_links:
        return placements
    q0 = np.zeros(robot.n)
    E = np.linalg.inv(np.linalg.inv(robot.link_poses(q0)[-1]) @ robot.fkine(q0))  # last link -> ee
    out = dict(placements)
    for ln in source.ee_links:
        p = placements[ln]
        if p.link != f"link{robot.n}":
            raise GeometryError(f"{source.label}: {ln!r} does not ride on {robot.name}'s last link")
        stroke = None if p.stroke is None else E[:3, :3] @ p.stroke
        out[ln] = Placement("ee", E @ p.T, stroke)
    return out


def source_frames(
    robot, tree, source: MeshSource
) -> tuple[dict[str, tuple[str, np.ndarray]], dict[str, float]]:
    """``(frames, slack)``: per URDF link of the chain (and the URDF base link) the symkin link it
    rides on and the pose of its frame in that link's frame (4, 4); per symkin link the bound on
    how far the two models place its points apart (module docstring). ``robot`` is the built-in
    Robot, ``tree`` the URDF's Tree with ``source.links`` among its frames."""
    n = robot.n
    if len(source.links) != n or tree.n != n:
        raise GeometryError(
            f"{source.label} moves {tree.n} joints to the links {list(source.links)}; {robot.name} has {n}"
        )
    B = et_matrix(Axis.Rz, source.base_yaw)
    q0 = np.zeros(n)
    L0 = robot.link_poses(q0)
    U0 = [B @ tree.fkine(q0, frame=ln) for ln in source.links]
    C = [np.linalg.inv(L0[k]) @ U0[k] for k in range(n)]
    # joint axis lines at q0 in both models: parallel, e_j apart
    w_s = robot.jacob0(q0)[3:]
    w_u = B[:3, :3] @ tree.jacob0(q0, frame=source.links[-1])[3:]
    gaps = []
    for j in range(n):
        a, b = w_s[:, j], w_u[:, j]
        if np.linalg.norm(np.cross(a, b)) > 1e-9 or np.dot(a, b) <= 0:
            raise GeometryError(
                f"{source.label}: joint {j + 1}'s axis is not {robot.name}'s (directions {a} and {b})"
            )
        gaps.append(float(np.linalg.norm(np.cross(U0[j][:3, 3] - L0[j][:3, 3], a))))
    slack = {f"link{k + 1}": 2.0 * sum(gaps[: k + 1]) for k in range(n)}
    slack["base"] = 0.0
    for q in robot.random_q(64, seed=0):
        L = robot.link_poses(q)
        for k, ln in enumerate(source.links):
            D = np.linalg.inv(L[k]) @ B @ tree.fkine(q, frame=ln)
            if np.abs(D[:3, :3] - C[k][:3, :3]).max() > 1e-9 or (
                np.linalg.norm(D[:3, 3] - C[k][:3, 3]) > slack[f"link{k + 1}"] + 1e-9
            ):
                raise GeometryError(
                    f"{source.label}: the URDF link {ln!r} does not move with {robot.name}'s link frame {k} "
                    f"(at q = {np.round(q, 4).tolist()})"
                )
    frames = {
        tree.base_link: ("base", B),
        **{ln: (f"link{k + 1}", C[k]) for k, ln in enumerate(source.links)},
    }
    return frames, slack
