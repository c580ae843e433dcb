"""Turn what a user typed (a built-in name, ETS text, a DH table file or a URDF path) into a Robot.

Used by :func:`symkin.compile` and by every ``symkin`` command that takes a ROBOT, so the same
spellings work everywhere.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from symkin.errors import RobotError, SymkinError
from symkin.model.ets import ETS
from symkin.model.robot import Robot

__all__ = ["resolve_robot", "robot_with_joints"]

_URDF_SUFFIXES = (".urdf", ".xml", ".xacro")  # .xacro: refused by the URDF reader, with how to expand it


def resolve_robot(spec: str | Robot | ETS, tool: Any = None, base: Any = None) -> Robot:
    """A Robot from a built-in name (``panda``), an ETS, ETS text (``"Rz(q) tx(1) Rz(q) tx(1)"``), a DH table
    file, a URDF file or ``path.urdf:FRAME`` (the chain from the root to link FRAME).

    ``tool``/``base``: a constant transform appended after the end effector / placed before the
    first link (any form :meth:`symkin.Robot.with_tool` takes, e.g. ``"tz(0.1)"`` or
    ``"0 0 0.1 0 0 pi/2"``), on top of any the source itself has (a DH file's ``# tool:``).
    """
    robot = _resolve(spec)
    if tool is not None:
        robot = robot.with_tool(tool)
    if base is not None:
        robot = robot.with_base(base)
    return robot


def robot_with_joints(spec: str | Robot | ETS, purpose: str = "") -> Robot:
    """:func:`resolve_robot` of ``spec``; a SymkinError when the robot has no joints (``purpose``,
    what they are needed for, ends its message)."""
    robot = resolve_robot(spec)
    if robot.n == 0:
        raise SymkinError(f"robot {robot.name!r} has no joints" + (f": {purpose}" if purpose else ""))
    return robot


def _resolve(spec: str | Robot | ETS) -> Robot:
    if isinstance(spec, Robot):
        return spec
    if isinstance(spec, ETS):
        return Robot(spec, name="ets_robot")
    from symkin.model.robots import list_robots, load

    if not isinstance(spec, str):
        raise TypeError(
            f"a robot is a Robot, a built-in name, ETS text or a file path, not {type(spec).__name__}"
        )
    text = spec.strip()
    if text in list_robots():
        return load(text)
    if "(" in text:
        return Robot.from_ets(text, name="ets_robot")
    head, sep, frame = text.rpartition(":")  # path.urdf:FRAME, the chain to link FRAME
    if sep and frame and "/" not in frame and Path(head).suffix.lower() in _URDF_SUFFIXES:
        return Robot.from_urdf(Path(head).expanduser(), end_link=frame)
    path = Path(text).expanduser()
    if path.is_dir():
        raise RobotError(
            f"{text!r} is a folder; give a DH table file, a URDF file, a built-in name or ETS text"
        )
    if not path.exists() and ("/" in text or os.sep in text or path.suffix):
        raise RobotError(
            f"no such file: {text!r} (a robot is a built-in name, quoted ETS text, a DH table or a URDF file)"
        )
    if path.suffix.lower() in _URDF_SUFFIXES:
        return Robot.from_urdf(path)
    if path.is_file():
        from symkin.model.robots import load_dh_file

        return load_dh_file(path)
    return load(text)  # raises UnknownRobotError with the list of built-in robots and close matches
