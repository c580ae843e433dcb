"""The kinematics a task (IK, servo, MMC) runs on: a chain itself, or one frame of a model."""

from __future__ import annotations

from typing import Any

from symkin.errors import FrameError

__all__ = ["task_kinematics"]


def task_kinematics(kin: Any, frame: Any = None) -> Any:
    """``kin.select(frame)`` for symkin's models and compiled kinematics (a chain itself for
    ``frame=None``, else a :class:`symkin.model.frame_view.FrameView`; a one-frame tree's frame
    may be omitted); any other chain-like object as it is (``frame`` must then be None)."""
    select = getattr(kin, "select", None)
    if select is not None:
        return select(frame)
    if frame is not None:
        raise FrameError(
            f"frame={frame!r} picks a frame of a symkin model or its compiled kinematics; "
            f"{getattr(kin, 'name', type(kin).__name__)} has one frame"
        )
    return kin
