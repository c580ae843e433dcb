"""The kinematics a task (IK, servo, MMC) runs on: a chain itself, or one frame of a tree."""

from __future__ import annotations

from typing import Any

from symkin.errors import FrameError

__all__ = ["is_tree", "task_kinematics"]


def is_tree(kin: Any) -> bool:
    """A :class:`symkin.Tree` or compiled tree kinematics (a class attribute marks them, so the
    test costs no instance attribute lookup)."""
    return bool(getattr(type(kin), "_symkin_tree", False))


def task_kinematics(kin: Any, frame: Any = None) -> Any:
    """``kin`` itself for a serial chain (``frame`` must be None), its :class:`FrameView` of
    ``frame`` for a tree (``frame`` may be omitted when the tree has one frame)."""
    if is_tree(kin):
        return kin.select(frame)
    if frame is not None:
        raise FrameError(
            f"frame={frame!r} picks a frame of a tree (symkin.Tree or its compiled kinematics); "
            f"{getattr(kin, 'name', type(kin).__name__)} is a serial chain"
        )
    return kin
