"""Turn what a user typed (a built-in name, ETS text, a DH table file or a URDF path) into a Robot.

Used by :func:`symkin.compile` and by every ``symkin`` command that takes a ROBOT, so the same
spellings work everywhere.
"""

from __future__ import annotations

from pathlib import Path

from symkin.model.robot import Robot

__all__ = ["resolve_robot"]

_URDF_SUFFIXES = (".urdf", ".xml")


def resolve_robot(spec: str | Robot) -> Robot:
    """A Robot from a built-in name (``panda``), ETS text (``"Rz(q) tx(1) Rz(q) tx(1)"``), a DH table
    file, a URDF file or ``path.urdf:FRAME`` (the chain from the root to link FRAME)."""
    if isinstance(spec, Robot):
        return spec
    from symkin.model.robots import list_robots, load

    text = spec.strip()
    if text in list_robots():
        return load(text)
    head, sep, frame = text.rpartition(":")  # path.urdf:FRAME, the chain to link FRAME
    if sep and frame and "(" not in text and "/" not in frame and Path(head).suffix.lower() in _URDF_SUFFIXES:
        return Robot.from_urdf(Path(head).expanduser(), end_link=frame)
    path = Path(text).expanduser()
    if "(" not in text and path.suffix.lower() in _URDF_SUFFIXES:
        return Robot.from_urdf(path)
    if "(" not in text and path.is_file():
        from symkin.model.dh import load_dh_file

        return load_dh_file(path)
    if "(" in text:
        return Robot.from_ets(text, name="ets_robot")
    return load(text)  # raises UnknownRobotError with the list of built-in robots and close matches
