"""A model from the JSON data its ``to_data`` gave (:meth:`symkin.Robot.to_data`,
:meth:`symkin.Tree.to_data`): what the manifests of :func:`symkin.write_generated` store."""

from __future__ import annotations

from fractions import Fraction
from typing import Any

import numpy as np

from symkin.model.ets import ET, ETS
from symkin.model.robot import Robot
from symkin.model.slots import Segment, Slot
from symkin.model.tree import Tree

__all__ = ["model_of_data"]


def model_of_data(kind: str, data: dict[str, Any]) -> Robot | Tree:
    """The model ``to_data`` gave as ``(kind, data)``: a Robot (``"chain"``) or a Tree (``"tree"``);
    KeyError, TypeError, ValueError or a SymkinError when the data is not one."""
    if kind == "chain":
        return Robot(
            ETS.parse(data["ets"]),
            name=data["name"],
            qlim=np.array(data["qlim"], dtype=float),
            configs={k: np.array(v, dtype=float) for k, v in data.get("configs", {}).items()},
            joint_names=tuple(data["joint_names"]),
            qd_max=None if data.get("qd_max") is None else np.array(data["qd_max"], dtype=float),
            source=data.get("source", ""),
        )
    segments = []
    for seg in data["segments"]:
        joints = iter(seg["joints"])
        ets = ETS.parse(seg["ets"]).ets if seg["ets"] else ()
        ets = tuple(ET(e.axis, joint=int(next(joints)), flip=e.flip) if e.is_joint else e for e in ets)
        if next(joints, None) is not None:
            raise ValueError(f"segment {seg['name']!r} lists more joints than its ETS has")
        slot = None if seg["slot"] is None else int(seg["slot"])
        segments.append(Segment(seg["name"], int(seg["parent"]), seg["link"], ets, slot))
    slots = [
        Slot(
            s["name"],
            int(s["segment"]),
            int(s["joint"]),
            Fraction(s["multiplier"]),
            Fraction(s["offset"]),
            bool(s["revolute"]),
            s["mimics"],
        )
        for s in data["slots"]
    ]
    return Tree(
        name=data["name"],
        base_link=data["base_link"],
        segments=tuple(segments),
        slots=tuple(slots),
        frames=tuple(data["frames"]),
        frame_segments=tuple(int(k) for k in data["frame_segments"]),
        joint_names=tuple(data["joint_names"]),
        qlim=np.array(data["qlim"], dtype=float),
        velocity=np.array([np.nan if v is None else v for v in data["velocity"]], dtype=float),
        source=data.get("source", ""),
    )
